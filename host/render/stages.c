/* The stages form of the wavefront under the path integrator
 * (cl/wavefront.cl's stages_* kernels; docs/wavefront.md, "The stages
 * form"): a pool of path slots whose state lies in structure-of-arrays on
 * the device, and per iteration one launch of each stage over its compacted
 * queue: the logic kernel, the new paths, a shade kernel
 * per BSDF kind, the segments (nearest hit) and the shadow rays (any hit).
 * The logic kernel looks only at the paths that ended (but in a piece's
 * first iteration, when it pushes every slot on the free stack), and the
 * extension kernel sorts the paths it traced by the BSDF kind they hit.
 * A piece's paths are numbered sample by sample; a slot whose path ends
 * takes the next at once (path regeneration), and the host loops until
 * every path of the piece is done.
 *
 * The queue kernels read their queue's length on the device and loop over
 * it, so a launch's size need not be the length. By default the host reads
 * the counters once an iteration, after the logic kernel, and gives the
 * new-path and shade launches their exact sizes and the segment and shadow
 * launches a bound; with RTCL_STAGES_LAUNCH=device every queue launch fills
 * the device and the host reads the counters without waiting, only to know
 * when the piece is done. Launches are enqueued without waiting; their
 * profiled times are read once a later read has waited for them. */
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
#include "render/stages.h"

static const char *const kernel_names[STAGE_COUNT] = {
	"stages_begin",		   "stages_logic",	     "stages_new_path",	 "stages_advance",
	"stages_shade_mapped",	   "stages_shade_diffuse",   "stages_shade_conductor",
	"stages_shade_dielectric", "stages_shade_principled", "stages_extend",
	"stages_shadow",	   "stages_finish"};

/* Launches whose times are not read yet: two iterations' and more. */
#define STAGES_PENDING 64

struct stages {
	struct render_buffers b; /* b.item_flops: every launch's work-items, appended */
	cl_kernel kernels[STAGE_COUNT];
	cl_mem state, queues, counts, item_counts;
	cl_uint slots;
	size_t local;	      /* 1D work-group size of the queue launches */
	size_t item_capacity; /* work-items whose counts item_counts holds */
	size_t item_alloc;    /* b.item_flops' room */
	size_t local_bytes;   /* the scene's __local argument */
	int device_sizes;     /* RTCL_STAGES_LAUNCH=device: the queue launches
				 each over `fill` work-items that read their
				 counts on the device; the host reads the counters
				 without waiting, to know when the piece is done */
	size_t fill;	      /* work-items that fill the device */
	cl_event pending[STAGES_PENDING];
	enum stage pending_stage[STAGES_PENDING];
	int pending_count;
	struct stages_stats *stats; /* the result's */
};

const char *stages_name(enum stage stage)
{
	static const char *const names[STAGE_COUNT] = {
		"begin",	    "logic",	      "new_path",	  "advance", "shade_mapped",
		"shade_diffuse",    "shade_conductor", "shade_dielectric", "shade_principled",
		"extend",	    "shadow",	      "finish"};

	return names[stage];
}

int stages_item_bytes(enum stage stage)
{
	switch (stage) {
	case STAGE_LOGIC: /* its entry; reads 6 words (a miss: the ray's 4, a clear
			     shadow ray's light) and an int, writes the flags; a
			     free entry */
		return 4 + 6 * 16 + 4 + 4 + 4;
	case STAGE_NEW_PATH: /* its slot; writes 5 words and an extension entry */
		return 4 + 5 * 16 + 4;
	case STAGE_EXTEND: /* its slot; the ray's 2 words; the hit's 1.5; a shade entry */
		return 4 + 2 * 16 + 16 + 8 + 4;
	case STAGE_SHADOW: /* its slot; 3 words; the answer */
		return 4 + 3 * 16 + 4;
	case STAGE_BEGIN:
	case STAGE_ADVANCE:
	case STAGE_FINISH:
	case STAGE_COUNT:
		return 0;
	default: /* a shade kernel: its slot; reads 8 words (the last shadow ray's
		    light), writes 8; 2 entries */
		return 4 + 8 * 16 + 8 * 16 + 8;
	}
}

void stages_stats_free(struct stages_stats *stats)
{
	if (!stats)
		return;
	free(stats->live);
	free(stats->started);
	free(stats->extended);
	free(stats->shadowed);
	free(stats);
}

