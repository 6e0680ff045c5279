/* rtcl's own PNG writer (8-bit RGB, zlib), so that the commonest output needs
 * neither OpenImageIO nor the time its hundreds of libraries take to load. */
#ifndef RTCL_IMAGE_PNG_H
#define RTCL_IMAGE_PNG_H

#include <stdio.h>

#include "output/image.h"

/* Writes the image as PNG to file: each channel image_encode_8bit() in the
 * meta's encoding, tagged as OpenImageIO tags it (gAMA 1.0 for linear; sRGB,
 * gAMA 1/2.2 and cHRM otherwise; tEXt Software, Description and
 * oiio:ColorSpace). Returns 0, or -1 with errno set (0: out of memory or a
 * zlib failure). */
int image_png_write(FILE *file, const float *rgb, int width, int height,
		    const struct image_meta *meta);

/* Whether the file at path starts with a PNG signature and an IHDR of
 * width × height, 8-bit RGB. */
int image_png_check(const char *path, int width, int height);

#endif
