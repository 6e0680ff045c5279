/* What a render is asked for and what it gives back: the data that passes
 * between main, render.c and the renderers below it (singlepass.c,
 * wavefront.c). Types only, so that every layer can include it. */
#ifndef RTCL_SETTINGS_H
#define RTCL_SETTINGS_H

#include <stddef.h>
#include <stdint.h>

#include "rtcl_shared.h"
#include "device/device.h"
#include "scene/scene.h"

struct render_settings;
struct render_result;
struct renderer_ops; /* renderer.h */
struct stages_stats;  /* render/stages.h */

/* The counting build's paths (docs/RENDERING.md, "Paths per bounce"), summed
 * over work-items: by length in segments (bin b: b + 1 segments, the last
 * bin RT_PATH_LENGTH_BINS or more), the longest, and every path's segments.
 * All 0 under Whitted. */
struct path_counts {
	uint64_t lengths[RT_PATH_LENGTH_BINS];
	uint64_t max, segments;
};

/* Adds one work-item's counts (RT_ITEM_COUNTS words) to paths. */
static inline void path_counts_add_item(struct path_counts *paths, const uint64_t *item)
{
	for (int b = 0; b < RT_PATH_LENGTH_BINS; b++)
		paths->lengths[b] += item[RT_ITEM_PATH_LENGTHS + b];
	if (item[RT_ITEM_PATH_MAX] > paths->max)
		paths->max = item[RT_ITEM_PATH_MAX];
	paths->segments += item[RT_ITEM_PATH_SEGMENTS];
}

/* Adds the paths `from` counted (another device's, a piece's) to `to`. */
static inline void path_counts_merge(struct path_counts *to, const struct path_counts *from)
{
	for (int b = 0; b < RT_PATH_LENGTH_BINS; b++)
		to->lengths[b] += from->lengths[b];
	if (from->max > to->max)
		to->max = from->max;
	to->segments += from->segments;
}

/* The scheduling kernels, one cl/NAME.cl each. */
struct kernel_info {
	const char *name;
	const char *summary;
	int uses_groups;		/* persistent work-groups: --groups applies */
	int single_item;		/* one work-item renders everything: -w does not apply */
	int multi_pass;			/* several launches per frame (wavefront) */
	int pixel_counter;		/* its work counter counts pixels, --batch at a time */
	int counts_handed_out;		/* the progress line reads the work handed out
					   (RT_COUNTER_NEXT), not the chunks done */
	const struct renderer_ops *ops; /* singlepass_ops or wavefront_ops */
};

/* --accel: how the tracer finds a ray's hit among the spheres. */
enum accel {
	ACCEL_NONE,	   /* every sphere tested, the paper's brute force */
	ACCEL_BVH,	   /* a BVH built on the host (host/layout/bvh.c, docs/bvh.md) */
	ACCEL_BVH_COMPACT, /* the same, its leaves of triangles larger: fewer
			      nodes, more triangle tests (bvh-compact) */
};

/* The --accel word of an enum accel: "none", "bvh", "bvh-compact". */
const char *accel_name(int accel);

/* --fetch: how a work-item of the persistent kernel takes its pixels from
 * the global counter (cl/persistent.cl). */
enum fetch {
	FETCH_ITEM,	/* an atomic of its own */
	FETCH_GROUP,	/* from its work-group's block in __local memory */
	FETCH_SUBGROUP, /* one atomic for the active lanes of its warp */
};

/* The --fetch word of an enum fetch: "item", "group", "subgroup". */
const char *fetch_name(int fetch);

/* --checkpoint: every `seconds` of a render's passes, the image of the
 * samples done so far (the mean of every pixel's first `samples`) goes to
 * write(context, ...), which returns 0, or -1 with one message in err (the
 * render then fails). Only for a render of the whole image on one device
 * (render(), render_reference()). */
struct render_checkpoint {
	double seconds;
	int (*write)(void *context, const float *rgb, int samples, char *err, size_t err_size);
	void *context;
};