static void release_all(struct stages *w)
{
	cl_mem buffers[] = {w->state, w->queues, w->counts, w->item_counts};

	for (int i = 0; i < w->pending_count; i++)
		clReleaseEvent(w->pending[i]);
	for (size_t i = 0; i < sizeof(buffers) / sizeof(buffers[0]); i++)
		if (buffers[i])
			clReleaseMemObject(buffers[i]);
	for (int i = STAGE_COUNT - 1; i >= 0; i--)
		if (w->kernels[i])
			clReleaseKernel(w->kernels[i]);
	buffers_release(&w->b);
}

/* Appends the counts of a launch's `items` work-items. */
static cl_int append_counts(struct device *dev, struct stages *w, size_t items)
{
	return buffers_append_item_counts(dev, &w->b, w->item_counts, items, &w->item_alloc);
}

/* Reads the profiled times of the first `upto` launches pending, which
 * are done (the queue is in order and the caller waited on a later
 * command), and drops them from the list. */
static cl_int collect_times(struct stages *w, double *ms, int upto)
{
	cl_int status = CL_SUCCESS;

	for (int i = 0; i < upto; i++) {
		struct launch_span span = {0, 0};
		if (status == CL_SUCCESS)
			status = launch_event_span(w->pending[i], &span);
		double t = (double)(span.end - span.start) * 1e-6;
		*ms += t;
		w->stats->ms[w->pending_stage[i]] += t;
		clReleaseEvent(w->pending[i]);
	}
	memmove(w->pending, w->pending + upto, (size_t)(w->pending_count - upto) * sizeof(cl_event));
	memmove(w->pending_stage, w->pending_stage + upto,
		(size_t)(w->pending_count - upto) * sizeof(enum stage));
	w->pending_count -= upto;
	return status;
}

/* Enqueues stage's kernel over `items` work-items (1D, rounded up to the
 * work-group size; a 2D piece launch when global2 is given) after setting
 * its arguments; with --flops, waits and appends the work-items' counts. */
static cl_int enqueue(struct renderer *r, struct stages *w, enum stage stage, size_t items,
		      const size_t *global2, uint64_t busy, double *ms)
{
	struct device *dev = r->dev;
	size_t global = (items + w->local - 1) / w->local * w->local;
	cl_event event;
	cl_int status;

	if (w->pending_count == STAGES_PENDING) {
		status = clFinish(dev->queue);
		if (status == CL_SUCCESS)
			status = collect_times(w, ms, w->pending_count);
		if (status != CL_SUCCESS)
			return status;
	}
	if (global2)
		status = clEnqueueNDRangeKernel(dev->queue, w->kernels[stage], 2, NULL, global2,
						r->result->local_size, 0, NULL, &event);
	else
		status = clEnqueueNDRangeKernel(dev->queue, w->kernels[stage], 1, NULL, &global,
						&w->local, 0, NULL, &event);
	if (status != CL_SUCCESS)
		return status;
	w->pending[w->pending_count] = event;
	w->pending_stage[w->pending_count++] = stage;
	w->stats->launches[stage]++;
	w->stats->items[stage] += busy;
	/* The advance kernel counts nothing: its one work-item is not in the
	   --flops array. */
	if (r->settings->count_flops && stage != STAGE_ADVANCE) {
		status = clFinish(dev->queue);
		if (status == CL_SUCCESS)
			status = append_counts(dev, w, global2 ? global2[0] * global2[1] : global);
	}
	return status;
}

static cl_int set_args(cl_kernel kernel, const void *const *values, const size_t *sizes,
		       cl_uint count)
{
	cl_int status = CL_SUCCESS;

	for (cl_uint i = 0; status == CL_SUCCESS && i < count; i++)
		status = clSetKernelArg(kernel, i, sizes[i], values[i]);
	return status;
}

/* Sets the arguments every queue kernel starts with: the scene, the state,
 * the slots, the queues and their counters. */
static cl_int set_common(struct stages *w, cl_kernel kernel)
{
	const void *args[] = {&w->b.scene, NULL, &w->state, &w->slots, &w->queues, &w->counts};
	const size_t sizes[] = {sizeof(cl_mem), w->local_bytes,	 sizeof(cl_mem),
				sizeof(cl_uint), sizeof(cl_mem), sizeof(cl_mem)};

	return set_args(kernel, args, sizes, 6);
}

