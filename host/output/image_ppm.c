/* Image output without OpenImageIO (OIIO=0): image_common.c writes .ppm,
 * .pfm and .png itself; every other extension is refused here. */
#include <stddef.h>

#include "output/image.h"
#include "output/image_backend.h"

int image_backend_check_format(const char *path, const char *ext, char *err, size_t err_size)
{
	image_set_error(
		err, err_size,
		"%s: this build has no OpenImageIO and writes only .ppm, .pfm and .png%s%s%s "
		"(rebuild without OIIO=0 for other formats)",
		path, *ext ? ", not \"" : "", ext, *ext ? "\"" : "");
	return -1;
}

int image_backend_encode(const char *path, const char *tmp_path, int tmp_fd, const float *rgb,
			 int width, int height, const struct image_meta *meta, char *err,
			 size_t err_size)
{
	/* Unreachable: image_backend_check_format() refused the format. */
	(void)tmp_path;
	(void)tmp_fd;
	(void)rgb;
	(void)width;
	(void)height;
	(void)meta;
	image_set_error(err, err_size, "%s: no writer for this format in this build", path);
	return -1;
}

int image_backend_verify(const char *path, const char *tmp_path, int width, int height, char *err,
			 size_t err_size)
{
	/* Unreachable, as image_backend_encode is. */
	(void)tmp_path;
	(void)width;
	(void)height;
	image_set_error(err, err_size, "%s: no reader for this format in this build", path);
	return -1;
}
