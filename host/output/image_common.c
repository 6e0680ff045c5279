/* The part of image output shared by both builds (see image.h): checks,
 * the temporary file and its rename, and the .ppm/.pfm writers (.png:
 * image_png.c; the 8-bit encoding: image_encode.c). */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "output/image.h"
#include "base/files.h"
#include "output/image_backend.h"
#include "output/image_png.h"

static int is_ppm(const char *ext)
{
	return strcasecmp(ext, ".ppm") == 0;
}

static int is_pfm(const char *ext)
{
	return strcasecmp(ext, ".pfm") == 0;
}

static int is_png(const char *ext)
{
	return strcasecmp(ext, ".png") == 0;
}

/* The formats rtcl writes itself, without the backend. */
static int is_native(const char *ext)
{
	return is_ppm(ext) || is_pfm(ext) || is_png(ext);
}

/* The format check (from the extension), then files_check_writable. */
static int check_path(const char *path, char *err, size_t err_size)
{
	const char *ext;

	if (!path || !*path) {
		image_set_error(err, err_size, "no output file name given");
		return -1;
	}
	ext = files_extension(path);
	if (!*ext && files_base_name(path)[0] == '.') {
		image_set_error(err, err_size,
				"%s: a name that starts with a dot has no extension to choose an "
				"image format by (e.g. render.png)",
				path);
		return -1;
	}
	if (!is_native(ext) && image_backend_check_format(path, ext, err, err_size))
		return -1;
	return files_check_writable(path, err, err_size);
}

int image_check_writable(const char *path, char *err, size_t err_size)
{
	return check_path(path, err, err_size);
}

/* Writes s on a "# " comment line, with line breaks made spaces. */
static void write_comment(FILE *file, const char *key, const char *s)
{
	fprintf(file, "# %s: ", key);
	for (; *s; s++)
		fputc(*s == '\n' || *s == '\r' ? ' ' : *s, file);
	fputc('\n', file);
}

/* Binary PPM, 8 bits per channel, metadata in comments. */
static int write_ppm(FILE *file, const float *rgb, int width, int height,
		     const struct image_meta *meta)
{
	size_t row_length = 3 * (size_t)width;
	unsigned char *row = malloc(row_length);
	int x, y;

	if (!row)
		return -1;
	fputs("P6\n", file);
	if (meta && meta->software)
		write_comment(file, "Software", meta->software);
	if (meta && meta->description)
		write_comment(file, "ImageDescription", meta->description);
	if (meta)
		write_comment(file, "Encoding", meta->encoding == IMAGE_LINEAR ? "linear" : "sRGB");
	if (meta && meta->samples > 0)
		fprintf(file, "# %s: %d\n", IMAGE_SAMPLES_KEY, meta->samples);
	fprintf(file, "%d %d\n255\n", width, height);

	for (y = 0; y < height; y++) {
		const float *in = rgb + (size_t)y * row_length;

		for (x = 0; x < 3 * width; x++)
			row[x] = image_encode_8bit(in[x], image_meta_encoding(meta));
		if (fwrite(row, 1, row_length, file) != row_length)
			break;
	}
	free(row);
	return ferror(file) ? -1 : 0;
}

/* PFM: linear floats, little endian (scale -1), rows from the bottom up.
 * The format has no room for metadata. */
static int write_pfm(FILE *file, const float *rgb, int width, int height)
{
	size_t row_floats = 3 * (size_t)width;
	unsigned char *row = malloc(4 * row_floats);
	size_t i;
	int y;

	if (!row)
		return -1;
	fprintf(file, "PF\n%d %d\n-1.0\n", width, height);

	for (y = height - 1; y >= 0; y--) {
		const float *in = rgb + (size_t)y * row_floats;

		for (i = 0; i < row_floats; i++) {
			uint32_t bits;

			memcpy(&bits, &in[i], 4);
			row[4 * i + 0] = (unsigned char)bits;
			row[4 * i + 1] = (unsigned char)(bits >> 8);
			row[4 * i + 2] = (unsigned char)(bits >> 16);
			row[4 * i + 3] = (unsigned char)(bits >> 24);
		}
		if (fwrite(row, 1, 4 * row_floats, file) != 4 * row_floats)
			break;
	}
	free(row);
	return ferror(file) ? -1 : 0;
}

/* Writes .ppm, .pfm or .png into fd, which it closes. */
static int write_native(int fd, const char *path, const float *rgb, int width, int height,
			const struct image_meta *meta, char *err, size_t err_size)
{
	FILE *file = fdopen(fd, "wb");
	int failed;

	if (!file) {
		image_set_error(err, err_size, "%s: %s", path, strerror(errno));
		close(fd);
		return -1;
	}
	errno = 0;
	if (is_png(files_extension(path)))
		failed = image_png_write(file, rgb, width, height, meta);
	else if (is_pfm(files_extension(path)))
		failed = write_pfm(file, rgb, width, height);
	else
		failed = write_ppm(file, rgb, width, height, meta);
	if (!failed)
		failed = fflush(file) || (fsync(fileno(file)) && errno != EINVAL);
	if (failed) {
		image_set_error(err, err_size, "%s: cannot write: %s", path,
				errno ? strerror(errno) : "out of memory");
		fclose(file);
		return -1;
	}
	if (fclose(file)) {
		image_set_error(err, err_size, "%s: cannot write: %s", path, strerror(errno));
		return -1;
	}
	return 0;
}

