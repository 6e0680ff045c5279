/* The single-pass renderer: serial, naive, cyclic, dynamic and persistent
 * (cl/NAME.cl) each trace a piece of the image (renderer.h) in one launch of
 * their `render` kernel. */
#include "render/singlepass.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rtcl_shared.h"
#include "render/checks.h"
#include "base/test_hooks.h"
#include "render/launch.h"
#include "render/program.h"
#include "base/progress.h"
#include "base/timing.h"

/* The arguments of every single-pass kernel, in order. */
enum render_arg {
	ARG_SCENE,
	ARG_SCENE_LOCAL,
	ARG_IMAGE,
	ARG_WORK_COUNTER,
	ARG_COUNTS,
	ARG_WRITE_COUNTS,
	ARG_PIECE,
	RENDER_ARGS
};

/* Everything one render holds on the device, released in reverse order. */
struct launch_state {
	cl_program program;
	cl_kernel kernel;
	cl_mem scene_buffer;
	struct guarded_image image;
	struct work_counter work_counter; /* cl/rtcl_shared.h, RT_COUNTER_* */
	cl_mem counts;			  /* flops per pixel, then RT_ITEM_COUNTS per work-item */
	cl_mem write_counts;
	void *scene_block;
	uint64_t *item_flops; /* per work-item of the plan, added over the launches */
	uint64_t rays, node_visits;
};

static void release_state(struct launch_state *st)
{
	free(st->item_flops);
	free(st->scene_block);
	if (st->write_counts)
		clReleaseMemObject(st->write_counts);
	if (st->counts)
		clReleaseMemObject(st->counts);
	launch_release_counter(&st->work_counter);
	checks_release_image(&st->image);
	if (st->scene_buffer)
		clReleaseMemObject(st->scene_buffer);
	if (st->kernel)
		clReleaseKernel(st->kernel);
	if (st->program)
		clReleaseProgram(st->program);
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

static int set_args(const struct launch_state *st, const struct render_result *res, char *err,
		    size_t err_size)
{
	const cl_mem *buffers[RENDER_ARGS] = {
		[ARG_SCENE] = &st->scene_buffer,
		[ARG_IMAGE] = &st->image.image,
		[ARG_WORK_COUNTER] = &st->work_counter.buffer,
		[ARG_COUNTS] = &st->counts,
		[ARG_WRITE_COUNTS] = &st->write_counts,
	};

	for (cl_uint i = 0; i < RENDER_ARGS; i++) {
		cl_int status;
		if (i == ARG_PIECE)
			continue; /* set per piece */
		if (i == ARG_SCENE_LOCAL)
			status = clSetKernelArg(
				st->kernel, i,
				res->scene_in_local ? res->scene_bytes : UNUSED_BUFFER_BYTES, NULL);
		else
			status = clSetKernelArg(st->kernel, i, sizeof(cl_mem), buffers[i]);
		if (status != CL_SUCCESS) {
			snprintf(err, err_size, "clSetKernelArg(%u) failed: %s", i,
				 cl_error_name(status));
			return -1;
		}
	}
	return 0;
}

static int create_buffers(struct device *dev, const struct render_settings *s,
			  struct launch_state *st, struct render_result *res, void *scene_block,
			  char *err, size_t err_size)
{
	st->scene_buffer =
		device_create_buffer(dev, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, res->scene_bytes,
				     scene_block, "scene", err, err_size);
	if (!st->scene_buffer || checks_create_image(dev, s, &st->image, err, err_size))
		return -1;
	if (launch_create_counter(dev, progress_enabled(), &st->work_counter, err, err_size))
		return -1;
	res->item_count = res->global_size[0] * res->global_size[1];
	st->counts = device_create_buffer(dev, CL_MEM_READ_WRITE,
					  s->count_flops ? (size_t)counts_bytes(s, res)
							 : UNUSED_BUFFER_BYTES,
					  NULL, "flop counts", err, err_size);
	if (!st->counts)
		return -1;
	st->write_counts = checks_create_write_counts(dev, s, err, err_size);
	if (!st->write_counts)
		return -1;
	return set_args(st, res, err, err_size);
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

/* Adds the launch's per-work-item counts to the host's sums. */
static cl_int add_item_counts(struct device *dev, const struct render_settings *s,
			      struct launch_state *st, size_t items)
{
	cl_ulong *counts = malloc(items * RT_ITEM_COUNTS * sizeof(cl_ulong));
	cl_int status;

	if (!counts)
		return CL_OUT_OF_HOST_MEMORY;
	status = clEnqueueReadBuffer(dev->queue, st->counts, CL_TRUE, pixel_counts_bytes(s),
				     items * RT_ITEM_COUNTS * sizeof(cl_ulong), counts, 0, NULL,
				     NULL);
	for (size_t i = 0; status == CL_SUCCESS && i < items; i++) {
		st->item_flops[i] += counts[RT_ITEM_COUNTS * i];
		st->rays += counts[RT_ITEM_COUNTS * i + 1];
		st->node_visits += counts[RT_ITEM_COUNTS * i + 2];
	}
	free(counts);
	return status;
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
	cl_int status = launch_reset_counter(&st->work_counter);

	piece_global_size(s, r->result, piece, global);
	out->kernel_ms = 0;
	out->launches = 1;
	if (status == CL_SUCCESS) {
		call = "clSetKernelArg";
		status = clSetKernelArg(st->kernel, ARG_PIECE, sizeof(*piece), piece);
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
		status = add_item_counts(dev, s, st, global[0] * global[1]);
	}
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "%s failed (kernel '%s' on %s): %s", call, s->kernel->name,
			 dev->name, cl_error_name(status));
		return -1;
	}
	return 0;
}

