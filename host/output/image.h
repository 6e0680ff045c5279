/* Image output.
 *
 * One interface, two implementations chosen at build time: image_dl.c loads
 * the module rtcl-oiio.so (image_oiio.cpp), which writes every format
 * OpenImageIO knows; image_ppm.c (OIIO=0) refuses them. Both link
 * image_common.c, which owns the checks, the temporary file and the .ppm/.pfm
 * writers, image_png.c, rtcl's own PNG writer, and image_encode.c, the 8-bit
 * conversion, so a .ppm, .pfm or .png is byte for byte the same whichever
 * implementation is linked.
 *
 * Float formats keep the linear values: .exr (32-bit float), .hdr (RGBE) and
 * .pfm (32-bit float). Every other format, TIFF included, gets 8 bits per
 * channel from image_encode_8bit() in the image's encoding (RENDERING.md,
 * "Writing the image"), and is tagged with it where the format can say so.
 *
 * Messages are one line, "PATH: what is wrong", without a trailing newline.
 */
#ifndef RTCL_IMAGE_H
#define RTCL_IMAGE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* How the 8-bit formats store a value c in [0, 1]. */
enum image_encoding {
	IMAGE_LINEAR,  /* round(255 c), tagged linear (the paper's images) */
	IMAGE_SRGB,    /* round(255 E(c)), E the sRGB curve, tagged sRGB */
	IMAGE_DISPLAY, /* round(255 c), tagged sRGB: values already meant for a
			  display (the work map's colour scale) */
};

struct image_meta {
	const char *software; /* e.g. "rtcl 0.1.0"; NULL for none */
	const char
		*description; /* e.g. "scene: scenes/paper60.json, kernel dynamic"; NULL for none */
	enum image_encoding encoding; /* a NULL meta: IMAGE_LINEAR */
	/* Samples per pixel the image holds (0: not said), recorded as
	 * IMAGE_SAMPLES_KEY: a PNG tEXt chunk, a PPM comment, an attribute of
	 * the formats OpenImageIO writes (EXR...) but TIFF; PFM has no room. */
	int samples;
};

/* The key a rendered image's samples per pixel are recorded under. */
#define IMAGE_SAMPLES_KEY "rtcl:samples_per_pixel"

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

/* round(255 · clamp(c, 0, 1)), ties up; NaN gives 0. */
unsigned char image_to_8bit(float c);

/* The IEC 61966-2-1 (sRGB) transfer curve of c in [0, 1]: 12.92 c up to
 * 0.0031308, else 1.055 c^(1/2.4) − 0.055; computed in double. */
double image_srgb_curve(double c);

/* round(255 · E(clamp(c, 0, 1))), ties up, NaN gives 0, with E the sRGB curve
 * for IMAGE_SRGB and the identity otherwise: the one 8-bit conversion. */
unsigned char image_encode_8bit(float c, enum image_encoding encoding);

/* The encoding a meta asks for (IMAGE_LINEAR for NULL). */
static inline enum image_encoding image_meta_encoding(const struct image_meta *meta)
{
	return meta ? meta->encoding : IMAGE_LINEAR;
}

#ifdef __cplusplus
}
#endif

#endif
