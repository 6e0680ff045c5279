/* The wavefront renderer (cl/wavefront.cl): a piece (renderer.h) is traced
 * one sample at a time, each with one launch for the primary rays of the
 * piece's pixels, then one launch per bounce over a queue of live rays, until
 * the queue is empty or max_depth is reached, then one launch that adds the
 * sample to the pixels' running sums. A piece's kernel time is the sum of its
 * launches' profiled times.
 *
 * The queues hold at most `capacity` rays each. A bounce can at most double
 * the number of rays, so no fixed capacity short of pixels·2^depth is safe;
 * instead a bounce that overflows its queue says so, and the sample is traced
 * again with queues twice as large (up to what the device can allocate).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rtcl_shared.h"
#include "render/aov.h"
#include "render/buffers.h"
#include "render/launch.h"
#include "render/renderer.h"
#include "render/program.h"
#include "base/progress.h"
#include "base/timing.h"
#include "render/wavefront.h"

#define FRAME_OVERFLOWED 1

struct wavefront {
	struct render_buffers b; /* b.item_flops: every launch's work-items, appended */
	cl_kernel start, bounce, accumulate;
	cl_mem queues[2], next_count, overflow, item_counts;
	cl_mem sample_rgb, sample_flops; /* the sample being traced */
	size_t capacity;		 /* rays per queue */
	size_t item_capacity;		 /* work-items whose counts item_counts holds */
	size_t bounce_local;		 /* 1D work-group size of the bounce launches */
	size_t item_alloc;		 /* b.item_flops' room */
	size_t entry_bytes;		 /* a queued ray's: struct rt_ray, or under the
					    path integrator struct rt_path_ray */
};

static void release_queues(struct wavefront *w)
{
	for (int i = 0; i < 2; i++)
		if (w->queues[i])
			clReleaseMemObject(w->queues[i]);
	if (w->item_counts)
		clReleaseMemObject(w->item_counts);
	w->queues[0] = w->queues[1] = w->item_counts = NULL;
}

static void release_all(struct wavefront *w)
{
	cl_mem buffers[] = {w->sample_flops, w->sample_rgb, w->overflow, w->next_count};

	release_queues(w);
	for (size_t i = 0; i < sizeof(buffers) / sizeof(buffers[0]); i++)
		if (buffers[i])
			clReleaseMemObject(buffers[i]);
	if (w->accumulate)
		clReleaseKernel(w->accumulate);
	if (w->bounce)
		clReleaseKernel(w->bounce);
	if (w->start)
		clReleaseKernel(w->start);
	buffers_release(&w->b);
}

/* (Re)creates the two ray queues and the per-work-item counts for the
 * current capacity. */
static int create_queues(struct device *dev, const struct render_settings *s, struct wavefront *w,
			 char *err, size_t err_size)
{
	size_t bytes = w->capacity * w->entry_bytes;
	char what[96];

	release_queues(w);
	snprintf(what, sizeof(what), "the wavefront ray queue (%zu rays)", w->capacity);
	if (device_check_fits(dev, what, (double)bytes, err, err_size))
		return -1;
	for (int i = 0; i < 2; i++) {
		w->queues[i] = device_create_buffer(dev, CL_MEM_READ_WRITE, bytes, NULL, what, err,
						    err_size);
		if (!w->queues[i])
			return -1;
	}
	size_t rounded = (w->capacity + w->bounce_local - 1) / w->bounce_local * w->bounce_local;
	w->item_capacity = rounded > w->item_capacity ? rounded : w->item_capacity;
	size_t count_bytes = w->item_capacity * RT_ITEM_COUNTS * sizeof(cl_ulong);
	w->item_counts = device_create_buffer(dev, CL_MEM_READ_WRITE,
					      s->count_flops ? count_bytes : UNUSED_BUFFER_BYTES,
					      NULL, "per-work-item counts", err, err_size);
	return w->item_counts ? 0 : -1;
}

static int create_wavefront_buffers(struct device *dev, const struct scene *scene,
				    const struct render_settings *s, struct render_result *res,
				    struct wavefront *w, char *err, size_t err_size)
{
	size_t pixels = (size_t)s->width * s->height;
	size_t flops_bytes = s->count_flops ? pixels * sizeof(cl_ulong) : UNUSED_BUFFER_BYTES;

