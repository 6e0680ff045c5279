/* CPU reference renderer: the test oracle for the OpenCL kernels.
 *
 * A plain recursive Whitted tracer and a path tracer (the scene's
 * integrator), in double precision (C++ with GLM), written from
 * docs/RENDERING.md independently of the code in cl/.
 */
#ifndef RTCL_REFERENCE_H
#define RTCL_REFERENCE_H

#include <stddef.h>

#include "scene/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Renders `scene` as RENDERING.md defines it, by its integrator (trace(), or
 * "Path tracing"), with width, height and max_depth taken from the arguments
 * (not from the scene). Writes the linear,
 * unclamped colour of pixel (x, y) to rgb[3 * (y * width + x) + c], c = 0, 1, 2
 * for red, green, blue; rgb must hold 3 * width * height floats.
 * Returns 0 on success, -1 on invalid arguments (NULL pointer, width or height
 * < 1, max_depth < 0) or allocation failure; rgb is then left unspecified. */
int reference_render(const struct scene *scene, int width, int height, int max_depth, float *rgb);

/* reference_render with `samples` samples per pixel (RENDERING.md, "Samples
 * per pixel"): the pixel is the mean of its samples' colours. samples < 1 is
 * refused (-1). reference_render is samples = 1. */
int reference_render_samples(const struct scene *scene, int width, int height, int max_depth,
			     int samples, float *rgb);

/* Adds sample k of `samples` of every pixel to sums (3 doubles a pixel,
 * row-major), the same colour reference_render_samples takes the mean of:
 * called for k = 0, 1, ... in order, then reference_mean, it gives the same
 * image. Returns 0, or -1 as reference_render_samples. */
int reference_render_sample(const struct scene *scene, int width, int height, int max_depth, int k,
			    int samples, double *sums);

/* The mean of `values` sums of `samples` samples into rgb, as floats. */
void reference_mean(const double *sums, size_t values, int samples, float *rgb);

/* Sets uv to sample k (0 <= k < n) of pixel (x, y)'s position in the pixel, in
 * [0, 1)^2 from its top-left corner, as RENDERING.md defines it. */
void reference_sample_position(int x, int y, int k, int n, double uv[2]);

/* Sets st to dimension pair `pair` (>= 1: 1 the lens, 2 + depth * lights +
 * light a light's sample) of sample k of pixel (x, y) out of n, in [0, 1)^2,
 * as RENDERING.md ("More dimensions") defines it. */
void reference_sample_pair(int x, int y, int k, int n, int pair, double st[2]);

/* For tests of the path integrator (RENDERING.md "Path tracing"): at the hit
 * of sample k of n of pixel (x, y)'s primary ray in `scene` (its own image
 * size), the MIS weights of vertex 0's light sample (weights[0]) and of a
 * BSDF ray along the same direction finding the same emitter or the
 * environment (weights[1]). Returns 0, or -1 when that sample has no such
 * pair (a delta light, a blocked light, f = 0, no hit). */
int reference_path_mis_weights(const struct scene *scene, int x, int y, int k, int n,
			       double weights[2]);

#ifdef __cplusplus
}
#endif

#endif