struct render_settings {
	const struct kernel_info *kernel; /* NULL: the CPU reference */
	int workgroup[2];		  /* local size, e.g. 8x8 */
	int groups[2];	   /* persistent work-groups; 0x0: enough to fill the device */
	int width, height; /* image size */
	int max_depth;
	int samples;		/* N, samples per pixel (0 counts as 1) */
	int samples_per_pass;	/* 0: chosen by render_pass_samples() */
	int repeat;		/* timed frames */
	int warm_up;		/* one untimed launch first (-r given) */
	int batch;		/* pixels per fetch of the persistent kernel (0: 1) */
	int fetch;		/* enum fetch: how its work-items fetch (--fetch) */
	int regenerate;		/* its paths regenerated (--regenerate, RTCL_REGENERATE) */
	int wavefront_stages;	/* --wavefront-form stages: the wavefront under the
				   path integrator in stages (host/render/stages.c) */
	int wavefront_form_given; /* --wavefront-form given: the path integrator only */
	int paths_in_flight;	/* its pool of path slots (0: stages_default_paths) */
	int queues;		/* in-order queues per device (--queues; 0: the
				   default, renderer_queues()) */
	int count_flops;	/* build with RTCL_COUNT_FLOPS and return the counts */
	int check_writes;	/* tests: count writes per pixel, poison the image and
				   surround it with guard zones (checks.h) */
	int record_schedule;	/* build with RTCL_SCHEDULE_MAP and return each pixel's
				   work-group, work-item and ticket (probe.h) */
	int aov;		/* build cl/aov.cl's kernel and render the auxiliary
				   images after the image (render_result.aov) */
	int force_global_scene; /* read the scene from __global memory even if it
				   would fit in __local memory */
	int accel;		/* enum accel (--accel) */
	const char *source_dir; /* load cl/ sources from here instead of the
				   embedded copies (development) */
	int progress;		/* render() runs the progress line (progress.h) itself;
				   else its caller does, and render() adds to it */
	int stoppable;		/* an interrupt between passes stops the render, which
				   keeps the samples done (interrupt_stop_signal;
				   render_result.samples_done); one frame, no -r */
	const struct render_checkpoint *checkpoint; /* NULL: none */
	int verbose;
};

/* Where a render's host time went, in milliseconds (wall clock). */
struct render_times {
	double build;	  /* the program build */
	double scene;	  /* packing the scene, creating and filling the buffers */
	double kernels;	  /* every launch, warm-up included, with its waits */
	double aov;	  /* the auxiliary images' pass (settings.aov), read-back included */
	double read_back; /* the image and counts back to the host */
};

/* Room for rtcl's own build options and RTCL_BUILD_OPTIONS (program.h). */
#define BUILD_OPTIONS_SIZE 576

/* One piece of an image over several devices (schedule/tiles.h), as the
 * --stats document shows it: the schedule over devices made visible. */
struct piece_record {
	struct rt_piece piece; /* its split rows and samples */
	int device;	       /* index into the job's devices */
	double start_ms, end_ms; /* taken and done, from the frame's start */
	double kernel_ms;	 /* its launches' profiled time */
};

struct render_result {
	float *rgb; /* width*height*3 linear floats, row 0 at the top */
	/* With settings.aov: width*height*7 floats, the albedo (3 a pixel), the
	 * normal (3 a pixel), then the depth (1 a pixel), planes one after
	 * another (cl/aov.cl). */
	float *aov;
	/* Each timed frame's time, in order, and their median, min and max: on
	 * one device the sum of its launches' profiled kernel times; over
	 * several devices (--devices) the frame's wall time. */
	double kernel_ms_median, kernel_ms_min, kernel_ms_max;
	double *kernel_ms;
	/* Each timed frame's wall time on the host, from its first launch to the
	 * end of its last, the gaps between launches included, and their
	 * median: what --devices times, so that one device and several compare
	 * alike (docs/GUIDE.md, "Measuring"). */
	double *frame_ms;
	double frame_ms_median;
	int repeat;
	int launches; /* frames rendered: the timed ones and any warm-up */
	int passes;   /* passes per frame, each a range of the samples */
	int samples_done; /* samples of every pixel in rgb: settings_samples(),
			     or fewer when an interrupt stopped the render */
	int passes_done;  /* passes that ran: passes, or fewer when stopped */
	struct render_times times;
	int groups[2]; /* as launched (1x1 for serial; the NDRange's for naive) */
	size_t global_size[2], local_size[2];
	int scene_in_local;
	size_t scene_bytes;
	int vertex_count; /* the triangles' distinct vertices (host/layout/mesh_block.h) */
	char build_options[BUILD_OPTIONS_SIZE];
	int build_cached; /* the program came from rtcl's cache (progcache.h) */
	int fetch_lanes;  /* the persistent kernel's work-items one fetch from the
			     global counter serves at most (settings.fetch): 1 for
			     item, the work-group's for group, the warp's (32) for
			     subgroup where the device has warp primitives, else 1 */
	int queues;	  /* the most in-order queues a piece rendered with
			     (renderer_all_samples) */

