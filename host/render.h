/* Rendering a scene on an OpenCL device with one of the scheduling kernels of
 * cl/: program build, buffers, launches and their timing. */
#ifndef RTCL_RENDER_H
#define RTCL_RENDER_H

#include <stddef.h>
#include <stdint.h>

#include "device.h"
#include "scene.h"

/* The scheduling kernels, one cl/NAME.cl each. */
struct kernel_info {
	const char *name;
	const char *summary;
	int uses_groups; /* persistent work-groups: --groups applies */
	int single_item; /* one work-item renders everything: -w does not apply */
	int multi_pass;	 /* several launches per frame (wavefront) */
};

extern const struct kernel_info render_kernels[];
extern const int render_kernel_count;

/* Returns the kernel named `name`, or NULL. */
const struct kernel_info *render_find_kernel(const char *name);

struct render_settings {
	const struct kernel_info *kernel;
	int workgroup[2];  /* local size, e.g. 8x8 */
	int groups[2];	   /* persistent work-groups; 0x0: enough to fill the device */
	int width, height; /* image size */
	int max_depth;
	int repeat;		/* timed launches after one warm-up launch */
	int batch;		/* pixels per fetch of the persistent kernel (0: 1) */
	int count_flops;	/* build with RTCL_COUNT_FLOPS and return the counts */
	int check_writes;	/* tests: count writes per pixel, poison the image and
				   surround it with guard zones */
	int force_global_scene; /* read the scene from __global memory even if it
				   would fit in __local memory */
	const char *source_dir; /* load cl/ sources from here instead of the
				   embedded copies (development) */
	int progress;		/* show progress on stderr */
	int verbose;
};

struct render_result {
	float *rgb; /* width*height*3 linear floats, row 0 at the top */
	double kernel_ms_median, kernel_ms_min, kernel_ms_max;
	double *kernel_ms; /* each timed launch, in order */
	int repeat;
	int groups[2]; /* as launched (1x1 for serial; the NDRange's for naive) */
	size_t global_size[2], local_size[2];
	int scene_in_local;
	size_t scene_bytes;
	char build_options[512];

	/* With count_flops: per launched work-item, row-major over the global
	 * NDRange. */
	uint64_t *item_flops;
	size_t item_count;
	uint64_t *pixel_flops; /* per pixel, row-major */
	uint64_t total_flops, total_rays;

	/* With check_writes. */
	uint32_t *write_counts; /* per pixel */
	int guards_intact;	/* no byte outside the image was written */
};

/* Renders `scene` with `settings` on `dev`. Returns 0, or -1 with one message
 * in err (a failed build puts the build log and the options there). */
int render(struct device *dev, const struct scene *scene, const struct render_settings *settings,
	   struct render_result *result, char *err, size_t err_size);

void render_result_free(struct render_result *result);

/* Sets the median, min and max of result->kernel_ms[0 .. repeat). Returns 0,
 * or -1 with a message when out of memory. */
int render_summarize_times(struct render_result *result, char *err, size_t err_size);

/* The groups used when --groups is not given: enough work-groups of the given
 * size to fill the device, shaped to cover the image's chunks. */
void render_default_groups(const struct device *dev, const struct render_settings *settings,
			   int groups[2]);

#endif
