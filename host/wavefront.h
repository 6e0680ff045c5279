/* The multi-pass wavefront renderer (cl/wavefront.cl). */
#ifndef RTCL_WAVEFRONT_H
#define RTCL_WAVEFRONT_H

#include "settings.h"

/* A renderer_fn (settings.h): one launch for the primary rays, then one per
 * bounce over a queue of live rays, for the warm-up and timed frames. */
int wavefront_render(struct device *dev, const struct scene *scene,
		     const struct render_settings *settings, struct render_result *result,
		     char *err, size_t err_size);

#endif
