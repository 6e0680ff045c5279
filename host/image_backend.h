/* Between image_common.c and the implementation linked with it
 * (image_oiio.cpp or image_ppm.c); not for the rest of the host.
 *
 * image_common.c validates, creates the temporary file, writes .ppm, .pfm and
 * (with image_png.c) .png itself, syncs and renames. The implementation only says which other
 * extensions it can write and encodes those.
 */
#ifndef RTCL_IMAGE_BACKEND_H
#define RTCL_IMAGE_BACKEND_H

#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

#include "image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Returns 0 if this build can write the format named by `ext` (the file
 * name's extension with its dot, e.g. ".png" or ".TIF"; "" for none), else
 * -1 with "PATH: ..." in err. Never called for .ppm, .pfm and .png. */
int image_backend_check_format(const char *path, const char *ext, char *err, size_t err_size);

/* Encodes the image (as for image_write) into tmp_path, an empty file that
 * ends in the same extension as `path`, open for writing as tmp_fd. Messages
 * name `path`, the file the user asked for. The caller syncs and closes
 * tmp_fd, and removes tmp_path on failure. */
int image_backend_encode(const char *path, const char *tmp_path, int tmp_fd, const float *rgb,
			 int width, int height, const struct image_meta *meta, char *err,
			 size_t err_size);

/* Reads the header of tmp_path, just written for `path`, back: it must open
 * as the format path's extension names, width × height pixels. Returns 0, or
 * -1 with "PATH: ..." in err. */
int image_backend_verify(const char *path, const char *tmp_path, int width, int height, char *err,
			 size_t err_size);

/* snprintf into err[err_size]; does nothing when err is NULL or err_size 0.
 * Inline, so that the backends need nothing back from image_common.c. */
#ifdef __GNUC__
__attribute__((format(printf, 3, 4)))
#endif
static inline void image_set_error(char *err, size_t err_size, const char *format, ...)
{
	va_list args;

	if (!err || err_size == 0)
		return;
	va_start(args, format);
	vsnprintf(err, err_size, format, args);
	va_end(args);
}

#ifdef __cplusplus
}
#endif

#endif
