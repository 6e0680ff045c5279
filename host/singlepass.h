/* The single-pass renderer (serial, naive, cyclic, dynamic, persistent). */
#ifndef RTCL_SINGLEPASS_H
#define RTCL_SINGLEPASS_H

#include "settings.h"

/* A renderer_fn (settings.h): builds cl/KERNEL.cl, renders the warm-up and
 * timed frames with one launch each, and reads the image and counts back. */
int singlepass_render(struct device *dev, const struct scene *scene,
		      const struct render_settings *settings, struct render_result *result,
		      char *err, size_t err_size);

#endif
