/* The single-pass renderer: serial, naive, cyclic, dynamic and persistent
 * (cl/NAME.cl) each trace a piece of the image (renderer.h) in one launch of
 * their `render` kernel. */
#include "render/singlepass.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rtcl_shared.h"
#include "render/aov.h"
#include "render/buffers.h"
#include "base/test_hooks.h"
#include "render/launch.h"
#include "render/watch.h"
#include "render/program.h"
#include "base/progress.h"
#include "base/timing.h"

/* The arguments of every single-pass kernel, in order. */
enum render_arg {
	ARG_SCENE,
	ARG_SCENE_LOCAL,
	ARG_IMAGE,
	ARG_SUMS,
	ARG_WORK_COUNTER,
	ARG_COUNTS,
	ARG_PROBE,
	ARG_PIECE,
	RENDER_ARGS
};

/* A further in-order queue of the device with its own kernel object and
 * work counter (renderer.h, renderer_all_samples); lane 0 is the device's queue,
 * st->kernel and st->work_counter. */
struct lane {
	cl_command_queue queue;
	cl_kernel kernel;
	struct work_counter work_counter;
};

/* Everything one render holds on the device, released in reverse order. */
struct launch_state {
	/* b.flops: flops per pixel, then RT_ITEM_COUNTS per work-item;
	 * b.item_flops: per work-item of the plan, added over the launches. */
	struct render_buffers b;
	cl_kernel kernel;
	struct work_counter work_counter; /* cl/rtcl_shared.h, RT_COUNTER_* */
	struct lane lanes[RENDER_MAX_QUEUES]; /* [1, r->queues) */
};

static void release_state(struct launch_state *st)
{
	for (int i = RENDER_MAX_QUEUES - 1; i > 0; i--) {
		struct lane *l = &st->lanes[i];
		watch_release_counter(&l->work_counter);
		if (l->kernel)
			clReleaseKernel(l->kernel);
		if (l->queue)
			clReleaseCommandQueue(l->queue);
	}
	watch_release_counter(&st->work_counter);
	if (st->kernel)
		clReleaseKernel(st->kernel);
	buffers_release(&st->b);
}

/* Bytes of the counts buffer: one per pixel (flops), then RT_ITEM_COUNTS per
 * work-item of the largest launch, the whole image's (flops, rays, node
 * visits). */
static double counts_bytes(const struct render_settings *s, const struct render_result *res)
{
	double items = (double)res->global_size[0] * res->global_size[1];

	return (items * RT_ITEM_COUNTS + (double)s->width * s->height) * sizeof(cl_ulong);
}

/* Bytes of the per-pixel flops at the head of the counts buffer. */
static size_t pixel_counts_bytes(const struct render_settings *s)
{
	return (size_t)s->width * s->height * sizeof(cl_ulong);
}

/* Bytes of the kernels' __local argument: the scene when it lives there,
 * rounded up to whole uint4. */
static size_t local_argument_bytes(const struct render_result *res)
{
	size_t bytes = res->scene_in_local ? (res->scene_bytes + 15) / 16 * 16 : 0;

	return bytes > UNUSED_BUFFER_BYTES ? bytes : UNUSED_BUFFER_BYTES;
}

/* Bytes after the work counter's words: with --fetch group the persistent
 * kernel's block, a 64-bit word per work-group (cl/persistent.cl,
 * group_block; RT_COUNTER_WORDS is even, so the words are aligned). */
static size_t counter_group_bytes(const struct render_settings *s, const struct render_result *res)
{
	if (s->fetch != FETCH_GROUP)
		return 0;
	size_t groups = (res->global_size[0] / res->local_size[0]) *
			(res->global_size[1] / res->local_size[1]);
	return groups * sizeof(cl_ulong);
}

/* Sets every argument of kernel but the piece, with counter as its work
 * counter. */