static int write_with_backend(int fd, const char *path, const char *tmp, const float *rgb,
			      int width, int height, const struct image_meta *meta, char *err,
			      size_t err_size)
{
	if (image_backend_encode(path, tmp, fd, rgb, width, height, meta, err, err_size)) {
		close(fd);
		return -1;
	}
	if (files_sync_close(fd)) {
		image_set_error(err, err_size, "%s: cannot write: %s", path, strerror(errno));
		return -1;
	}
	return 0;
}

/* Reads the header of the written file back: magic, width, height. */
static int verify_native(const char *path, const char *tmp, int width, int height, char *err,
			 size_t err_size)
{
	if (is_png(files_extension(path))) {
		if (image_png_check(tmp, width, height))
			return 0;
		image_set_error(err, err_size,
				"%s: the written file does not read back as a %dx%d PNG image",
				path, width, height);
		return -1;
	}
	const char *magic = is_pfm(files_extension(path)) ? "PF" : "P6";
	FILE *file = fopen(tmp, "rb");
	char found[3] = "";
	int w = 0, h = 0, ch, ok = 0;

	if (file && fread(found, 1, 2, file) == 2 && strcmp(found, magic) == 0) {
		/* Comments (PPM only) run from '#' to the end of the line. */
		while ((ch = fgetc(file)) == '#' || ch == ' ' || ch == '\n' || ch == '\r' ||
		       ch == '\t')
			if (ch == '#')
				while ((ch = fgetc(file)) != EOF && ch != '\n')
					;
		ok = ch != EOF && ungetc(ch, file) != EOF && fscanf(file, "%d %d", &w, &h) == 2 &&
		     w == width && h == height;
	}
	if (file)
		fclose(file);
	if (!ok)
		image_set_error(err, err_size,
				"%s: the written file does not read back as a %dx%d %s image", path,
				width, height, magic);
	return ok ? 0 : -1;
}

/* The largest value the format at ext holds: Radiance HDR's RGBE keeps an
 * 8-bit exponent, whose largest value is 2^127 (a value at or above it wraps
 * to black); the other float formats hold any float. */
static float largest_value(const char *ext)
{
	if (strcasecmp(ext, ".hdr") == 0 || strcasecmp(ext, ".rgbe") == 0)
		return nextafterf(ldexpf(1.0f, 127), 0.0f);
	return FLT_MAX;
}

/* Radiance that overflowed float (+inf) or that the format cannot hold,
 * clamped to its largest value (RENDERING.md, "Writing
 * the image"): never inf, never black. Returns rgb itself when nothing
 * needs it, else a malloc'd copy in *copy (NULL when out of memory). */
static const float *clamp_radiance(const float *rgb, size_t count, float largest, float **copy)
{
	size_t i = 0;

	*copy = NULL;
	while (i < count && !(rgb[i] > largest))
		i++;
	if (i == count)
		return rgb;
	*copy = malloc(count * sizeof(float));
	if (!*copy)
		return NULL;
	for (i = 0; i < count; i++)
		(*copy)[i] = rgb[i] > largest ? largest : rgb[i]; /* NaN stays NaN */
	return *copy;
}

int image_stage(struct staged_file *staged, const char *path, const float *rgb, int width,
		int height, const struct image_meta *meta, char *err, size_t err_size)
{
	const char *ext = files_extension(path);
	int native = is_native(ext);
	int fd, failed;
	float *clamped;

	if (check_path(path, err, err_size))
		return -1;
	if (!rgb || width <= 0 || height <= 0 || (size_t)width > SIZE_MAX / 12 / (size_t)height) {
		image_set_error(err, err_size, "%s: invalid image (%d x %d pixels%s)", path, width,
				height, rgb ? "" : ", no data");
		return -1;
	}
	rgb = clamp_radiance(rgb, (size_t)width * (size_t)height * 3, largest_value(ext), &clamped);
	if (!rgb) {
		image_set_error(err, err_size, "%s: out of memory for a %d x %d image", path, width,
				height);
		return -1;
	}
	fd = files_stage(staged, path, err, err_size);
	if (fd < 0) {
		free(clamped);
		return -1;
	}
	if (native)
		failed = write_native(fd, path, rgb, width, height, meta, err, err_size) ||
			 verify_native(path, staged->temp, width, height, err, err_size);
	else
		failed = write_with_backend(fd, path, staged->temp, rgb, width, height, meta, err,
					    err_size) ||
			 image_backend_verify(path, staged->temp, width, height, err, err_size);
	free(clamped);
	if (failed)
		files_discard(staged);
	return failed ? -1 : 0;
}

int image_write(const char *path, const float *rgb, int width, int height,
		const struct image_meta *meta, char *err, size_t err_size)
{
	struct staged_file staged;

	if (image_stage(&staged, path, rgb, width, height, meta, err, err_size))
		return -1;
	return files_commit(&staged, 1, err, err_size);
}
