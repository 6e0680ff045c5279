#include "render/launch.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "render/block.h"
#include "render/program.h"
#include "base/timing.h"

void launch_default_groups(const struct device *dev, const struct render_settings *s, int groups[2])
{
	int items = s->workgroup[0] * s->workgroup[1];
	int chunks_x = (s->width + s->workgroup[0] - 1) / s->workgroup[0];
	int chunks_y = (s->height + s->workgroup[1] - 1) / s->workgroup[1];
	/* A GPU runs many work-groups per compute unit at once (up to 2048
	 * work-items on current NVIDIA parts); a CPU runs one per core. */
	long total = dev->is_gpu ? (long)dev->compute_units * (items >= 1024 ? 1 : 1024 / items)
				 : (long)dev->compute_units * 4;
	int gx = (int)ceil(sqrt((double)total));

	if (total < 1)
		total = 1;
	if (gx > chunks_x)
		gx = chunks_x;
	int gy = (int)((total + gx - 1) / gx);
	if (gy > chunks_y)
		gy = chunks_y;
	groups[0] = gx;
	groups[1] = gy;
}

int launch_check_workgroup(const struct device *dev, const struct render_settings *s, char *err,
			   size_t err_size)
{
	const size_t *max_items = dev->max_work_item_sizes;
	size_t wx = (size_t)s->workgroup[0], wy = (size_t)s->workgroup[1];

	if (wx > max_items[0] || wy > max_items[1] || wx * wy > dev->max_work_group_size) {
		snprintf(err, err_size,
			 "work-group %zux%zu (%zu work-items) is larger than %s allows: at most "
			 "%zu work-items, %zux%zu in x and y (choose a smaller -w)",
			 wx, wy, wx * wy, dev->name, dev->max_work_group_size, max_items[0],
			 max_items[1]);
		return -1;
	}
	return 0;
}

/* Checks the NDRange against what the kernels can index. Every work-item's
 * row-major index is a uint in cl/tracer.cl (store_counts() writes at
 * 2 * index, also a uint), so a launch may have at most 2^31 work-items; that
 * also keeps the work-group count below PoCL 3.1's 32-bit count of groups
 * (2^32 groups crash its pthread driver with SIGFPE) and every global size
 * within a 32-bit device size_t (CL_DEVICE_ADDRESS_BITS), so no device query
 * is needed. */
static int check_work_items(const struct render_settings *s, const struct render_result *res,
			    char *err, size_t err_size)
{
	uint64_t groups = (uint64_t)res->groups[0] * (uint64_t)res->groups[1];
	uint64_t group_items = (uint64_t)res->local_size[0] * res->local_size[1];

	if (groups * group_items <= LAUNCH_MAX_WORK_ITEMS)
		return 0;
	snprintf(err, err_size,
		 "%s %dx%d: %llu work-groups of %llu work-item%s is more than the kernels can "
		 "index (at most %llu work-items in all); choose fewer groups",
		 s->kernel->uses_groups && s->groups[0] > 0 ? "--groups" : "work-groups",
		 res->groups[0], res->groups[1], (unsigned long long)groups,
		 (unsigned long long)group_items, group_items == 1 ? "" : "s",
		 (unsigned long long)LAUNCH_MAX_WORK_ITEMS);
	return -1;
}

/* Checks the persistent kernel's uint pixel counter (cl/persistent.cl): it
 * hands out every pixel of the whole chunks, then each work-item's last fetch
 * of --batch pixels overshoots, so the counter must count that far without
 * wrapping to 0 (which would hand out pixels again). With --fetch group each
 * work-group's last block (a fetch per work-item) overshoots too. */
static int check_pixel_counter(const struct render_settings *s, const struct render_result *res,
			       char *err, size_t err_size)
{
	uint64_t chunk_w = res->local_size[0], chunk_h = res->local_size[1];
	uint64_t chunks =
		((s->width + chunk_w - 1) / chunk_w) * ((s->height + chunk_h - 1) / chunk_h);
	uint64_t items = (uint64_t)res->global_size[0] * res->global_size[1];
	uint64_t batch = s->batch > 0 ? (uint64_t)s->batch : 1;
	uint64_t fetches = s->fetch == FETCH_GROUP ? 2 * items + 1 : items + 1;
	uint64_t end = chunks * chunk_w * chunk_h + fetches * batch;

	if (!s->kernel->pixel_counter || end <= UINT32_MAX)
		return 0;
	snprintf(err, err_size,
		 "%s %dx%d with --batch %llu: the persistent kernel's 32-bit pixel counter "
		 "would count to %llu (the pixels, then %s of %llu by each of %llu "
		 "work-items), more than %lu; choose fewer groups or a smaller --batch",
		 s->kernel->uses_groups && s->groups[0] > 0 ? "--groups" : "work-groups",
		 res->groups[0], res->groups[1], (unsigned long long)batch, (unsigned long long)end,
		 s->fetch == FETCH_GROUP ? "two fetches" : "one fetch", (unsigned long long)batch,
		 (unsigned long long)items, (unsigned long)UINT32_MAX);
	return -1;
}

int launch_plan(const struct device *dev, const struct render_settings *s,
		struct render_result *res, char *err, size_t err_size)
{
	size_t wx = (size_t)s->workgroup[0], wy = (size_t)s->workgroup[1];