/* Zeroes counters [first, first + count). */
static cl_int zero_counts(struct device *dev, struct stages *w, int first, int count)
{
	cl_uint zero = 0;

	return clEnqueueFillBuffer(dev->queue, w->counts, &zero, sizeof(zero),
				   (size_t)first * sizeof(cl_uint), (size_t)count * sizeof(cl_uint),
				   0, NULL, NULL);
}

/* Records an iteration's live and started paths; returns its index, or -1
 * when out of memory (the figures stop; the render goes on). */
static int record_iteration(struct stages_stats *st, uint32_t live, uint32_t started)
{
	if (st->iterations == st->iteration_alloc) {
		int alloc = st->iteration_alloc ? 2 * st->iteration_alloc : 64;
		uint32_t *p[4] = {realloc(st->live, alloc * sizeof(uint32_t)),
				  realloc(st->started, alloc * sizeof(uint32_t)),
				  realloc(st->extended, alloc * sizeof(uint32_t)),
				  realloc(st->shadowed, alloc * sizeof(uint32_t))};
		st->live = p[0] ? p[0] : st->live;
		st->started = p[1] ? p[1] : st->started;
		st->extended = p[2] ? p[2] : st->extended;
		st->shadowed = p[3] ? p[3] : st->shadowed;
		if (!p[0] || !p[1] || !p[2] || !p[3])
			return -1;
		st->iteration_alloc = alloc;
	}
	st->live[st->iterations] = live;
	st->started[st->iterations] = started;
	st->extended[st->iterations] = 0;
	st->shadowed[st->iterations] = 0;
	return st->iterations++;
}

/* What the host learns at the read after an iteration's logic kernel:
 * the counters, and the paths of the piece handed out before it. */
struct stage_read {
	cl_uint counts[RT_STAGE_COUNTERS];
	cl_ulong handed_out;
};

/* Takes in an iteration's read: its figures, and the paths its new-path
 * launch starts (*started); returns whether the piece is done (every path
 * handed out, none left to shade). */
static int take_read(struct stages *w, const struct stage_read *read, uint64_t total,
		     int *recorded, cl_uint *started)
{
	struct stages_stats *st = w->stats;
	uint64_t live = 0;

	for (int k = 0; k < RT_STAGE_KINDS; k++) {
		live += read->counts[RT_STAGE_QUEUE_SHADE(k)];
		st->items[STAGE_SHADE_MAPPED + k] += read->counts[RT_STAGE_QUEUE_SHADE(k)];
	}
	/* the paths that ended, which the logic kernel just took */
	st->items[STAGE_LOGIC] += read->counts[RT_STAGE_QUEUE_DECIDE];
	/* the segments and shadow rays of the iteration before */
	st->items[STAGE_EXTEND] += read->counts[RT_STAGE_QUEUE_EXTEND];
	st->items[STAGE_SHADOW] += read->counts[RT_STAGE_QUEUE_SHADOW];
	if (*recorded >= 0) {
		st->extended[*recorded] = read->counts[RT_STAGE_QUEUE_EXTEND];
		st->shadowed[*recorded] = read->counts[RT_STAGE_QUEUE_SHADOW];
	}
	uint64_t left = total - read->handed_out;
	*started = read->counts[RT_STAGE_QUEUE_NEW] < left ? read->counts[RT_STAGE_QUEUE_NEW]
							    : (cl_uint)left;
	st->items[STAGE_NEW_PATH] += *started;
	if (left == 0 && live == 0)
		return 1;
	*recorded = record_iteration(st, (uint32_t)live, *started);
	return 0;
}

/* Sets a queue kernel's arguments after the common ones. */
static cl_int set_rest(cl_kernel kernel, const void *const *values, const size_t *sizes,
		       cl_uint count)
{
	cl_int status = CL_SUCCESS;

	for (cl_uint i = 0; status == CL_SUCCESS && i < count; i++)
		status = clSetKernelArg(kernel, 6 + i, sizes[i], values[i]);
	return status;
}

/* Enqueues the launches of an iteration after its read: with the read's
 * counts (read != NULL: exact sizes, or bounds for the rays), or each over
 * the grid that fills the device, its work-items reading the counts. */
