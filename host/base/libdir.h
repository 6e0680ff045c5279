/* Where rtcl's companion files lie: the OpenImageIO module (rtcl-oiio.so) and
 * the mesh import helper (rtcl-meshread). Installed, they are in
 * PREFIX/lib/rtcl, i.e. ../lib/rtcl beside the program; in a build tree, in
 * the build folder (RTCL_MODULE_DIR, set by the Makefile). */
#ifndef RTCL_LIBDIR_H
#define RTCL_LIBDIR_H

#include <stddef.h>

/* The first of ../lib/rtcl/NAME beside this program and RTCL_MODULE_DIR/NAME
 * that exists, into path[size]. Returns 0, or -1 with path set to a phrase
 * saying where NAME was looked for. */
int libdir_find(const char *name, char *path, size_t size);

#endif
