/* Image output.
 *
 * One interface, two implementations chosen at build time: image_oiio.cpp
 * writes every format OpenImageIO knows, image_ppm.c (OIIO=0) only .ppm and
 * .pfm. Both link image_common.c, which owns the 8-bit conversion, the
 * checks, the temporary file and the .ppm/.pfm writers, so a .ppm or .pfm is
 * byte for byte the same whichever implementation wrote it.
 *
 * Float formats keep the linear values: .exr (32-bit float), .hdr (RGBE) and
 * .pfm (32-bit float). Every other format, TIFF included, gets 8 bits per
 * channel from image_to_8bit(), with no transfer curve (SCENE.md).
 *
 * Messages are one line, "PATH: what is wrong", without a trailing newline.
 */
#ifndef RTCL_IMAGE_H
#define RTCL_IMAGE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

struct image_meta {
	const char *software; /* e.g. "rtcl 0.1.0"; NULL for none */
	const char
		*description; /* e.g. "scene: scenes/paper60.json, kernel dynamic"; NULL for none */
};

/* Checks, before any rendering, that `path` can be written: its extension
 * names a format this build can write, its directory exists and a file can
 * be created there (tried, then removed), and `path` is not something other
 * than a regular file (a device, a directory). Returns 0, or -1 with one
 * message in err[err_size]. */
int image_check_writable(const char *path, char *err, size_t err_size);

/* Writes width × height linear RGB floats, rgb[3 * (y * width + x) + c], row
 * 0 at the top. The image goes to a temporary file in the same directory
 * that is renamed over `path` once complete, so a failure leaves neither a
 * partial nor a temporary file, and an existing file at `path` unchanged.
 * `meta` (may be NULL) is recorded as Software and ImageDescription where
 * the format has room for it. Returns 0, or -1 with one message in
 * err[err_size] naming `path` and the reason. */
int image_write(const char *path, const float *rgb, int width, int height,
		const struct image_meta *meta, char *err, size_t err_size);

/* Like image_write, but leaves the image staged beside path for the caller
 * to commit with the run's other outputs (files.h). The written file's header
 * is read back (format, size) before this returns 0. */
struct staged_file;
int image_stage(struct staged_file *staged, const char *path, const float *rgb, int width,
		int height, const struct image_meta *meta, char *err, size_t err_size);

/* round(255 · clamp(c, 0, 1)), ties up; NaN gives 0. The one 8-bit
 * conversion used everywhere. */
unsigned char image_to_8bit(float c);

#ifdef __cplusplus
}
#endif

#endif
