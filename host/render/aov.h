/* The auxiliary images (--aov, --denoise): cl/aov.cl's pass over the whole
 * image on a renderer's program and scene, after the image. */
#ifndef RTCL_AOV_H
#define RTCL_AOV_H

#include "render/buffers.h"

/* Floats a pixel in render_result.aov: albedo 3, normal 3, depth 1. */
#define AOV_FLOATS 7

/* Renders the auxiliary images of s's image with b's program (built with
 * settings.aov) and scene into res->aov (malloc'd), over the samples the
 * image holds (res->samples_done, fewer than all after an interrupt).
 * Returns 0, or -1 with one message in err. */
int aov_render(struct device *dev, const struct render_settings *s, struct render_result *res,
	       const struct render_buffers *b, char *err, size_t err_size);

#endif
