/* The single-pass renderer: serial, naive, cyclic, dynamic and persistent
 * (cl/NAME.cl) each trace a whole frame in one launch of their `render`
 * kernel. */
#include "singlepass.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../cl/rtcl_shared.h"
#include "checks.h"
#include "launch.h"
#include "program.h"
#include "timing.h"

/* The arguments of every single-pass kernel, in order. */
enum render_arg {
	ARG_SCENE,
	ARG_SCENE_LOCAL,
	ARG_IMAGE,
	ARG_WORK_COUNTER,
	ARG_COUNTS,
	ARG_WRITE_COUNTS,
	RENDER_ARGS
};

/* Everything one render holds on the device, released in reverse order. */
struct launch_state {
	cl_program program;
	cl_kernel kernel;
	cl_mem scene_buffer;
	struct guarded_image image;
	cl_mem work_counter; /* the next chunk or pixel to hand out */
	cl_mem counts;	     /* flops and rays per work-item, then flops per pixel */
	cl_mem write_counts;
};

static void release_state(struct launch_state *st)
{
	if (st->write_counts)
		clReleaseMemObject(st->write_counts);
	if (st->counts)
		clReleaseMemObject(st->counts);
	if (st->work_counter)
		clReleaseMemObject(st->work_counter);
	checks_release_image(&st->image);
	if (st->scene_buffer)
		clReleaseMemObject(st->scene_buffer);
	if (st->kernel)
		clReleaseKernel(st->kernel);
	if (st->program)
		clReleaseProgram(st->program);
}

/* Bytes of the counts buffer: RT_ITEM_COUNTS per work-item (flops, rays, node
 * visits), then one per pixel (flops). */
static double counts_bytes(const struct render_settings *s, const struct render_result *res)
{
	double items = (double)res->global_size[0] * res->global_size[1];

	return (items * RT_ITEM_COUNTS + (double)s->width * s->height) * sizeof(cl_ulong);
}