static int set_args(const struct launch_state *st, cl_kernel kernel,
		    const struct work_counter *counter, const struct render_result *res, char *err,
		    size_t err_size)
{
	const cl_mem *buffers[RENDER_ARGS] = {
		[ARG_SCENE] = &st->b.scene,
		[ARG_IMAGE] = &st->b.image.image,
		[ARG_SUMS] = &st->b.sums,
		[ARG_WORK_COUNTER] = &counter->buffer,
		[ARG_COUNTS] = &st->b.flops,
		[ARG_PROBE] = &st->b.probe,
	};

	for (cl_uint i = 0; i < RENDER_ARGS; i++) {
		cl_int status;
		if (i == ARG_PIECE)
			continue; /* set per piece */
		if (i == ARG_SCENE_LOCAL)
			status = clSetKernelArg(kernel, i, local_argument_bytes(res), NULL);
		else
			status = clSetKernelArg(kernel, i, sizeof(cl_mem), buffers[i]);
		if (status != CL_SUCCESS) {
			snprintf(err, err_size, "clSetKernelArg(%u) failed: %s", i,
				 cl_error_name(status));
			return -1;
		}
	}
	return 0;
}

static int create_buffers(struct device *dev, const struct scene *scene,
			  const struct render_settings *s, struct launch_state *st,
			  struct render_result *res, char *err, size_t err_size)
{
	if (buffers_create(dev, scene, s, res, &st->b, (size_t)counts_bytes(s, res), "flop counts",
			   err, err_size) ||
	    watch_create_counter(dev, dev->queue, progress_enabled(), counter_group_bytes(s, res),
				 &st->work_counter, err, err_size))
		return -1;
	res->item_count = res->global_size[0] * res->global_size[1];
	st->b.item_count = res->item_count;
	return set_args(st, st->kernel, &st->work_counter, res, err, err_size);
}

/* Opens lanes 1 .. queues - 1: a queue each, with profiling, a kernel object
 * of the program and a work counter (not watched: the progress line moves
 * launch by launch). */
static int open_lanes(struct renderer *r, int queues, char *err, size_t err_size)
{
	struct device *dev = r->dev;
	struct launch_state *st = r->state;

	for (int i = 1; i < queues; i++) {
		struct lane *l = &st->lanes[i];
		cl_int status;
		l->queue = clCreateCommandQueue(dev->context, dev->id, CL_QUEUE_PROFILING_ENABLE,
						&status);
		if (status != CL_SUCCESS) {
			snprintf(err, err_size, "clCreateCommandQueue failed for queue %d of %s: %s",
				 i + 1, dev->name, cl_error_name(status));
			return -1;
		}
		l->kernel = program_create_kernel(st->b.program, "render", err, err_size);
		if (!l->kernel ||
		    watch_create_counter(dev, l->queue, 0,
					 counter_group_bytes(r->settings, r->result),
					 &l->work_counter, err, err_size) ||
		    set_args(st, l->kernel, &l->work_counter, r->result, err, err_size))
			return -1;
	}
	return 0;
}

/* The NDRange of piece: the plan's, except the naive kernel's, which covers
 * the piece's rectangle rounded up to whole work-groups. */
static void piece_global_size(const struct render_settings *s, const struct render_result *res,
			      const struct rt_piece *piece, size_t global[2])
{
	global[0] = res->global_size[0];
	global[1] = res->global_size[1];
	if (s->kernel->uses_groups || s->kernel->single_item)
		return;
	global[0] = ((size_t)piece->width + res->local_size[0] - 1) / res->local_size[0] *
		    res->local_size[0];
	global[1] = ((size_t)piece->height + res->local_size[1] - 1) / res->local_size[1] *
		    res->local_size[1];
}

/* What the progress line reads of a launch over piece: the pixels its work
 * counter reaches when done, those of the piece's whole chunks (1x1 for
 * serial), counted as handed out (dynamic in chunks, persistent in pixels)
 * or as done (the others, with RTCL_PROGRESS; program_counts_progress). */