static cl_int enqueue_queues(struct renderer *r, struct stages *w, const struct stage_read *read,
			     cl_uint started, const struct rt_piece *launched, cl_ulong total,
			     double *ms)
{
	cl_uint samples = (cl_uint)launched->samples, unlimited = 0xffffffffu;
	uint64_t live = 0;
	/* the queues the last iteration's rays and the logic kernel took */
	cl_int status = zero_counts(r->dev, w, RT_STAGE_QUEUE_EXTEND, 3);

	if (read)
		for (int k = 0; k < RT_STAGE_KINDS; k++)
			live += read->counts[RT_STAGE_QUEUE_SHADE(k)];
	if (status == CL_SUCCESS && (!read || started > 0)) {
		cl_uint limit = read ? started : unlimited;
		const void *args[] = {&limit, &total, launched, &w->item_counts, &w->b.flops};
		const size_t sizes[] = {sizeof(cl_uint), sizeof(cl_ulong), sizeof(*launched),
					sizeof(cl_mem), sizeof(cl_mem)};
		status = set_common(w, w->kernels[STAGE_NEW_PATH]);
		if (status == CL_SUCCESS)
			status = set_rest(w->kernels[STAGE_NEW_PATH], args, sizes, 5);
		if (status == CL_SUCCESS)
			status = enqueue(r, w, STAGE_NEW_PATH, read ? started : w->fill, NULL, 0, ms);
		if (status == CL_SUCCESS)
			status = clSetKernelArg(w->kernels[STAGE_ADVANCE], 1, sizeof(total), &total);
		if (status == CL_SUCCESS)
			status = enqueue(r, w, STAGE_ADVANCE, 1, NULL, 0, ms);
	}
	for (int k = 0; status == CL_SUCCESS && k < RT_STAGE_KINDS; k++) {
		cl_uint count = read ? read->counts[RT_STAGE_QUEUE_SHADE(k)] : unlimited;
		cl_kernel kernel = w->kernels[STAGE_SHADE_MAPPED + k];
		const void *args[] = {&count, &samples, &w->item_counts, &w->b.flops};
		const size_t sizes[] = {sizeof(cl_uint), sizeof(cl_uint), sizeof(cl_mem),
					sizeof(cl_mem)};
		if (count == 0)
			continue;
		status = set_common(w, kernel);
		if (status == CL_SUCCESS)
			status = set_rest(kernel, args, sizes, 4);
		if (status == CL_SUCCESS)
			status = enqueue(r, w, (enum stage)(STAGE_SHADE_MAPPED + k),
					 read ? count : w->fill, NULL, 0, ms);
	}
	/* the shade queues taken, for the extension kernel to fill */
	if (status == CL_SUCCESS)
		status = zero_counts(r->dev, w, RT_STAGE_QUEUE_SHADE(0), RT_STAGE_KINDS);
	/* At most one segment per path started or shaded, one shadow ray per
	 * path shaded. */
	size_t bounds[2] = {read ? started + live : w->fill, read ? live : w->fill};
	for (int s = 0; status == CL_SUCCESS && s < 2; s++) {
		enum stage stage = s ? STAGE_SHADOW : STAGE_EXTEND;
		const void *args[] = {&w->item_counts, &w->b.flops};
		const size_t sizes[] = {sizeof(cl_mem), sizeof(cl_mem)};
		if (bounds[s] == 0)
			continue;
		status = set_common(w, w->kernels[stage]);
		if (status == CL_SUCCESS)
			status = set_rest(w->kernels[stage], args, sizes, 2);
		if (status == CL_SUCCESS)
			status = enqueue(r, w, stage, bounds[s], NULL, 0, ms);
	}
	return status;
}

