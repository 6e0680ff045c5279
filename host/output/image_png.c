/* The PNG writer (see image_png.h): one IDAT stream compressed by zlib, each
 * row with the Up filter (the row minus the one above), which suits renders'
 * smooth areas and costs one subtraction a byte. zlib level 1: on a
 * 1000x1000 render of 60 balls (busy machine) 585 kB in 75 ms of encoding and
 * writing, against 537 kB in 110 ms at level 3 and 469 kB (OpenImageIO's
 * size) in 310 ms at level 6; a render's time to image matters more than a
 * fifth of its file. */
#include "output/image_png.h"

#include <errno.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#define PNG_LEVEL 1

static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

static void put32(unsigned char *p, uint32_t v)
{
	p[0] = (unsigned char)(v >> 24);
	p[1] = (unsigned char)(v >> 16);
	p[2] = (unsigned char)(v >> 8);
	p[3] = (unsigned char)v;
}

/* One chunk: length, type, data, CRC of type and data. */
static int chunk(FILE *file, const char type[4], const void *data, size_t size)
{
	unsigned char head[8], tail[4];
	uLong crc = crc32(0L, (const Bytef *)type, 4);

	if (size > 0x7fffffff)
		return -1;
	put32(head, (uint32_t)size);
	memcpy(head + 4, type, 4);
	if (size)
		crc = crc32(crc, data, (uInt)size);
	put32(tail, (uint32_t)crc);
	return fwrite(head, 1, 8, file) == 8 && (!size || fwrite(data, 1, size, file) == size) &&
			       fwrite(tail, 1, 4, file) == 4
		       ? 0
		       : -1;
}

/* A tEXt chunk: keyword, NUL, text (line breaks made spaces, as in PPMs). */
static int text_chunk(FILE *file, const char *key, const char *text)
{
	size_t k = strlen(key), t = strlen(text);
	char *data = malloc(k + 1 + t);
	int ret;

	if (!data)
		return -1;
	memcpy(data, key, k + 1);
	for (size_t i = 0; i < t; i++)
		data[k + 1 + i] = text[i] == '\n' || text[i] == '\r' ? ' ' : text[i];
	ret = chunk(file, "tEXt", data, k + 1 + t);
	free(data);
	return ret;
}

/* IHDR, the colour tags and the text chunks. */
static int header(FILE *file, int width, int height, const struct image_meta *meta)
{
	/* sRGB's white point and primaries, times 100000 (the cHRM chunk). */
	static const uint32_t chrm[8] = {31270, 32900, 64000, 33000, 30000, 60000, 15000, 6000};
	int linear = image_meta_encoding(meta) == IMAGE_LINEAR;
	unsigned char ihdr[13] = {0}, gama[4], chrm_data[32], intent = 3;

	put32(ihdr, (uint32_t)width);
	put32(ihdr + 4, (uint32_t)height);
	ihdr[8] = 8; /* bits per channel */
	ihdr[9] = 2; /* RGB */
	put32(gama, linear ? 100000 : 45455);
	for (int i = 0; i < 8; i++)
		put32(chrm_data + 4 * i, chrm[i]);
	if (fwrite(signature, 1, 8, file) != 8 || chunk(file, "IHDR", ihdr, 13) ||
	    chunk(file, "gAMA", gama, 4) ||
	    (!linear && (chunk(file, "sRGB", &intent, 1) || chunk(file, "cHRM", chrm_data, 32))))
		return -1;
	if (meta && meta->software && text_chunk(file, "Software", meta->software))
		return -1;
	if (meta && meta->description && text_chunk(file, "Description", meta->description))
		return -1;
	if (meta && meta->samples > 0) {
		char samples[16];
		snprintf(samples, sizeof(samples), "%d", meta->samples);
		if (text_chunk(file, IMAGE_SAMPLES_KEY, samples))
			return -1;
	}
	return text_chunk(file, "oiio:ColorSpace", linear ? "linear" : "sRGB");
}

/* Row y as PNG wants it: the filter byte (2, Up), then each byte minus the
 * one above it (row - 1 is zero above the first). */
static void filter_row(const float *rgb, int width, int y, enum image_encoding encoding,
		       unsigned char *above, unsigned char *out)
{
	size_t n = 3 * (size_t)width;
	const float *in = rgb + (size_t)y * n;

	out[0] = 2;
	for (size_t i = 0; i < n; i++) {
		unsigned char v = image_encode_8bit(in[i], encoding);
		out[1 + i] = (unsigned char)(v - above[i]);
		above[i] = v;
	}
}

/* Compresses the filtered rows into IDAT chunks of out_size bytes (the last
 * one shorter). */
static int write_idat(FILE *file, z_stream *z, const float *rgb, int width, int height,
		      enum image_encoding encoding, unsigned char *row, unsigned char *above,
		      unsigned char *out, size_t out_size)
{
	size_t row_size = 1 + 3 * (size_t)width;
	int status = Z_OK;

	z->next_out = out;
	z->avail_out = (uInt)out_size;
	for (int y = 0; y <= height; y++) {
		int last = y == height;
		if (!last)
			filter_row(rgb, width, y, encoding, above, row);
		z->next_in = row;
		z->avail_in = last ? 0 : (uInt)row_size;
		do {
			status = deflate(z, last ? Z_FINISH : Z_NO_FLUSH);
			if (status == Z_STREAM_ERROR)
				return -1;
			if (z->avail_out == 0 || status == Z_STREAM_END) {
				size_t have = out_size - z->avail_out;
				if (have && chunk(file, "IDAT", out, have))
					return -1;
				z->next_out = out;
				z->avail_out = (uInt)out_size;
			}
		} while (z->avail_in > 0 || (last && status != Z_STREAM_END));
	}
	return 0;
}

int image_png_write(FILE *file, const float *rgb, int width, int height,
		    const struct image_meta *meta)
{
	const size_t out_size = 1 << 16;
	size_t row_size = 1 + 3 * (size_t)width;
	unsigned char *row = malloc(row_size), *above = calloc(row_size, 1);
	unsigned char *out = malloc(out_size);
	z_stream z;
	int ret = -1;

	memset(&z, 0, sizeof(z));
	errno = 0;
	if (!row || !above || !out || deflateInit(&z, PNG_LEVEL) != Z_OK)
		goto out_free;
	if (header(file, width, height, meta) == 0 &&
	    write_idat(file, &z, rgb, width, height, image_meta_encoding(meta), row, above, out,
		       out_size) == 0 &&
	    chunk(file, "IEND", NULL, 0) == 0)
		ret = 0;
	deflateEnd(&z);
out_free:
	free(out);
	free(above);
	free(row);
	return ret;
}

int image_png_check(const char *path, int width, int height)
{
	unsigned char head[8 + 8 + 13];
	FILE *file = fopen(path, "rb");
	int ok;

	if (!file)
		return 0;
	ok = fread(head, 1, sizeof(head), file) == sizeof(head) &&
	     memcmp(head, signature, 8) == 0 && memcmp(head + 12, "IHDR", 4) == 0 &&
	     head[16] == (unsigned char)(width >> 24) && head[17] == (unsigned char)(width >> 16) &&
	     head[18] == (unsigned char)(width >> 8) && head[19] == (unsigned char)width &&
	     head[20] == (unsigned char)(height >> 24) &&
	     head[21] == (unsigned char)(height >> 16) &&
	     head[22] == (unsigned char)(height >> 8) && head[23] == (unsigned char)height &&
	     head[24] == 8 && head[25] == 2;
	fclose(file);
	return ok;
}