static int set_args(const struct launch_state *st, const struct render_result *res, char *err,
		    size_t err_size)
{
	const cl_mem *buffers[RENDER_ARGS] = {
		[ARG_SCENE] = &st->scene_buffer,	 [ARG_IMAGE] = &st->image.image,
		[ARG_WORK_COUNTER] = &st->work_counter, [ARG_COUNTS] = &st->counts,
		[ARG_WRITE_COUNTS] = &st->write_counts,
	};

	for (cl_uint i = 0; i < RENDER_ARGS; i++) {
		cl_int status;
		if (i == ARG_SCENE_LOCAL)
			status = clSetKernelArg(st->kernel, i,
						res->scene_in_local ? res->scene_bytes
								    : UNUSED_BUFFER_BYTES,
						NULL);
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
	st->work_counter = device_create_buffer(dev, CL_MEM_READ_WRITE, sizeof(cl_uint), NULL,
						"chunk counter", err, err_size);
	if (!st->work_counter)
		return -1;
	res->item_count = res->global_size[0] * res->global_size[1];
	st->counts = device_create_buffer(
		dev, CL_MEM_READ_WRITE,
		s->count_flops ? (size_t)counts_bytes(s, res) : UNUSED_BUFFER_BYTES, NULL,
		"flop counts", err, err_size);
	if (!st->counts)
		return -1;
	st->write_counts = checks_create_write_counts(dev, s, err, err_size);
	if (!st->write_counts)
		return -1;
	return set_args(st, res, err, err_size);
}

/* Renders the warm-up and timed frames, one launch each; the host resets the
 * work counter before every launch. */
static int launch_all(struct device *dev, const struct render_settings *s, struct launch_state *st,
		      struct render_result *res, char *err, size_t err_size)
{
	int launches = launch_begin_timing(s, res, err, err_size);

	if (launches < 0)
		return -1;
	for (int i = 0; i < launches; i++) {
		char label[96];
		double ms = 0;
		const char *call = "clEnqueueFillBuffer";
		cl_uint zero = 0;
		cl_int status = clEnqueueFillBuffer(dev->queue, st->work_counter, &zero,
						    sizeof(zero), 0, sizeof(zero), 0, NULL, NULL);

		if (status == CL_SUCCESS)
			status = checks_poison(dev, s, &st->image, st->write_counts);
		snprintf(label, sizeof(label), "rendering (%s, launch %d of %d)", s->kernel->name,
			 i + 1, launches);
		if (status == CL_SUCCESS)
			status = launch_run(dev, s, st->kernel, 2, res->global_size,
					    res->local_size, label, &ms, &call);
		if (status == CL_SUCCESS && i == launches - 1 && checks_device_fault_injected()) {
			call = "waiting for the kernel";
			status = CL_OUT_OF_RESOURCES;
		}
		if (status != CL_SUCCESS) {
			snprintf(err, err_size, "%s failed (kernel '%s' on %s): %s", call,
				 s->kernel->name, dev->name, cl_error_name(status));
			return -1;
		}
		launch_record_frame(res, i, launches, ms);
	}
	return launch_end_timing(res, err, err_size);
}

/* Reads the per-work-item flops, rays and node visits (interleaved on the
 * device) and the
 * per-pixel flops that follow them. */
static cl_int read_counts(struct device *dev, const struct render_settings *s,
			  const struct launch_state *st, struct render_result *res)
{
	size_t pixels = (size_t)s->width * s->height;
	size_t item_bytes = res->item_count * RT_ITEM_COUNTS * sizeof(cl_ulong);
	cl_ulong *counts = malloc(item_bytes);
	cl_int status;

	res->item_flops = malloc(res->item_count * sizeof(uint64_t));
	res->pixel_flops = malloc(pixels * sizeof(uint64_t));
	if (!counts || !res->item_flops || !res->pixel_flops) {
		free(counts);
		return CL_OUT_OF_HOST_MEMORY;
	}
	status = clEnqueueReadBuffer(dev->queue, st->counts, CL_TRUE, 0, item_bytes, counts, 0,
				     NULL, NULL);
	if (status == CL_SUCCESS)
		status = clEnqueueReadBuffer(dev->queue, st->counts, CL_TRUE, item_bytes,
					     pixels * sizeof(cl_ulong), res->pixel_flops, 0, NULL,
					     NULL);
	for (size_t i = 0; status == CL_SUCCESS && i < res->item_count; i++) {
		res->item_flops[i] = counts[RT_ITEM_COUNTS * i];
		res->total_flops += counts[RT_ITEM_COUNTS * i];
		res->total_rays += counts[RT_ITEM_COUNTS * i + 1];
		res->total_node_visits += counts[RT_ITEM_COUNTS * i + 2];
	}
	free(counts);
	return status;
}

static int read_back(struct device *dev, const struct render_settings *s, struct launch_state *st,
		     struct render_result *res, char *err, size_t err_size)
{
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

int singlepass_render(struct device *dev, const struct scene *scene,
		      const struct render_settings *s, struct render_result *res, char *err,
		      size_t err_size)
{
	struct launch_state st;
	void *scene_block = NULL;
	int ret = -1;

	memset(&st, 0, sizeof(st));
	if (launch_setup(dev, scene, s, res, &scene_block, &st.program, err, err_size) ||
	    (s->count_flops &&
	     device_check_fits(dev, "the flop count buffer", counts_bytes(s, res), err, err_size)))
		goto out;
	st.kernel = program_create_kernel(st.program, "render", err, err_size);
	if (!st.kernel)
		goto out;
	if (!s->kernel->single_item &&
	    launch_check_kernel(dev, st.kernel, res, s->kernel->name, err, err_size))
		goto out;
	double lap = timing_now();
	if (create_buffers(dev, s, &st, res, scene_block, err, err_size))
		goto out;
	res->times.scene += timing_lap_ms(&lap);
	if (launch_all(dev, s, &st, res, err, err_size))
		goto out;
	res->times.kernels = timing_lap_ms(&lap);
	if (read_back(dev, s, &st, res, err, err_size))
		goto out;
	res->times.read_back = timing_lap_ms(&lap);
	ret = 0;

out:
	release_state(&st);
	free(scene_block);
	return ret;
}