/* The loop over one piece's paths. */
static cl_int trace_piece(struct renderer *r, struct stages *w, const struct rt_piece *piece,
			  double *ms, int *launches)
{
	struct device *dev = r->dev;
	struct rt_piece launched = renderer_launch_piece(piece);
	cl_uint samples = (cl_uint)piece->samples;
	uint64_t per_sample = (uint64_t)piece->width * (uint64_t)piece->height;
	cl_ulong total = per_sample * (uint64_t)(piece->sample_end - piece->sample_begin);
	size_t global2[2];
	int recorded = -1; /* the index of the last iteration's figures */
	cl_uint in_flight = 0; /* paths started or shaded last iteration */
	int before = 0;
	cl_int status;

	if (piece->sample_begin == 0) /* a frame begins: its figures replace the last's */
		w->stats->iterations = 0;
	for (int s = 0; s < STAGE_COUNT; s++)
		before += w->stats->launches[s];
	for (int d = 0; d < 2; d++) {
		size_t extent = (size_t)(d ? piece->height : piece->width);
		size_t local = r->result->local_size[d];
		global2[d] = (extent + local - 1) / local * local;
	}
	{
		const void *args[] = {&w->b.scene, NULL, &w->b.sums, &w->item_counts, &launched};
		const size_t sizes[] = {sizeof(cl_mem), w->local_bytes, sizeof(cl_mem),
					sizeof(cl_mem), sizeof(launched)};
		status = set_args(w->kernels[STAGE_BEGIN], args, sizes, 5);
	}
	if (status == CL_SUCCESS)
		status = enqueue(r, w, STAGE_BEGIN, 0, global2, per_sample, ms);
	if (status == CL_SUCCESS) /* the counters and the paths handed out */
		status = zero_counts(dev, w, 0, RT_STAGE_COUNTERS + 2);
	for (cl_uint every = 1; status == CL_SUCCESS; every = 0) {
		struct stage_read read;
		cl_event read_done = NULL;
		cl_uint started = 0;
		int done = 0;
		/* The logic kernel: over every slot in the piece's first iteration
		   (all are free: the piece before ended its paths), then over the
		   paths that ended, at most those in flight; never over more
		   work-items than fill the device (each loads the scene), which
		   loop over the rest. */
		size_t logic_items = every ? w->slots : w->device_sizes ? w->fill : in_flight;
		if (logic_items > w->fill)
			logic_items = w->fill;

		status = set_common(w, w->kernels[STAGE_LOGIC]);
		if (status == CL_SUCCESS) {
			const void *args[] = {&w->b.image.image, &w->b.sums, &w->item_counts,
					      &w->b.flops, &samples, &every};
			const size_t sizes[] = {sizeof(cl_mem), sizeof(cl_mem), sizeof(cl_mem),
						sizeof(cl_mem), sizeof(cl_uint), sizeof(cl_uint)};
			status = set_rest(w->kernels[STAGE_LOGIC], args, sizes, 6);
		}
		if (status == CL_SUCCESS && logic_items > 0)
			status = enqueue(r, w, STAGE_LOGIC, logic_items, NULL, every ? w->slots : 0,
					 ms);
		/* The read: waited for now, or (device sizes) after the
		 * iteration's other launches are enqueued. */
		int mark = w->pending_count;
		if (status == CL_SUCCESS)
			status = clEnqueueReadBuffer(dev->queue, w->counts, !w->device_sizes, 0,
						     sizeof(read), &read, 0, NULL,
						     w->device_sizes ? &read_done : NULL);
		if (status == CL_SUCCESS && !w->device_sizes) {
			done = take_read(w, &read, total, &recorded, &started);
			in_flight = started;
			for (int k = 0; k < RT_STAGE_KINDS; k++)
				in_flight += read.counts[RT_STAGE_QUEUE_SHADE(k)];
			if (!done)
				status = enqueue_queues(r, w, &read, started, &launched, total, ms);
		} else if (status == CL_SUCCESS) {
			status = enqueue_queues(r, w, NULL, 0, &launched, total, ms);
			if (status == CL_SUCCESS)
				status = clFlush(dev->queue);
			if (status == CL_SUCCESS)
				status = clWaitForEvents(1, &read_done);
			if (status == CL_SUCCESS)
				done = take_read(w, &read, total, &recorded, &started);
		}
		if (read_done)
			clReleaseEvent(read_done);
		if (status == CL_SUCCESS)
			status = collect_times(w, ms, mark);
		if (status == CL_SUCCESS)
			progress_partial(dev, (double)(read.handed_out + started));
		if (done)
			break;
	}
	if (status == CL_SUCCESS) {
		const void *args[] = {&w->b.scene,  NULL,	     &w->b.image.image, &w->b.sums,
				      &w->item_counts, &w->b.flops, &w->b.probe,	&launched};
		const size_t sizes[] = {sizeof(cl_mem), w->local_bytes, sizeof(cl_mem),
					sizeof(cl_mem), sizeof(cl_mem), sizeof(cl_mem),
					sizeof(cl_mem), sizeof(launched)};
		status = set_args(w->kernels[STAGE_FINISH], args, sizes, 8);
	}
	if (status == CL_SUCCESS)
		status = enqueue(r, w, STAGE_FINISH, 0, global2, per_sample, ms);
	if (status == CL_SUCCESS)
		status = clFinish(dev->queue);
	if (status == CL_SUCCESS)
		status = collect_times(w, ms, w->pending_count);
	for (int s = 0; s < STAGE_COUNT; s++) {
		*launches += w->stats->launches[s];
		w->stats->state_bytes[s] =
			w->stats->items[s] * (uint64_t)stages_item_bytes((enum stage)s);
	}
	*launches -= before;
	return status;
}