	if (s->kernel->single_item) {
		res->local_size[0] = res->local_size[1] = 1;
		res->global_size[0] = res->global_size[1] = 1;
		res->groups[0] = res->groups[1] = 1;
		return 0;
	}
	if (launch_check_workgroup(dev, s, err, err_size))
		return -1;
	res->local_size[0] = wx;
	res->local_size[1] = wy;
	if (s->kernel->uses_groups) {
		if (s->groups[0] > 0 && s->groups[1] > 0) {
			res->groups[0] = s->groups[0];
			res->groups[1] = s->groups[1];
		} else {
			launch_default_groups(dev, s, res->groups);
		}
	} else {
		res->groups[0] = (int)((s->width + wx - 1) / wx);
		res->groups[1] = (int)((s->height + wy - 1) / wy);
	}
	if (check_work_items(s, res, err, err_size))
		return -1;
	res->global_size[0] = (size_t)res->groups[0] * wx;
	res->global_size[1] = (size_t)res->groups[1] * wy;
	return check_pixel_counter(s, res, err, err_size);
}

int launch_check_kernel(const struct device *dev, cl_kernel kernel, const struct render_result *res,
			const char *name, char *err, size_t err_size)
{
	size_t max_items = 0;
	cl_int status = clGetKernelWorkGroupInfo(kernel, dev->id, CL_KERNEL_WORK_GROUP_SIZE,
						 sizeof(max_items), &max_items, NULL);

	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clGetKernelWorkGroupInfo failed: %s",
			 cl_error_name(status));
		return -1;
	}
	size_t items = res->local_size[0] * res->local_size[1];
	if (items > max_items) {
		snprintf(err, err_size,
			 "work-group %zux%zu (%zu work-items) is larger than kernel '%s' allows on "
			 "%s: at most %zu work-items (choose a smaller -w)",
			 res->local_size[0], res->local_size[1], items, name, dev->name, max_items);
		return -1;
	}
	return 0;
}

cl_int launch_run(struct device *dev, cl_kernel kernel, cl_uint dims, const size_t *global,
		  const size_t *local, const struct launch_watch *watch, double *ms,
		  const char **call)
{
	cl_event event;
	cl_int status;

	*call = "clEnqueueNDRangeKernel";
	status = clEnqueueNDRangeKernel(dev->queue, kernel, dims, NULL, global, local, 0, NULL,
					&event);
	if (status != CL_SUCCESS)
		return status;
	*call = "clFlush";
	status = clFlush(dev->queue);
	if (status == CL_SUCCESS) {
		*call = "waiting for the kernel";
		status = watch_wait(event, watch);
	}
	struct launch_span span = {0, 0};
	if (status == CL_SUCCESS) {
		*call = "clGetEventProfilingInfo";
		status = launch_event_span(event, &span);
	}
	*ms += (double)(span.end - span.start) * 1e-6;
	clReleaseEvent(event);
	return status;
}

cl_int launch_event_span(cl_event event, struct launch_span *span)
{
	cl_int status = clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_START,
						sizeof(span->start), &span->start, NULL);

	if (status == CL_SUCCESS)
		status = clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_END, sizeof(span->end),
						 &span->end, NULL);
	return status;
}

static int by_start(const void *a, const void *b)
{
	const struct launch_span *x = a, *y = b;

	return x->start < y->start ? -1 : x->start > y->start;
}

double launch_busy_ms(struct launch_span *spans, int count)
{
	cl_ulong busy = 0, covered = 0; /* covered: the end of the union so far */

	qsort(spans, (size_t)count, sizeof(*spans), by_start);
	for (int i = 0; i < count; i++) {
		cl_ulong start = spans[i].start > covered ? spans[i].start : covered;
		if (spans[i].end > start)
			busy += spans[i].end - start;
		if (spans[i].end > covered)
			covered = spans[i].end;
	}
	return (double)busy * 1e-6;
}

int launch_setup(struct device *dev, const struct scene *scene, const struct render_settings *s,
		 struct render_result *res, void **scene_block, cl_program *program, char *err,
		 size_t err_size)
{
	double lap = timing_now();

	if (launch_plan(dev, s, res, err, err_size) ||
	    device_check_fits(dev, "the image", (double)image_float_bytes(s->width, s->height), err,
			      err_size) ||
	    (settings_samples(s) > 1 &&
	     device_check_fits(dev, "the sample sums buffer (32 bytes a pixel)",
			       (double)image_sum_bytes(s->width, s->height), err, err_size)) ||
	    block_prepare_scene(dev, scene, s, res, scene_block, err, err_size))
		return -1;
	res->times.scene = timing_lap_ms(&lap);
	int path = scene->integrator == SCENE_INTEGRATOR_PATH;
	struct program_features features = {res->scene_in_local, res->bvh_nodes > 0,
					    scene->triangle_count > 0,
					    res->bvh_nodes > 0 && scene->sphere_count == 0 &&
						    s->accel == ACCEL_BVH,
					    scene->camera.aperture > 0,
					    /* Whitted's own switches; the path integrator
					       samples every light and has its own BSDFs */
					    !path && scene_has_area_lights(scene),
					    !path && scene_has_fresnel(scene->materials,
								       scene->material_count),
					    scene_has_textures(scene),
					    scene->light_count == 0 && !path,
					    res->bvh_width == 4, path};
	if (program_build(dev, s, &features, program, res->build_options, &res->build_cached, err,
			  err_size))
		return -1;
	res->times.build = timing_lap_ms(&lap);
	res->fetch_lanes = s->fetch == FETCH_GROUP ? s->workgroup[0] * s->workgroup[1]
			   : s->fetch == FETCH_SUBGROUP && dev->simd_measurable ? 32
										: 1;
	return 0;
}
