/* Radiance .hdr images (environment maps, SCENE.md "environment"). */
#ifndef RTCL_HDR_READ_H
#define RTCL_HDR_READ_H

#include <stddef.h>

#define HDR_MAX_SIDE 16384

struct hdr_image {
	int width, height;
	float *rgb; /* width * height * 3 linear floats, row 0 at the top */
};

/* Reads the .hdr file at path (shown: its name as the scene writes it, for
 * messages) into *out. Returns 0, or -1 with one message in err, e.g.
 * `cannot read "sky.hdr": No such file or directory`. */
int hdr_read(const char *path, const char *shown, struct hdr_image *out, char *err,
	     size_t err_size);

#endif
