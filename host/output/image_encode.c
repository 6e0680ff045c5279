/* The 8-bit encoding of image values (image.h), on its own so that the
 * OpenImageIO module (rtcl-oiio.so) links it too without the rest of image
 * output. */
#include <math.h>

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