static struct launch_watch piece_watch(const struct renderer *r, const struct rt_piece *piece)
{
	const struct kernel_info *k = r->settings->kernel;
	struct launch_state *st = r->state;
	const size_t *local = r->result->local_size;
	double chunk_pixels = (double)local[0] * local[1];
	double chunks = (double)((piece->width + local[0] - 1) / local[0]) *
			(double)((piece->height + local[1] - 1) / local[1]);

	/* A timed launch of serial, naive or cyclic counts nothing: the line
	 * then moves launch by launch. */
	int counted = k->counts_handed_out || program_counts_progress(r->settings);

	return (struct launch_watch){
		.counter = counted ? &st->work_counter : NULL,
		.word = k->counts_handed_out ? RT_COUNTER_NEXT : RT_COUNTER_DONE,
		.pixels_per_count = k->counts_handed_out && !k->pixel_counter ? chunk_pixels : 1,
		.pixels = chunks * chunk_pixels,
		.work = (double)piece->width * piece->height *
			(piece->sample_end - piece->sample_begin),
		.slot = r->dev,
	};
}

/* Renders a piece with one launch; the host resets the work counter first. */
static int singlepass_piece(struct renderer *r, const struct rt_piece *piece,
			    struct piece_result *out, char *err, size_t err_size)
{
	struct device *dev = r->dev;
	const struct render_settings *s = r->settings;
	struct launch_state *st = r->state;
	const char *call = "clEnqueueFillBuffer";
	size_t global[2];
	struct launch_watch watch = piece_watch(r, piece);
	struct rt_piece launched = renderer_launch_piece(piece);
	cl_int status = watch_reset_counter(&st->work_counter);

	piece_global_size(s, r->result, piece, global);
	out->kernel_ms = 0;
	out->launches = 1;
	if (status == CL_SUCCESS) {
		call = "clSetKernelArg";
		status = clSetKernelArg(st->kernel, ARG_PIECE, sizeof(launched), &launched);
	}
	if (status == CL_SUCCESS)
		status = launch_run(dev, st->kernel, 2, global, r->result->local_size, &watch,
				    &out->kernel_ms, &call);
	if (status == CL_SUCCESS && hook_device_fault()) {
		call = "waiting for the kernel";
		status = CL_OUT_OF_RESOURCES;
	}
	if (status == CL_SUCCESS && s->count_flops) {
		call = "reading the flop counts";
		status = buffers_add_item_counts(dev, &st->b, st->b.flops, pixel_counts_bytes(s),
						 global[0] * global[1], st->b.item_flops);
	}
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "%s failed (kernel '%s' on %s): %s", call, s->kernel->name,
			 dev->name, cl_error_name(status));
		return -1;
	}
	return 0;
}

/* One launch in flight on a lane: its event and its pixel samples. */
struct in_flight {
	cl_event event;
	double work;
};

/* Waits for f's launch, adds its profiled interval to spans and its work
 * to the progress line. */
static cl_int finish_launch(struct renderer *r, struct in_flight *f, struct launch_span *spans,
			    int *span_count)
{
	struct launch_span span = {0, 0};
	cl_int status = clWaitForEvents(1, &f->event);

	if (status == CL_SUCCESS)
		status = launch_event_span(f->event, &span);
	clReleaseEvent(f->event);
	f->event = NULL;
	spans[(*span_count)++] = span;
	progress_add(r->dev, f->work);
	progress_draw();
	return status;
}

/* How many passes each lane has enqueued ahead (singlepass_passes). */
#define LANE_DEPTH 2

/* Waits for every launch still in flight on the lanes, in the order they
 * were enqueued (passes before `pass`); the first failure is returned. */