	if (buffers_create(dev, scene, s, res, &w->b, pixels * sizeof(cl_ulong), "per-pixel counts",
			   err, err_size))
		return -1;
	w->next_count = device_create_buffer(dev, CL_MEM_READ_WRITE, sizeof(cl_uint), NULL,
					     "queue counter", err, err_size);
	w->overflow = device_create_buffer(dev, CL_MEM_READ_WRITE, sizeof(cl_uint), NULL,
					   "overflow flag", err, err_size);
	w->sample_flops = device_create_buffer(dev, CL_MEM_READ_WRITE, flops_bytes, NULL,
					       "per-pixel counts of a sample", err, err_size);
	w->sample_rgb =
		device_create_buffer(dev, CL_MEM_READ_WRITE, image_float_bytes(s->width, s->height),
				     NULL, "the colours of a sample", err, err_size);
	if (!w->next_count || !w->overflow || !w->sample_flops || !w->sample_rgb)
		return -1;
	return create_queues(dev, s, w, err, err_size);
}

/* Appends the counts of a launch's `items` work-items. */
static cl_int append_counts(struct device *dev, struct wavefront *w, size_t items)
{
	return buffers_append_item_counts(dev, &w->b, w->item_counts, items, &w->item_alloc);
}

static cl_int set_kernel_args(cl_kernel kernel, const void *const *values, const size_t *sizes,
			      cl_uint count)
{
	cl_int status = CL_SUCCESS;

	for (cl_uint i = 0; status == CL_SUCCESS && i < count; i++)
		status = clSetKernelArg(kernel, i, sizes[i], values[i]);
	return status;
}

/* The NDRange of the per-pixel launches over piece: its rectangle rounded up
 * to whole work-groups, as the naive kernel covers it. */
static void wavefront_global_size(const struct render_result *res, const struct rt_piece *piece,
				  size_t global[2])
{
	for (int d = 0; d < 2; d++) {
		size_t extent = (size_t)(d ? piece->height : piece->width);
		global[d] =
			(extent + res->local_size[d] - 1) / res->local_size[d] * res->local_size[d];
	}
}

/* Launches the primary rays of sample `sample` of every pixel of piece. */
static cl_int launch_primary(struct renderer *r, struct wavefront *w, size_t local_bytes,
			     const struct rt_piece *piece, cl_uint sample, double *ms)
{
	struct device *dev = r->dev;
	size_t global[2];
	cl_uint zero = 0;
	const char *call; /* the wavefront's errors name the sample, not the call */
	const void *args[] = {&w->b.scene,	NULL,		&w->queues[0], &w->item_counts,
			      &w->sample_flops, &w->sample_rgb, piece,	       &sample};
	const size_t sizes[] = {sizeof(cl_mem), local_bytes,	sizeof(cl_mem), sizeof(cl_mem),
				sizeof(cl_mem), sizeof(cl_mem), sizeof(*piece), sizeof(cl_uint)};
	cl_int status = clEnqueueFillBuffer(dev->queue, w->overflow, &zero, sizeof(zero), 0,
					    sizeof(zero), 0, NULL, NULL);

	wavefront_global_size(r->result, piece, global);
	if (status == CL_SUCCESS)
		status = set_kernel_args(w->start, args, sizes, 8);
	if (status == CL_SUCCESS)
		status = launch_run(dev, w->start, 2, global, r->result->local_size, NULL, ms,
				    &call);
	if (status == CL_SUCCESS && r->settings->count_flops)
		status = append_counts(dev, w, global[0] * global[1]);
	return status;
}

/* Adds sample `sample` to the sums of piece's pixels (or stores their mean). */
static cl_int launch_accumulate(struct renderer *r, struct wavefront *w, size_t local_bytes,
				const struct rt_piece *piece, cl_uint sample, double *ms)
{
	size_t global[2];
	const char *call;
	struct rt_piece launched = renderer_launch_piece(piece);
	const void *args[] = {&w->b.scene,	NULL,		&w->b.image.image, &w->b.sums,
			      &w->sample_rgb,	&w->item_counts, &w->b.flops,	    &w->sample_flops,
			      &w->b.probe,	&launched,	&sample};
	const size_t sizes[] = {sizeof(cl_mem), local_bytes,	sizeof(cl_mem),	  sizeof(cl_mem),
				sizeof(cl_mem), sizeof(cl_mem), sizeof(cl_mem),	  sizeof(cl_mem),
				sizeof(cl_mem), sizeof(launched), sizeof(cl_uint)};
	cl_int status = set_kernel_args(w->accumulate, args, sizes, 11);

	wavefront_global_size(r->result, piece, global);
	if (status == CL_SUCCESS)
		status = launch_run(r->dev, w->accumulate, 2, global, r->result->local_size, NULL,
				    ms, &call);
	if (status == CL_SUCCESS && r->settings->count_flops)
		status = append_counts(r->dev, w, global[0] * global[1]);
	return status;
}
/* Traces the *queued rays of queue bounce % 2, sample `sample` of `samples`,
 * appending the rays they spawn to the other queue, and sets *queued to their
 * number. Returns CL_SUCCESS,
 * FRAME_OVERFLOWED, or an OpenCL error. */
