/* The 8-bit encoding of image values (image.h), on its own so that the
 * OpenImageIO module (rtcl-oiio.so) links it too without the rest of image
 * output. */
#include <math.h>
#include <pthread.h>
#include <unistd.h>

#include "output/image.h"

double image_srgb_curve(double c)
{
	return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

unsigned char image_encode_8bit(float c, enum image_encoding encoding)
{
	if (encoding != IMAGE_SRGB || !(c > 0.0f) || c >= 1.0f)
		return image_to_8bit(c);
	return (unsigned char)floor(255.0 * image_srgb_curve((double)c) + 0.5);
}

unsigned char image_to_8bit(float c)
{
	if (!(c > 0.0f)) /* also NaN */
		return 0;
	if (c >= 1.0f)
		return 255;
	/* 255 · c is exact in double, so this rounds the true product. */
	return (unsigned char)floor(255.0 * (double)c + 0.5);
}

struct encode_range {
	const float *in;
	unsigned char *out;
	size_t begin, end;
	enum image_encoding encoding;
};

static void *encode_range(void *arg)
{
	const struct encode_range *r = arg;

	for (size_t i = r->begin; i < r->end; i++)
		r->out[i] = image_encode_8bit(r->in[i], r->encoding);
	return NULL;
}

void image_encode_all(const float *in, size_t count, enum image_encoding encoding,
		      unsigned char *out)
{
	struct encode_range ranges[IMAGE_ENCODE_THREADS];
	pthread_t ids[IMAGE_ENCODE_THREADS];
	int started[IMAGE_ENCODE_THREADS] = {0};
	long cores = sysconf(_SC_NPROCESSORS_ONLN);
	/* A thread for at least 2^18 values (a 300x300 image): smaller ones
	 * take less than starting it. */
	size_t most = count >> 18;
	int threads = cores < 1 ? 1 : cores > IMAGE_ENCODE_THREADS ? IMAGE_ENCODE_THREADS : (int)cores;

	if ((size_t)threads > most)
		threads = most < 1 ? 1 : (int)most;
	for (int i = 0; i < threads; i++) {
		ranges[i] = (struct encode_range){in, out, count * i / threads,
						  count * (i + 1) / threads, encoding};
		started[i] = i > 0 && pthread_create(&ids[i], NULL, encode_range, &ranges[i]) == 0;
	}
	for (int i = 0; i < threads; i++)
		if (!started[i]) /* the first, and any the system would not start */
			encode_range(&ranges[i]);
	for (int i = 1; i < threads; i++)
		if (started[i])
			pthread_join(ids[i], NULL);
}