/* Reads the per-pixel flops and hands over the per-work-item sums. */
static cl_int read_counts(struct device *dev, const struct render_settings *s,
			  struct launch_state *st, struct render_result *res)
{
	size_t pixels = (size_t)s->width * s->height;

	res->pixel_flops = malloc(pixels * sizeof(uint64_t));
	if (!res->pixel_flops)
		return CL_OUT_OF_HOST_MEMORY;
	res->item_flops = st->item_flops;
	st->item_flops = NULL;
	res->total_flops = 0;
	for (size_t i = 0; i < res->item_count; i++)
		res->total_flops += res->item_flops[i];
	res->total_rays = st->rays;
	res->total_node_visits = st->node_visits;
	return clEnqueueReadBuffer(dev->queue, st->counts, CL_TRUE, 0, pixel_counts_bytes(s),
				   res->pixel_flops, 0, NULL, NULL);
}

static int singlepass_read_back(struct renderer *r, char *err, size_t err_size)
{
	struct device *dev = r->dev;
	const struct render_settings *s = r->settings;
	struct launch_state *st = r->state;
	struct render_result *res = r->result;
	cl_int status = clEnqueueReadBuffer(dev->queue, st->image.image, CL_TRUE, 0,
					    image_float_bytes(s->width, s->height), res->rgb, 0,
					    NULL, NULL);

	if (status == CL_SUCCESS && s->count_flops) {
		status = read_counts(dev, s, st, res);
		if (status == CL_OUT_OF_HOST_MEMORY) {
			snprintf(err, err_size, "out of host memory for the flop counts");
			return -1;
		}
	}
	if (status == CL_SUCCESS)
		status = checks_read(dev, s, &st->image, st->write_counts, res);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clEnqueueReadBuffer failed: %s", cl_error_name(status));
		return -1;
	}
	return 0;
}

/* Zeroes the counts and, with check_writes, poisons the image: the pieces
 * add to what the buffers hold. */
static int clear_buffers(struct device *dev, const struct render_settings *s,
			 struct launch_state *st, char *err, size_t err_size)
{
	cl_ulong zero = 0;
	cl_int status = checks_poison(dev, s, &st->image, st->write_counts);

	if (status == CL_SUCCESS && s->count_flops)
		status = clEnqueueFillBuffer(dev->queue, st->counts, &zero, sizeof(zero), 0,
					     pixel_counts_bytes(s), 0, NULL, NULL);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clEnqueueFillBuffer failed: %s", cl_error_name(status));
		return -1;
	}
	return 0;
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
	if (launch_setup(dev, scene, s, res, &st->scene_block, &st->program, err, err_size) ||
	    (s->count_flops &&
	     device_check_fits(dev, "the flop count buffer", counts_bytes(s, res), err, err_size)))
		return -1;
	st->kernel = program_create_kernel(st->program, "render", err, err_size);
	if (!st->kernel)
		return -1;
	if (!s->kernel->single_item &&
	    launch_check_kernel(dev, st->kernel, res, s->kernel->name, err, err_size))
		return -1;
	double lap = timing_now();
	if (create_buffers(dev, s, st, res, st->scene_block, err, err_size))
		return -1;
	st->item_flops = calloc(res->item_count, sizeof(uint64_t));
	if (!st->item_flops) {
		snprintf(err, err_size, "out of host memory for the flop counts");
		return -1;
	}
	if (clear_buffers(dev, s, st, err, err_size))
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

const struct renderer_ops singlepass_ops = {singlepass_open, singlepass_piece, singlepass_read_back,
					    singlepass_close};
