/* Textures for rtcl-meshread (docs/SCENE.md, "Textures"): the files a mesh
 * file names, read under SCENE.md's path rule, and images decoded with
 * stb_image into the RGBA texels of docs/RENDERING.md, "Textures". */
#ifndef RTCL_TEXTURE_READ_H
#define RTCL_TEXTURE_READ_H

#include <stddef.h>

#include "scene/mesh.h"

/* Reads the texture `name` (as the mesh file at mesh_path names it,
 * relative to its folder) into *bytes (malloc'd) and *size. Returns 0, or -1
 * with why in reason: outside the folder, missing, not a regular file. */
int texture_file_bytes(const char *mesh_path, const char *name, unsigned char **bytes,
		       size_t *size, char *reason, size_t reason_size);

/* Decodes an encoded image (PNG, JPEG, ...) of size bytes into t (width,
 * height, format, bytes) and *texels (malloc'd, t->bytes of them), the alpha
 * as t->role asks. Returns 0, or -1 with why in t->reason. */
int texture_decode(const unsigned char *bytes, size_t size, struct mesh_texture *t,
		   unsigned char **texels);

/* E^-1(x), the sRGB curve's inverse (RENDERING.md, "Writing the image"), in double. */
double texture_srgb_to_linear(double x);

#endif