	/* With count_flops: per launched work-item, row-major over the global
	 * NDRange. */
	uint64_t *item_flops;
	size_t item_count;
	uint64_t *pixel_flops; /* per pixel, row-major */
	uint64_t total_flops, total_rays;
	uint64_t total_node_visits; /* BVH nodes visited by every ray */
	uint64_t total_leaf_visits; /* BVH leaves visited by every ray */
	uint64_t total_prim_tests;  /* spheres and triangles tested in them */
	/* SIMD steps, measured (simd_measured: RT_SIMD_* phases): the steps every
	 * work-item took, and the warp-steps (docs/RENDERING.md). */
	int simd_measured;
	uint64_t lane_steps[RT_SIMD_PHASES], warp_steps[RT_SIMD_PHASES];
	struct path_counts paths; /* the paths by length, under the path integrator */

	/* The BVH, with ACCEL_BVH and a sphere or triangle (else bvh_nodes 0). */
	int bvh_nodes, bvh_depth;
	int bvh_width; /* the device's nodes: 2 (binary) or 4 (a CPU's), 0: none */
	int bvh_device_nodes; /* bvh_nodes, or the four-wide nodes they became */
	double bvh_sah_cost, bvh_build_ms;
	size_t bvh_bytes; /* its nodes and references in the scene block */

	/* With record_schedule: RT_SCHEDULE_WORDS per pixel, row-major. */
	uint32_t *schedule;

	/* With check_writes. */
	uint32_t *write_counts; /* per pixel */
	int guards_intact;	/* no byte outside the image was written */

	/* The stages form's launches and queues (--wavefront-form stages), over
	 * every frame; NULL otherwise. */
	struct stages_stats *stages;

	/* One image over several devices in this process: the last frame's
	 * pieces, in the order they were handed out. */
	struct piece_record *pieces;
	int piece_count;
};

/* Samples per pixel, 0 counting as 1. */
static inline int settings_samples(const struct render_settings *s)
{
	return s->samples > 0 ? s->samples : 1;
}

/* Whether s asks for an instrumented render (counting flops, recording the
 * schedule): one untimed frame, no warm-up. */
static inline int settings_instrumented(const struct render_settings *s)
{
	return s->count_flops || s->record_schedule;
}

/* Bytes of the linear RGB float image of width × height pixels. */
static inline size_t image_float_bytes(int width, int height)
{
	return (size_t)width * (size_t)height * 3 * sizeof(float);
}

/* Bytes of the fixed-point sums of width × height pixels (4 cl_long each:
 * the three channels' sums and their saturation bits; docs/RENDERING.md,
 * "Samples per pixel"). */
static inline size_t image_sum_bytes(int width, int height)
{
	return (size_t)width * (size_t)height * 4 * sizeof(cl_long);
}

/* What a pixel's sum of `samples` samples is multiplied by for its mean:
 * 1 / (samples * RT_SUM_ONE) rounded to float (rt_piece.mean_scale). */
static inline float settings_mean_scale(int samples)
{
	return (float)(1.0 / ((double)samples * (double)RT_SUM_ONE));
}

#endif