static cl_int launch_bounce(struct device *dev, const struct render_settings *s,
			    struct wavefront *w, size_t local_bytes, int bounce, cl_uint *queued,
			    cl_uint sample, cl_uint samples, double *ms)
{
	cl_mem in = w->queues[bounce % 2], out = w->queues[(bounce + 1) % 2];
	size_t global = (*queued + w->bounce_local - 1) / w->bounce_local * w->bounce_local;
	cl_uint zero = 0, overflowed = 0, capacity = (cl_uint)w->capacity;
	const char *call;
	const void *args[] = {
		&w->b.scene,	 NULL,	    &in,	  queued,	  &out,
		&w->next_count,	 &capacity, &w->overflow, &w->sample_rgb, &w->item_counts,
		&w->sample_flops, &sample,  &samples};
	const size_t sizes[] = {sizeof(cl_mem), local_bytes,	 sizeof(cl_mem),  sizeof(cl_uint),
				sizeof(cl_mem), sizeof(cl_mem),	 sizeof(cl_uint), sizeof(cl_mem),
				sizeof(cl_mem), sizeof(cl_mem),	 sizeof(cl_mem),  sizeof(cl_uint),
				sizeof(cl_uint)};
	cl_int status = clEnqueueFillBuffer(dev->queue, w->next_count, &zero, sizeof(zero), 0,
					    sizeof(zero), 0, NULL, NULL);

	if (status == CL_SUCCESS)
		status = set_kernel_args(w->bounce, args, sizes, 13);
	if (status == CL_SUCCESS)
		status = launch_run(dev, w->bounce, 1, &global, &w->bounce_local, NULL, ms, &call);
	if (status == CL_SUCCESS && s->count_flops)
		status = append_counts(dev, w, global);
	if (status == CL_SUCCESS)
		status = clEnqueueReadBuffer(dev->queue, w->next_count, CL_TRUE, 0, sizeof(*queued),
					     queued, 0, NULL, NULL);
	if (status == CL_SUCCESS)
		status = clEnqueueReadBuffer(dev->queue, w->overflow, CL_TRUE, 0,
					     sizeof(overflowed), &overflowed, 0, NULL, NULL);
	return status == CL_SUCCESS && overflowed ? FRAME_OVERFLOWED : status;
}

/* Traces sample `sample` of piece's pixels: the primary rays, the bounces,
 * and the sample added to the image; again with larger queues when one
 * overflows, dropping the counts of the attempt. Adds its time to *ms and
 * its launches to *launches. */
static int trace_sample(struct renderer *r, struct wavefront *w, const struct rt_piece *piece,
			cl_uint sample, double *ms, int *launches, char *err, size_t err_size)
{
	size_t local_bytes =
		r->result->scene_in_local ? r->result->scene_bytes : UNUSED_BUFFER_BYTES;
	size_t items_before = w->b.item_count;
	struct trace_counts counts_before = w->b.counts;

	for (;;) {
		double attempt = 0;
		cl_uint queued = (cl_uint)((size_t)piece->width * piece->height);
		int bounce = 0;
		cl_int status = launch_primary(r, w, local_bytes, piece, sample, &attempt);

		for (; status == CL_SUCCESS && queued > 0; bounce++)
			status = launch_bounce(r->dev, r->settings, w, local_bytes, bounce, &queued,
					       sample, (cl_uint)piece->samples, &attempt);
		if (status == FRAME_OVERFLOWED) {
			if (r->settings->verbose)
				fprintf(stderr,
					"rtcl: wavefront queue of %zu rays overflowed; "
					"tracing the sample again with %zu\n",
					w->capacity, 2 * w->capacity);
			w->capacity *= 2;
			w->b.item_count = items_before;
			w->b.counts = counts_before;
			if (create_queues(r->dev, r->settings, w, err, err_size))
				return -1;
			continue;
		}
		if (status == CL_SUCCESS)
			status = launch_accumulate(r, w, local_bytes, piece, sample, &attempt);
		if (status != CL_SUCCESS) {
			snprintf(err, err_size, "wavefront sample %u on %s failed: %s", sample,
				 r->dev->name, cl_error_name(status));
			return -1;
		}
		*ms += attempt;
		*launches += bounce + 2;
		return 0;
	}
}

