/* What every renderer does around its kernels: the NDRange plan and its
 * checks against the device and the kernels, the setup every renderer does
 * first (the plan, the scene block, the program), and launches with their
 * profiled time. */
#ifndef RTCL_LAUNCH_H
#define RTCL_LAUNCH_H

#include "render/settings.h"
#include "render/watch.h"

/* Bytes of a buffer or __local argument that a kernel takes but does not
 * use in this build (OpenCL wants a non-empty one). */
#define UNUSED_BUFFER_BYTES 16

/* The most work-items one launch may have: the kernels index them with
 * 32-bit uints (launch.c says where). */
#define LAUNCH_MAX_WORK_ITEMS (1ull << 31)

/* The groups used when --groups is not given: enough work-groups of the given
 * size to fill the device, shaped to cover the image's chunks. */
void launch_default_groups(const struct device *dev, const struct render_settings *settings,
			   int groups[2]);

/* Checks the work-group size against the device's limits. */
int launch_check_workgroup(const struct device *dev, const struct render_settings *settings,
			   char *err, size_t err_size);

/* Chooses the 2D NDRange of a single-pass kernel (result->local_size,
 * global_size and groups) and checks it against the device and against what
 * the kernels can index (LAUNCH_MAX_WORK_ITEMS, the persistent kernel's
 * pixel counter). */
int launch_plan(const struct device *dev, const struct render_settings *settings,
		struct render_result *result, char *err, size_t err_size);

/* Checks the kernel's own work-group limit, known only once it is built. */
int launch_check_kernel(const struct device *dev, cl_kernel kernel,
			const struct render_result *result, const char *name, char *err,
			size_t err_size);

/* What every renderer does first: launch_plan, the image checked against the
 * device, block_prepare_scene, and the program built. Returns 0, or -1 with
 * one message in err; the caller frees *scene_block and releases *program. */
int launch_setup(struct device *dev, const struct scene *scene,
		 const struct render_settings *settings, struct render_result *result,
		 void **scene_block, cl_program *program, char *err, size_t err_size);

/* One launch's profiled interval on the device's clock, in nanoseconds. */
struct launch_span {
	cl_ulong start, end;
};

/* Reads a finished launch's profiled interval (its queue profiles). */
cl_int launch_event_span(cl_event event, struct launch_span *span);

/* Enqueues one launch, waits for it (drawing the progress line, with the
 * share that watch reads when not NULL) and adds its profiled time to *ms.
 * On failure *call names what failed. */
cl_int launch_run(struct device *dev, cl_kernel kernel, cl_uint dims, const size_t *global,
		  const size_t *local, const struct launch_watch *watch, double *ms,
		  const char **call);


/* The time in ms during which at least one of the launches ran: the union of
 * their intervals, which may overlap (launches on several queues of one
 * device). Sorts spans. */
double launch_busy_ms(struct launch_span *spans, int count);

#endif