static cl_int drain_lanes(struct renderer *r, struct in_flight (*flight)[LANE_DEPTH], int count,
			  int pass, struct launch_span *spans, int *span_count)
{
	cl_int status = CL_SUCCESS;

	for (int p = pass; p < pass + LANE_DEPTH; p++)
		for (int i = 0; i < count; i++) {
			struct in_flight *f = &flight[i][p % LANE_DEPTH];
			if (!f->event)
				continue;
			cl_int done = finish_launch(r, f, spans, span_count);
			if (status == CL_SUCCESS)
				status = done;
		}
	return status;
}

/* Renders the samples of the disjoint parts (the same range for each), part
 * i on lane i, in passes of per_pass samples: each lane's launches are enqueued LANE_DEPTH ahead of
 * the host, so that a lane's next launch is waiting when its last one ends
 * and another lane's launch can fill the device while one ends. Between
 * passes, a checkpoint waits for every lane (renderer_checkpoint), and a
 * stop (renderer_stopping) enqueues no more. */
static int singlepass_passes(struct renderer *r, const struct rt_piece *parts, int count,
			     int per_pass, struct piece_result *out, char *err, size_t err_size)
{
	const struct render_settings *s = r->settings;
	struct launch_state *st = r->state;
	struct in_flight flight[RENDER_MAX_QUEUES][LANE_DEPTH] = {{{0}}};
	int begin = parts[0].sample_begin, end = parts[0].sample_end;
	int passes = (end - begin + per_pass - 1) / per_pass;
	struct launch_span *spans = malloc((size_t)passes * count * sizeof(*spans));
	int span_count = 0, pass;
	const char *call = "malloc";
	cl_int status = spans ? CL_SUCCESS : CL_OUT_OF_HOST_MEMORY;

	/* What the device's queue holds (the image cleared, the scene
	 * uploaded, the last piece's launches) comes before every lane's
	 * launches: queues are in order only within themselves. */
	if (status == CL_SUCCESS) {
		call = "clFinish";
		status = clFinish(r->dev->queue);
	}

	for (pass = 0; pass < passes && status == CL_SUCCESS; pass++) {
		if (pass > 0 && renderer_stopping(r))
			break;
		if (pass > 0 && renderer_checkpoint_due(r)) {
			call = "waiting for the kernel";
			status = drain_lanes(r, flight, count, pass, spans, &span_count);
			if (status != CL_SUCCESS)
				break;
			if (renderer_checkpoint(r, pass * per_pass, err, err_size)) {
				free(spans);
				return -1;
			}
		}
		for (int i = 0; i < count && status == CL_SUCCESS; i++) {
			cl_command_queue queue = i ? st->lanes[i].queue : r->dev->queue;
			cl_kernel kernel = i ? st->lanes[i].kernel : st->kernel;
			struct work_counter *counter = i ? &st->lanes[i].work_counter
							 : &st->work_counter;
			struct in_flight *f = &flight[i][pass % LANE_DEPTH];
			struct rt_piece piece = renderer_launch_piece(&parts[i]);
			size_t global[2];
			piece.sample_begin = begin + pass * per_pass;
			piece.sample_end = end - piece.sample_begin > per_pass
						   ? piece.sample_begin + per_pass
						   : end;
			piece_global_size(s, r->result, &piece, global);
			call = "waiting for the kernel";
			if (f->event)
				status = finish_launch(r, f, spans, &span_count);
			if (status == CL_SUCCESS) {
				call = "clEnqueueFillBuffer";
				status = watch_reset_counter(counter);
			}
			if (status == CL_SUCCESS) {
				call = "clSetKernelArg";
				status = clSetKernelArg(kernel, ARG_PIECE, sizeof(piece), &piece);
			}
			if (status == CL_SUCCESS) {
				call = "clEnqueueNDRangeKernel";
				status = clEnqueueNDRangeKernel(queue, kernel, 2, NULL, global,
								r->result->local_size, 0, NULL,
								&f->event);
				if (status != CL_SUCCESS)
					f->event = NULL; /* none was made */
			}
			if (status == CL_SUCCESS) {
				call = "clFlush";
				f->work = (double)piece.width * piece.height *
					  (piece.sample_end - piece.sample_begin);
				status = clFlush(queue);
			}
		}
	}
	/* Every launch still in flight, in the order they were enqueued. */
	cl_int done = drain_lanes(r, flight, count, pass, spans, &span_count);
	if (status == CL_SUCCESS) {
		call = "waiting for the kernel";
		status = done;
	}
	if (status == CL_SUCCESS && hook_device_fault()) {
		call = "waiting for the kernel";
		status = CL_OUT_OF_RESOURCES;
	}
	out->launches = span_count;
	out->kernel_ms = spans ? launch_busy_ms(spans, span_count) : 0;
	out->passes = pass;
	out->samples = pass * per_pass < end - begin ? pass * per_pass : end - begin;
	free(spans);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "%s failed (kernel '%s' on %s, %d queues): %s", call,
			 s->kernel->name, r->dev->name, count, cl_error_name(status));
		return -1;
	}
	return 0;
}

