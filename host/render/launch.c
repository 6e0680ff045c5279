#include "render/launch.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "layout/scene_block.h"
#include "render/program.h"
#include "base/progress.h"
#include "base/quote.h"
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
 * wrapping to 0 (which would hand out pixels again). */
static int check_pixel_counter(const struct render_settings *s, const struct render_result *res,
			       char *err, size_t err_size)
{
	uint64_t chunk_w = res->local_size[0], chunk_h = res->local_size[1];
	uint64_t chunks =
		((s->width + chunk_w - 1) / chunk_w) * ((s->height + chunk_h - 1) / chunk_h);
	uint64_t items = (uint64_t)res->global_size[0] * res->global_size[1];
	uint64_t batch = s->batch > 0 ? (uint64_t)s->batch : 1;
	uint64_t end = chunks * chunk_w * chunk_h + (items + 1) * batch;

	if (!s->kernel->pixel_counter || end <= UINT32_MAX)
		return 0;
	snprintf(err, err_size,
		 "%s %dx%d with --batch %llu: the persistent kernel's 32-bit pixel counter "
		 "would count to %llu (the pixels, then one fetch of %llu by each of %llu "
		 "work-items), more than %lu; choose fewer groups or a smaller --batch",
		 s->kernel->uses_groups && s->groups[0] > 0 ? "--groups" : "work-groups",
		 res->groups[0], res->groups[1], (unsigned long long)batch, (unsigned long long)end,
		 (unsigned long long)batch, (unsigned long long)items, (unsigned long)UINT32_MAX);
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

int launch_check_scene_fits(const struct device *dev, const struct scene *scene,
			    const struct mesh_block *mesh, const struct bvh *bvh, char *err,
			    size_t err_size)
{
	size_t bytes = scene_block_bytes(scene, mesh, bvh);
	/* One buffer holds the whole block, whose offsets are 32-bit. */
	unsigned long long limit = dev->max_alloc_size < DEVSCENE_MAX_BYTES
					   ? (unsigned long long)dev->max_alloc_size
					   : (unsigned long long)DEVSCENE_MAX_BYTES;

	if (bytes <= limit)
		return 0;
	snprintf(err, err_size,
		 "%s: the scene (%d triangles) needs %zu bytes of device "
		 "memory, more than the limit of %llu bytes in one buffer on %s (%s)",
		 quote_text(scene->source), scene->triangle_count, bytes, limit, dev->name,
		 limit == dev->max_alloc_size ? "CL_DEVICE_MAX_MEM_ALLOC_SIZE"
					      : "rtcl's 32-bit scene offsets");
	return -1;
}

/* Builds the BVH of the scene's spheres and triangles into *bvh, with its
 * figures in res. */
static int launch_build_bvh(const struct scene *scene, struct render_result *res, struct bvh *bvh,
			    char *err, size_t err_size)
{
	double lap = timing_now();

	if (bvh_build_scene(scene, bvh)) {
		snprintf(err, err_size,
			 "out of host memory for the BVH of %d spheres and %d triangles",
			 scene->sphere_count, scene->triangle_count);
		return -1;
	}
	res->bvh_build_ms = timing_lap_ms(&lap);
	res->bvh_nodes = bvh->node_count;
	res->bvh_depth = bvh->depth;
	res->bvh_sah_cost = bvh->sah_cost;
	res->bvh_bytes = (size_t)bvh->node_count * sizeof(*bvh->nodes) +
			 (size_t)bvh->ref_count * sizeof(*bvh->refs);
	return 0;
}

/* Device bytes per triangle (issue 11's budget: 64): the whole scene block
 * over the triangles, and the shares of the triangles, their vertices and the
 * BVH. */
static void launch_print_triangle_bytes(const struct scene *scene, const struct render_result *res)
{
	double n = scene->triangle_count;
	size_t vertex_bytes = sizeof(struct rt_vertex) + sizeof(struct rt_vertex_normal);

	fprintf(stderr,
		"rtcl: device scene block %zu bytes for %d triangles: %.1f bytes per triangle "
		"(%zu triangle, %.1f vertices (%d), %.1f BVH)\n",
		res->scene_bytes, scene->triangle_count, res->scene_bytes / n,
		sizeof(struct rt_triangle), res->vertex_count * vertex_bytes / n, res->vertex_count,
		res->bvh_bytes / n);
}

/* The scene's triangles indexed (the mesh block) and its BVH (with use_bvh), checked
 * to fit on dev and packed into *block. */
static int launch_pack_scene(struct device *dev, const struct scene *scene,
			     const struct render_settings *s, int use_bvh,
			     struct render_result *res, void **block, char *err, size_t err_size)
{
	struct bvh bvh = {0};
	struct mesh_block mesh;
	int ret = -1;

	if (mesh_block_build(scene, &mesh)) {
		snprintf(err, err_size, "out of host memory for the %d triangles' vertices",
			 scene->triangle_count);
		return -1;
	}
	res->vertex_count = mesh.vertex_count;
	if (use_bvh && launch_build_bvh(scene, res, &bvh, err, err_size))
		goto free_mesh;
	if (launch_check_scene_fits(dev, scene, &mesh, use_bvh ? &bvh : NULL, err, err_size))
		goto free_bvh;
	*block = scene_block_pack(scene, &mesh, use_bvh ? &bvh : NULL, s->width, s->height,
			       s->max_depth, &res->scene_bytes);
	if (!*block)
		snprintf(err, err_size, "out of host memory for the scene's %zu bytes",
			 scene_block_bytes(scene, &mesh, use_bvh ? &bvh : NULL));
	else
		ret = 0;
free_bvh:
	bvh_free(&bvh);
free_mesh:
	mesh_block_free(&mesh);
	return ret;
}

int launch_prepare_scene(struct device *dev, const struct scene *scene,
			 const struct render_settings *s, struct render_result *res, void **block,
			 char *err, size_t err_size)
{
	int use_bvh =
		s->accel == ACCEL_BVH && (scene->sphere_count > 0 || scene->triangle_count > 0);

	*block = NULL;
	if (scene_block_check_resolution(scene, err, err_size) ||
	    launch_pack_scene(dev, scene, s, use_bvh, res, block, err, err_size))
		return -1;
	res->rgb = malloc(image_float_bytes(s->width, s->height));
	if (!res->rgb) {
		snprintf(err, err_size, "out of host memory for a %dx%d image", s->width,
			 s->height);
		return -1;
	}
	/* A third at most: every work-group holds its own copy, and a larger
	 * one leaves too few groups per compute unit. On the H100 (48 KiB) a
	 * 41 KiB block in __local memory ran 1.5 times slower than from
	 * __global (400 balls with their BVH), a 9 KiB one 6 % faster
	 * (docs/bvh.md). */
	res->scene_in_local =
		!s->force_global_scene &&
		(res->scene_bytes + LOCAL_MEM_RESERVE) * LOCAL_MEM_SHARE <= dev->local_mem_size;
	if (s->verbose && (scene->triangle_count || scene->skipped_triangles))
		fprintf(stderr,
			"rtcl: %d triangles; %ld of area 0 (after placement) skipped from mesh "
			"files\n",
			scene->triangle_count, scene->skipped_triangles);
	if (s->verbose && use_bvh)
		fprintf(stderr,
			"rtcl: BVH of %d sphere%s and %d triangle%s: %d nodes, depth %d, SAH cost "
			"%.2f, built in %.3f ms\n",
			scene->sphere_count, scene->sphere_count == 1 ? "" : "s",
			scene->triangle_count, scene->triangle_count == 1 ? "" : "s",
			res->bvh_nodes, res->bvh_depth, res->bvh_sah_cost, res->bvh_build_ms);
	if (s->verbose && scene->triangle_count)
		launch_print_triangle_bytes(scene, res);
	if (s->verbose)
		fprintf(stderr, "rtcl: scene is %zu bytes; %s\n", res->scene_bytes,
			res->scene_in_local
				? "copied into __local memory by each work-group"
				: "read from __global memory (it would take more than a third of "
				  "__local memory)");
	return 0;
}

int launch_begin_timing(const struct render_settings *s, struct render_result *res, char *err,
			size_t err_size)
{
	/* Instrumented runs are not timed: one run is enough. */
	int timed = settings_instrumented(s) ? 1 : s->repeat;
	int warm_up = !settings_instrumented(s) && s->warm_up;

	res->kernel_ms = calloc((size_t)timed, sizeof(double));
	if (!res->kernel_ms) {
		snprintf(err, err_size, "out of host memory");
		return -1;
	}
	res->repeat = timed;
	res->launches = timed + warm_up;
	return res->launches;
}

void launch_record_frame(struct render_result *res, int frame, int frames, double ms)
{
	int slot = frame - (frames - res->repeat);

	if (slot >= 0)
		res->kernel_ms[slot] = ms;
}

int launch_end_timing(struct render_result *res, char *err, size_t err_size)
{
	return timing_summarize(res->kernel_ms, res->repeat, &res->kernel_ms_median,
				&res->kernel_ms_min, &res->kernel_ms_max, err, err_size);
}

void launch_progress_begin(const struct render_settings *s, int frames, const char *devices)
{
	char what[64];

	snprintf(what, sizeof(what), "%s (%s%s%s)",
		 s->count_flops		? "counting flops"
		 : s->record_schedule ? "recording the schedule"
				      : "rendering",
		 s->kernel->name, devices ? ", " : "", devices ? devices : "");
	progress_begin(what, frames * launch_image_work(s));
}

void launch_progress_frame(const struct render_settings *s, const struct render_result *res,
			   int frame, int frames)
{
	char step[48];
	int timed = frame - (frames - res->repeat); /* -1: the warm-up */

	if (frames == 1)
		return;
	if (timed < 0)
		snprintf(step, sizeof(step), "warm-up launch");
	else
		snprintf(step, sizeof(step), "timed launch %d of %d", timed + 1, res->repeat);
	progress_step(step, launch_image_work(s));
}

double launch_image_work(const struct render_settings *s)
{
	return (double)s->width * s->height * settings_samples(s);
}

int launch_create_counter(struct device *dev, int watched, struct work_counter *c, char *err,
			  size_t err_size)
{
	size_t bytes = RT_COUNTER_WORDS * sizeof(cl_uint);
	int in_place = watched && dev->host_unified;
	cl_int status = CL_SUCCESS;

	memset(c, 0, sizeof(*c));
	c->queue = dev->queue;
	c->watched = watched;
	c->buffer = device_create_buffer(dev,
					 CL_MEM_READ_WRITE | (in_place ? CL_MEM_ALLOC_HOST_PTR : 0),
					 bytes, NULL, "work counter", err, err_size);
	if (!c->buffer)
		return -1;
	if (in_place)
		c->mapped = clEnqueueMapBuffer(dev->queue, c->buffer, CL_TRUE, CL_MAP_READ, 0,
					       bytes, 0, NULL, NULL, &status);
	else if (watched)
		c->side_queue = clCreateCommandQueue(dev->context, dev->id, 0, &status);
	if (status == CL_SUCCESS)
		return 0;
	snprintf(err, err_size, "%s failed for the work counter on %s: %s",
		 in_place ? "clEnqueueMapBuffer" : "clCreateCommandQueue", dev->name,
		 cl_error_name(status));
	return -1;
}

/* Waits for the read in flight, if any. */
static void finish_reading(struct work_counter *c)
{
	if (!c->reading)
		return;
	clWaitForEvents(1, &c->reading);
	clReleaseEvent(c->reading);
	c->reading = NULL;
}

cl_int launch_reset_counter(struct work_counter *c)
{
	cl_uint zero = 0;

	finish_reading(c);
	if (c->reset)
		clReleaseEvent(c->reset);
	c->reset = NULL;
	memset(c->copy, 0, sizeof(c->copy));
	return clEnqueueFillBuffer(c->queue, c->buffer, &zero, sizeof(zero), 0, sizeof(c->copy), 0,
				   NULL, c->watched ? &c->reset : NULL);
}

void launch_release_counter(struct work_counter *c)
{
	finish_reading(c);
	if (c->reset)
		clReleaseEvent(c->reset);
	if (c->mapped) {
		clEnqueueUnmapMemObject(c->queue, c->buffer, c->mapped, 0, NULL, NULL);
		clFinish(c->queue);
	}
	if (c->side_queue)
		clReleaseCommandQueue(c->side_queue);
	if (c->buffer)
		clReleaseMemObject(c->buffer);
	memset(c, 0, sizeof(*c));
}

/* The counter's word as last seen: in place, or from the last finished
 * read, starting the next. */
static cl_uint read_counter(struct work_counter *c, int word)
{
	cl_int state = CL_QUEUED;

	if (c->mapped) {
		/* Before the zeroing has run the words are the last launch's. */
		if (clGetEventInfo(c->reset, CL_EVENT_COMMAND_EXECUTION_STATUS, sizeof(state),
				   &state, NULL) != CL_SUCCESS ||
		    state != CL_COMPLETE)
			return 0;
		return __atomic_load_n(&c->mapped[word], __ATOMIC_RELAXED);
	}
	if (c->reading &&
	    clGetEventInfo(c->reading, CL_EVENT_COMMAND_EXECUTION_STATUS, sizeof(state), &state,
			   NULL) == CL_SUCCESS &&
	    state <= CL_COMPLETE) {
		clReleaseEvent(c->reading); /* done, or failed: a later read tries again */
		c->reading = NULL;
	}
	if (!c->reading &&
	    clEnqueueReadBuffer(c->side_queue, c->buffer, CL_FALSE, 0, sizeof(c->copy), c->copy,
				c->reset ? 1 : 0, c->reset ? &c->reset : NULL,
				&c->reading) == CL_SUCCESS)
		clFlush(c->side_queue);
	return c->copy[word];
}

/* Shows how far the launch is: its share of the work from the counter. */
static void show_share(const struct launch_watch *w)
{
	if (!w || !w->counter || !w->counter->watched)
		return;
	double count = read_counter(w->counter, w->word) * w->pixels_per_count;
	double share = count < w->pixels ? count / w->pixels : 1;
	progress_partial(w->slot, share * w->work);
}

/* The launches being waited for while the progress line is shown, one per
 * device at most, and the ticker thread that reads their counters and
 * redraws the line every PROGRESS_TICK_MS. The thread that waits for a
 * launch blocks in clWaitForEvents and so returns the moment the launch
 * ends: waiting in ticks, or for an event callback, added 17 ms to every
 * pass on the H100 (docs/results/h100-batch6, run 24). The ticker draws
 * only while some launch is waited for, and touches a watch's counter only
 * while it is in the list, under watch_lock. */
static pthread_mutex_t watch_lock = PTHREAD_MUTEX_INITIALIZER;
static const struct launch_watch *watched_launches[PROGRESS_SLOTS];
static int launches_waited_for;

static void *ticker(void *unused)
{
	struct timespec tick = {0, PROGRESS_TICK_MS * 1000000L};

	(void)unused;
	for (;;) {
		nanosleep(&tick, NULL);
		pthread_mutex_lock(&watch_lock);
		for (int i = 0; i < PROGRESS_SLOTS; i++)
			show_share(watched_launches[i]);
		if (launches_waited_for > 0)
			progress_draw();
		pthread_mutex_unlock(&watch_lock);
	}
	return NULL;
}

static void start_ticker(void)
{
	pthread_t thread;

	/* Without the thread the line still moves from launch to launch. */
	if (pthread_create(&thread, NULL, ticker, NULL) == 0)
		pthread_detach(thread);
}

/* Waits for the launch; with the progress line on, the ticker reads the
 * watch's counter meanwhile. */
static cl_int wait_for(cl_event event, const struct launch_watch *watch)
{
	static pthread_once_t ticker_once = PTHREAD_ONCE_INIT;
	int index = -1;

	if (!progress_enabled())
		return clWaitForEvents(1, &event);
	pthread_once(&ticker_once, start_ticker);
	pthread_mutex_lock(&watch_lock);
	launches_waited_for++;
	for (int i = 0; watch && watch->counter && i < PROGRESS_SLOTS && index < 0; i++)
		if (!watched_launches[i]) {
			watched_launches[i] = watch;
			index = i;
		}
	pthread_mutex_unlock(&watch_lock);

	cl_int status = clWaitForEvents(1, &event);

	pthread_mutex_lock(&watch_lock);
	launches_waited_for--;
	if (index >= 0) {
		watched_launches[index] = NULL;
		finish_reading(watch->counter);
	}
	pthread_mutex_unlock(&watch_lock);
	return status;
}

cl_int launch_run(struct device *dev, cl_kernel kernel, cl_uint dims, const size_t *global,
		  const size_t *local, const struct launch_watch *watch, double *ms,
		  const char **call)
{
	cl_event event;
	cl_ulong start = 0, end = 0;
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
		status = wait_for(event, watch);
	}
	if (status == CL_SUCCESS) {
		*call = "clGetEventProfilingInfo";
		status = clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_START, sizeof(start),
						 &start, NULL);
	}
	if (status == CL_SUCCESS)
		status = clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_END, sizeof(end), &end,
						 NULL);
	*ms += (double)(end - start) * 1e-6;
	clReleaseEvent(event);
	return status;
}

int launch_setup(struct device *dev, const struct scene *scene, const struct render_settings *s,
		 struct render_result *res, void **scene_block, cl_program *program, char *err,
		 size_t err_size)
{
	double lap = timing_now();

	if (launch_plan(dev, s, res, err, err_size) ||
	    device_check_fits(dev, "the image", (double)image_float_bytes(s->width, s->height), err,
			      err_size) ||
	    launch_prepare_scene(dev, scene, s, res, scene_block, err, err_size))
		return -1;
	res->times.scene = timing_lap_ms(&lap);
	struct program_features features = {res->scene_in_local, res->bvh_nodes > 0,
					    scene->triangle_count > 0};
	if (program_build(dev, s, &features, program, res->build_options, &res->build_cached, err,
			  err_size))
		return -1;
	res->times.build = timing_lap_ms(&lap);
	return 0;
}