static int wavefront_piece(struct renderer *r, const struct rt_piece *piece,
			   struct piece_result *out, char *err, size_t err_size)
{
	double pixels = (double)piece->width * piece->height;

	out->kernel_ms = 0;
	out->launches = 0;
	for (int k = piece->sample_begin; k < piece->sample_end; k++) {
		if (trace_sample(r, r->state, piece, (cl_uint)k, &out->kernel_ms, &out->launches,
				 err, err_size))
			return -1;
		/* The progress line moves a sample at a time: a sample's
		 * launches follow a queue whose length the host learns only
		 * bounce by bounce. */
		progress_partial(r->dev, (k + 1 - piece->sample_begin) * pixels);
		progress_draw();
	}
	return 0;
}

static int wavefront_read_rows(struct renderer *r, const struct rt_piece *piece, float *to,
			       int packed, char *err, size_t err_size)
{
	struct wavefront *w = r->state;

	return buffers_read_rows(r->dev, r->settings, &w->b, piece, to, packed, err, err_size);
}

static int wavefront_read_back(struct renderer *r, char *err, size_t err_size)
{
	struct wavefront *w = r->state;

	return buffers_read_back(r->dev, r->settings, &w->b, r->result, err, err_size);
}

static int wavefront_open(struct renderer *r, const struct scene *scene, char *err, size_t err_size)
{
	struct render_result *res = r->result;
	const struct render_settings *s = r->settings;
	size_t pixels = (size_t)s->width * s->height;
	struct wavefront *w = calloc(1, sizeof(*w));

	if (!w) {
		snprintf(err, err_size, "out of host memory");
		return -1;
	}
	r->state = w;
	r->buffers = &w->b;
	w->entry_bytes = scene->integrator == SCENE_INTEGRATOR_PATH ? sizeof(struct rt_path_ray)
								    : sizeof(struct rt_ray);
	/* The per-pixel launches cover the image as the naive kernel does. */
	if (launch_setup(r->dev, scene, s, res, &w->b.scene_block, &w->b.program, err, err_size))
		return -1;
	w->bounce_local = res->local_size[0] * res->local_size[1];
	w->item_capacity = res->global_size[0] * res->global_size[1];
	/* Room for two rays a pixel; more is found on demand. */
	w->capacity = pixels * 2 > 1024 ? pixels * 2 : 1024;
	w->start = program_create_kernel(w->b.program, "wavefront_start", err, err_size);
	w->bounce = w->start
			    ? program_create_kernel(w->b.program, "wavefront_bounce", err, err_size)
			    : NULL;
	w->accumulate = w->bounce ? program_create_kernel(w->b.program, "wavefront_accumulate", err,
							  err_size)
				  : NULL;
	double lap = timing_now();
	if (!w->accumulate || create_wavefront_buffers(r->dev, scene, s, res, w, err, err_size) ||
	    buffers_clear(r->dev, s, &w->b, err, err_size))
		return -1;
	res->times.scene += timing_lap_ms(&lap);
	return 0;
}

static void wavefront_close(struct renderer *r)
{
	if (r->state)
		release_all(r->state);
	free(r->state);
	r->state = NULL;
}

static int wavefront_read_sums(struct renderer *r, cl_long *to, size_t first, size_t count,
				cl_event *event, char *err, size_t err_size)
{
	struct wavefront *w = r->state;

	return buffers_read_sums(r->dev, &w->b, to, first, count, event, err, err_size);
}

static int wavefront_aov(struct renderer *r, char *err, size_t err_size)
{
	struct wavefront *w = r->state;

	return aov_render(r->dev, r->settings, r->result, &w->b, err, err_size);
}

const struct renderer_ops wavefront_ops = {wavefront_open,	   wavefront_piece,
					   NULL,		   wavefront_read_back,
					   wavefront_read_rows, wavefront_read_sums,
					   wavefront_close,	   wavefront_aov};
