/* --denoise: Intel Open Image Denoise's "RT" filter on the finished image,
 * fed with the albedo and normal of the auxiliary images (cl/aov.cl), on
 * the host's CPU. The library is loaded at run time (dlopen), as the
 * OpenImageIO module is: from $RTCL_OIDN_LIBRARY when set, else from where
 * `make deps` installs it (OIDN_DIR in the Makefile: the pyoidn wheel's
 * copy), else by its soname through the loader's own search. */
#ifndef RTCL_DENOISE_H
#define RTCL_DENOISE_H

#include <stddef.h>

/* Loads the library (once). Returns 0, or -1 with one message in err
 * saying where it was looked for and that `make deps` installs it. */
int denoise_load(char *err, size_t err_size);

/* Denoises rgb (width*height*3 linear floats, HDR) in place with the albedo
 * and normal images (3 floats a pixel each). Returns 0, or -1 with OIDN's
 * message in err. */
int denoise_image(float *rgb, const float *albedo, const float *normal, int width, int height,
		  char *err, size_t err_size);

#endif