static int singlepass_read_back(struct renderer *r, char *err, size_t err_size)
{
	struct launch_state *st = r->state;

	return buffers_read_back(r->dev, r->settings, &st->b, r->result, err, err_size);
}

static int singlepass_read_rows(struct renderer *r, const struct rt_piece *piece, float *to,
				int packed, char *err, size_t err_size)
{
	struct launch_state *st = r->state;

	return buffers_read_rows(r->dev, r->settings, &st->b, piece, to, packed, err, err_size);
}

static int singlepass_read_sums(struct renderer *r, cl_long *to, size_t first, size_t count,
				cl_event *event, char *err, size_t err_size)
{
	struct launch_state *st = r->state;

	return buffers_read_sums(r->dev, &st->b, to, first, count, event, err, err_size);
}

static int singlepass_open(struct renderer *r, const struct scene *scene, char *err,
			   size_t err_size)
{
	struct device *dev = r->dev;
	const struct render_settings *s = r->settings;
	struct render_result *res = r->result;
	struct launch_state *st = calloc(1, sizeof(*st));

	if (!st) {
		snprintf(err, err_size, "out of host memory");
		return -1;
	}
	r->state = st;
	r->buffers = &st->b;
	if (launch_setup(dev, scene, s, res, &st->b.scene_block, &st->b.program, err, err_size) ||
	    (s->count_flops &&
	     device_check_fits(dev, "the flop count buffer", counts_bytes(s, res), err, err_size)))
		return -1;
	st->kernel = program_create_kernel(st->b.program, "render", err, err_size);
	if (!st->kernel)
		return -1;
	if (!s->kernel->single_item &&
	    launch_check_kernel(dev, st->kernel, res, s->kernel->name, err, err_size))
		return -1;
	double lap = timing_now();
	if (create_buffers(dev, scene, s, st, res, err, err_size) ||
	    open_lanes(r, r->queues, err, err_size))
		return -1;
	st->b.item_flops = calloc(res->item_count, sizeof(uint64_t));
	if (!st->b.item_flops) {
		snprintf(err, err_size, "out of host memory for the flop counts");
		return -1;
	}
	if (buffers_clear(dev, s, &st->b, err, err_size))
		return -1;
	res->times.scene += timing_lap_ms(&lap);
	return 0;
}

static void singlepass_close(struct renderer *r)
{
	if (r->state)
		release_state(r->state);
	free(r->state);
	r->state = NULL;
}

static int singlepass_aov(struct renderer *r, char *err, size_t err_size)
{
	struct launch_state *st = r->state;

	return aov_render(r->dev, r->settings, r->result, &st->b, err, err_size);
}

const struct renderer_ops singlepass_ops = {singlepass_open,	    singlepass_piece,
					    singlepass_passes,	    singlepass_read_back,
					    singlepass_read_rows, singlepass_read_sums,
					    singlepass_close,	    singlepass_aov};
