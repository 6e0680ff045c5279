/* SIMD efficiency, modelled from one instrumented run's flops per pixel and
 * schedule map (docs/RENDERING.md, "SIMD efficiency, modelled"): warps of
 * consecutive work-items in lock-step, a warp-step costing its most
 * expensive lane. */
#ifndef RTCL_SIMD_H
#define RTCL_SIMD_H

#include <stddef.h>
#include <stdint.h>

#include "render/settings.h"

/* The warp width of the model: NVIDIA's warps. */
#define SIMD_WARP_WIDTH 32

struct simd_model {
	double efficiency;   /* Σ flops / (width × Σ warp-step costs); 1 with no work */
	uint64_t warp_steps; /* warp-steps that traced at least one pixel */
	uint64_t flops;	     /* Σ flops of every pixel */
	uint64_t capacity;   /* width × Σ warp-step costs */
	uint64_t items_used; /* work-items that traced at least one pixel */
	int width;
};

/* The measured SIMD efficiency of phase (RT_SIMD_*) of an instrumented run
 * (docs/RENDERING.md, "SIMD efficiency, measured"): its steps over
 * SIMD_WARP_WIDTH times its warp-steps; 1 with none. */
double simd_measured(const struct render_result *counted, int phase);

/* The measured SIMD efficiency of both phases together, intersection and
 * traversal (RT_SIMD_INTERSECT, RT_SIMD_TRAVERSAL): their steps over
 * SIMD_WARP_WIDTH times their warp-steps; 1 with none. */
double simd_measured_all(const struct render_result *counted);

/* The same over the first `phases` phases (RT_SIMD_PHASES: every phase,
 * the path integrator's shading included). */
double simd_measured_first(const struct render_result *counted, int phases);

/* Models `pixels` pixels: schedule holds RT_SCHEDULE_WORDS per pixel (group,
 * item, ticket), pixel_flops one count each; width lanes a warp. Pixels no
 * work-item started (group all ones) are left out. Returns 0, or -1 when out
 * of host memory. */
int simd_model_compute(const uint32_t *schedule, const uint64_t *pixel_flops, size_t pixels,
		       int width, struct simd_model *out);

#endif