static int stages_piece(struct renderer *r, const struct rt_piece *piece, struct piece_result *out,
			char *err, size_t err_size)
{
	struct stages *w = r->state;

	out->kernel_ms = 0;
	out->launches = 0;
	cl_int status = trace_piece(r, w, piece, &out->kernel_ms, &out->launches);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "the wavefront's stages on %s failed: %s", r->dev->name,
			 cl_error_name(status));
		return -1;
	}
	return 0;
}

static int stages_read_rows(struct renderer *r, const struct rt_piece *piece, float *to,
			    int packed, char *err, size_t err_size)
{
	struct stages *w = r->state;

	return buffers_read_rows(r->dev, r->settings, &w->b, piece, to, packed, err, err_size);
}

static int stages_read_back(struct renderer *r, char *err, size_t err_size)
{
	struct stages *w = r->state;

	return buffers_read_back(r->dev, r->settings, &w->b, r->result, err, err_size);
}

static int stages_read_sums(struct renderer *r, cl_long *to, size_t first, size_t count,
			    cl_event *event, char *err, size_t err_size)
{
	struct stages *w = r->state;

	return buffers_read_sums(r->dev, &w->b, to, first, count, event, err, err_size);
}

static int stages_aov(struct renderer *r, char *err, size_t err_size)
{
	struct stages *w = r->state;

	return aov_render(r->dev, r->settings, r->result, &w->b, err, err_size);
}

/* Whether the device has 64-bit atomics, which add a path's sample to its
 * pixel's sum while other samples of the pixel are in flight. */
static int has_int64_atomics(const struct device *dev)
{
	char extensions[8192] = "";

	clGetDeviceInfo(dev->id, CL_DEVICE_EXTENSIONS, sizeof(extensions) - 1, extensions, NULL);
	return strstr(extensions, "cl_khr_int64_base_atomics") != NULL;
}

unsigned stages_default_paths(const struct device *dev, unsigned long long paths)
{
	unsigned long long n = STAGES_GPU_PATHS;

	if (!dev->is_gpu && (unsigned long long)dev->compute_units * STAGES_CPU_PATHS_PER_UNIT < n)
		n = (unsigned long long)dev->compute_units * STAGES_CPU_PATHS_PER_UNIT;
	while (n > STAGES_LEAST_DEFAULT && (n * STAGES_PATH_BYTES > dev->global_mem_size / 8 ||
					    n * RT_STAGE_FIELDS * 16 > dev->max_alloc_size))
		n /= 2;
	if (n < STAGES_LEAST_DEFAULT) /* a device that reports no compute units */
		n = STAGES_LEAST_DEFAULT;
	return (unsigned)(paths < n ? paths : n);
}

static int create_buffers(struct device *dev, const struct scene *scene,
			  const struct render_settings *s, struct render_result *res,
			  struct stages *w, char *err, size_t err_size)
{
	size_t pixels = (size_t)s->width * s->height;
	size_t state_bytes = (size_t)w->slots * RT_STAGE_FIELDS * 16;
	size_t queue_bytes = (size_t)w->slots * RT_STAGE_QUEUES * sizeof(cl_uint);
	char what[96];

