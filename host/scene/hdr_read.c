/* Radiance .hdr (RGBE) images, read without OpenImageIO so that every build
 * has environment maps (SCENE.md, "environment"): the header, the standard
 * orientation "-Y H +X W", and the pixels flat or run-length encoded
 * ("new" RLE, one channel at a time per scanline), each decoded as
 * m * 2^(e - 136) per channel (0 where e is 0), as stb_image does. */
#include "scene/hdr_read.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/files.h"

/* A map of HDR_MAX_SIDE a side is 1 GiB of RGBE: the file's limit. */
#define HDR_MAX_BYTES ((size_t)HDR_MAX_SIDE * HDR_MAX_SIDE * 4 + 65536)

/* The next header line of text[*at ... len), without its newline, into
 * line[size]; false at the end of the text. */
static int next_line(const char *text, size_t len, size_t *at, char *line, size_t size)
{
	size_t n = 0;

	if (*at >= len)
		return 0;
	while (*at < len && text[*at] != '\n') {
		if (n + 1 < size)
			line[n++] = text[*at];
		(*at)++;
	}
	line[n] = '\0';
	(*at)++; /* the newline */
	return 1;
}

static void decode(const unsigned char rgbe[4], float *rgb)
{
	if (rgbe[3] == 0) {
		rgb[0] = rgb[1] = rgb[2] = 0;
		return;
	}
	float f = ldexpf(1.0f, (int)rgbe[3] - 136);
	for (int c = 0; c < 3; c++)
		rgb[c] = (float)rgbe[c] * f;
}

/* One scanline of width pixels at data[*at ... len) into rgbe[4 * width]:
 * flat, or run-length encoded channel by channel. Returns 0, or -1 when the
 * data ends early or a run overflows the line. */
static int read_scanline(const unsigned char *data, size_t len, size_t *at, int width,
			 unsigned char *rgbe)
{
	size_t i = *at;

	if (width >= 8 && width < 32768 && i + 4 <= len && data[i] == 2 && data[i + 1] == 2 &&
	    ((data[i + 2] << 8) | data[i + 3]) == width && !(data[i + 2] & 0x80)) {
		i += 4;
		for (int c = 0; c < 4; c++)
			for (int x = 0; x < width;) {
				if (i >= len)
					return -1;
				int count = data[i++];
				if (count > 128) { /* a run of one value */
					count -= 128;
					if (count > width - x || i >= len)
						return -1;
					for (int k = 0; k < count; k++)
						rgbe[4 * (x++) + c] = data[i];
					i++;
				} else { /* count values as they are */
					if (count == 0 || count > width - x || i + (size_t)count > len)
						return -1;
					for (int k = 0; k < count; k++)
						rgbe[4 * (x++) + c] = data[i++];
				}
			}
		*at = i;
		return 0;
	}
	if (i + 4 * (size_t)width > len)
		return -1;
	memcpy(rgbe, data + i, 4 * (size_t)width);
	*at = i + 4 * (size_t)width;
	return 0;
}

int hdr_read(const char *path, const char *shown, struct hdr_image *out, char *err,
	     size_t err_size)
{
	char *text = NULL, line[256];
	size_t len = 0, at = 0;
	int width = 0, height = 0, ret = -1;
	unsigned char *scanline = NULL;

	memset(out, 0, sizeof(*out));
	if (files_read(path, "environment map", HDR_MAX_BYTES, &text, &len, err, err_size)) {
		/* files_read names the path; the message names the file as the scene does */
		char reason[512];
		const char *colon = strrchr(err, ':');
		snprintf(reason, sizeof(reason), "%s", colon ? colon + 2 : err);
		snprintf(err, err_size, "cannot read \"%s\": %s", shown, reason);
		return -1;
	}
	if (len < 2 || text[0] != '#' || text[1] != '?') {
		snprintf(err, err_size,
			 "\"%s\" is not a Radiance HDR file (it does not start with \"#?\")", shown);
		goto out;
	}
	while (next_line(text, len, &at, line, sizeof(line)) && line[0] != '\0')
		if (strncmp(line, "FORMAT=", 7) == 0 && strcmp(line + 7, "32-bit_rle_rgbe") != 0) {
			snprintf(err, err_size,
				 "\"%s\": its FORMAT is \"%.64s\"; rtcl reads 32-bit_rle_rgbe", shown,
				 line + 7);
			goto out;
		}
	if (!next_line(text, len, &at, line, sizeof(line)) ||
	    sscanf(line, "-Y %d +X %d", &height, &width) != 2) {
		snprintf(err, err_size,
			 "\"%s\": its size line is \"%.64s\"; rtcl reads \"-Y height +X width\" "
			 "(rows from the top, columns from the left)",
			 shown, line);
		goto out;
	}
	if (width < 1 || height < 1 || width > HDR_MAX_SIDE || height > HDR_MAX_SIDE) {
		snprintf(err, err_size, "\"%s\" is %dx%d; rtcl reads 1 to %d pixels a side", shown,
			 width, height, HDR_MAX_SIDE);
		goto out;
	}
	/* The least a scanline takes: flat pixels of 4 bytes, or run-length
	 * encoded runs of at most 128 values, 2 bytes a run and channel. So a
	 * short file that declares a huge image is refused before its pixels
	 * are allocated. */
	size_t least = width >= 8 && width < 32768 ? 4 + 8 * (((size_t)width + 127) / 128)
						   : 4 * (size_t)width;
	if ((len - at) / least < (size_t)height) {
		snprintf(err, err_size,
			 "\"%s\": its header declares %dx%d pixels, at least %zu bytes, but the "
			 "file holds %zu after its header",
			 shown, width, height, least * (size_t)height, len - at);
		goto out;
	}
	out->rgb = malloc((size_t)width * height * 3 * sizeof(float));
	scanline = malloc((size_t)width * 4);
	if (!out->rgb || !scanline) {
		snprintf(err, err_size, "\"%s\": out of memory for its %dx%d pixels", shown, width,
			 height);
		goto out;
	}
	for (int y = 0; y < height; y++) {
		if (read_scanline((const unsigned char *)text, len, &at, width, scanline)) {
			snprintf(err, err_size, "\"%s\": its pixels end after row %d of %d", shown,
				 y, height);
			goto out;
		}
		for (int x = 0; x < width; x++)
			decode(scanline + 4 * x, out->rgb + 3 * ((size_t)y * width + x));
	}
	out->width = width;
	out->height = height;
	ret = 0;
out:
	if (ret) {
		free(out->rgb);
		out->rgb = NULL;
	}
	free(scanline);
	free(text);
	return ret;
}
