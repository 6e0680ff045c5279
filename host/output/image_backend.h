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

#include "output/image.h"

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

/* snprintf into err[err_size], every control byte escaped as \n, \t or
 * \xNN (a path with a newline or an ESC byte stays one line and cannot
 * drive the terminal, as quote.h does for the rest of the host); does nothing
 * when err is NULL or err_size 0. Inline, so that the backends need nothing
 * back from image_common.c. */
#ifdef __GNUC__
__attribute__((format(printf, 3, 4)))
#endif
static inline void
image_set_error(char *err, size_t err_size, const char *format, ...)
{
	char raw[8192];
	size_t n = 0;
	va_list args;

	if (!err || err_size == 0)
		return;
	va_start(args, format);
	vsnprintf(raw, sizeof(raw), format, args);
	va_end(args);
	for (const char *s = raw; *s && n + 5 <= err_size; s++) {
		unsigned char c = (unsigned char)*s;

		if (c == '\n' || c == '\t')
			n += (size_t)snprintf(err + n, err_size - n, "\\%c", c == '\n' ? 'n' : 't');
		else if (c < 0x20 || c == 0x7f)
			n += (size_t)snprintf(err + n, err_size - n, "\\x%02x", c);
		else
			err[n++] = (char)c;
	}
	err[n < err_size ? n : err_size - 1] = '\0';
}

#ifdef __cplusplus
}
#endif

#endif