	if (buffers_create(dev, scene, s, res, &w->b, pixels * sizeof(cl_ulong), "per-pixel counts",
			   err, err_size))
		return -1;
	snprintf(what, sizeof(what), "the path state of %u paths in flight", (unsigned)w->slots);
	if (device_check_fits(dev, what, (double)state_bytes + (double)queue_bytes, err, err_size))
		return -1;
	w->state = device_create_buffer(dev, CL_MEM_READ_WRITE, state_bytes, NULL, what, err,
					err_size);
	if (!w->state)
		return -1;
	w->queues = device_create_buffer(dev, CL_MEM_READ_WRITE, queue_bytes, NULL,
					 "the path queues", err, err_size);
	if (!w->queues)
		return -1;
	w->counts = device_create_buffer(dev, CL_MEM_READ_WRITE,
					 (RT_STAGE_COUNTERS + 2) * sizeof(cl_uint),
					 NULL, "the queue counters", err, err_size);
	if (!w->counts)
		return -1;
	size_t rounded = ((size_t)w->slots + w->local - 1) / w->local * w->local;
	size_t image_items = res->global_size[0] * res->global_size[1];
	w->item_capacity = rounded > image_items ? rounded : image_items;
	w->item_counts = device_create_buffer(
		dev, CL_MEM_READ_WRITE,
		s->count_flops ? w->item_capacity * RT_ITEM_COUNTS * sizeof(cl_ulong)
			       : UNUSED_BUFFER_BYTES,
		NULL, "per-work-item counts", err, err_size);
	if (!w->item_counts)
		return -1;
	/* Every slot starts free (flags 0). */
	cl_uint zero = 0;
	cl_int status = clEnqueueFillBuffer(dev->queue, w->state, &zero, sizeof(zero), 0,
					    state_bytes, 0, NULL, NULL);
	if (status == CL_SUCCESS)
		status = clFinish(dev->queue);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clearing the path state on %s failed: %s", dev->name,
			 cl_error_name(status));
		return -1;
	}
	return 0;
}

static int stages_open(struct renderer *r, const struct scene *scene, char *err, size_t err_size)
{
	struct render_result *res = r->result;
	const struct render_settings *s = r->settings;
	uint64_t paths = (uint64_t)s->width * s->height * (uint64_t)(s->samples > 0 ? s->samples : 1);
	struct stages *w = calloc(1, sizeof(*w));

	if (!w) {
		snprintf(err, err_size, "out of host memory");
		return -1;
	}
	r->state = w;
	if (!has_int64_atomics(r->dev)) {
		snprintf(err, err_size,
			 "--wavefront-form stages adds a pixel's samples with 64-bit atomics, which "
			 "%s lacks (cl_khr_int64_base_atomics); use --wavefront-form bounce",
			 r->dev->name);
		return -1;
	}
	w->stats = calloc(1, sizeof(*w->stats));
	if (!w->stats) {
		snprintf(err, err_size, "out of host memory");
		return -1;
	}
	res->stages = w->stats;
	w->slots = s->paths_in_flight > 0 ? (cl_uint)s->paths_in_flight
					  : (cl_uint)stages_default_paths(r->dev, paths);
	w->stats->slots = (int)w->slots;
	if (launch_setup(r->dev, scene, s, res, &w->b.scene_block, &w->b.program, err, err_size))
		return -1;
	w->local = res->local_size[0] * res->local_size[1];
	const char *sizes = getenv("RTCL_STAGES_LAUNCH");
	w->device_sizes = sizes && strcmp(sizes, "device") == 0;
	/* 2048 work-items a compute unit fill an NVIDIA SM; a CPU's take a few
	   work-groups each. */
	size_t fill = r->dev->is_gpu ? (size_t)r->dev->compute_units * 2048
				     : (size_t)r->dev->compute_units * w->local * 4;
	size_t rounded = ((size_t)w->slots + w->local - 1) / w->local * w->local;
	w->fill = fill < rounded ? (fill + w->local - 1) / w->local * w->local : rounded;
	w->local_bytes = res->scene_in_local ? res->scene_bytes : UNUSED_BUFFER_BYTES;
	for (int i = 0; i < STAGE_COUNT; i++) {
		w->kernels[i] = program_create_kernel(w->b.program, kernel_names[i], err, err_size);
		if (!w->kernels[i])
			return -1;
	}
	double lap = timing_now();
	if (create_buffers(r->dev, scene, s, res, w, err, err_size) ||
	    buffers_clear(r->dev, s, &w->b, err, err_size))
		return -1;
	cl_int status = clSetKernelArg(w->kernels[STAGE_ADVANCE], 0, sizeof(cl_mem), &w->counts);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clSetKernelArg on %s failed: %s", r->dev->name,
			 cl_error_name(status));
		return -1;
	}
	res->times.scene += timing_lap_ms(&lap);
	return 0;
}

static void stages_close(struct renderer *r)
{
	if (r->state)
		release_all(r->state);
	free(r->state);
	r->state = NULL;
}

const struct renderer_ops stages_ops = {stages_open,	  stages_piece,	    NULL,
					stages_read_back, stages_read_rows, stages_read_sums,
					stages_close,	  stages_aov};
