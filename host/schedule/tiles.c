#include "schedule/tiles.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "base/pages.h"
#include "base/test_hooks.h"
#include "render/repeats.h"
#include "base/progress.h"
#include "render/render.h"
#include "base/timing.h"

int tiles_band_rows(const struct render_settings *s, int piece_rows, int devices,
		    enum split split)
{
	int unit = s->workgroup[1] > 0 ? s->workgroup[1] : 1;
	int wanted = (split == SPLIT_DYNAMIC ? TILES_PER_DEVICE : 1) * (devices > 0 ? devices : 1);
	int rows;

	if (piece_rows > 0)
		return piece_rows < s->height ? piece_rows : s->height;
	rows = (s->height + wanted - 1) / wanted;
	/* Whole work-groups: the naive kernel's NDRange covers the band
	 * rounded up, so a band of a group's height wastes no work-items. */
	rows = (rows + unit - 1) / unit * unit;
	return rows < s->height ? rows : s->height;
}

int tiles_row_band(const struct render_settings *s)
{
	return s->workgroup[1] > 0 ? s->workgroup[1] : 8;
}

int tiles_row_classes(const struct device *devs, int count)
{
	int gpus = 0;

	for (int k = 0; k < count; k++)
		gpus += devs[k].is_gpu != 0;
	return gpus > 0 ? gpus : count;
}

void tiles_row_map(struct rt_piece *map, const struct render_settings *s, enum row_order order,
		   int classes)
{
	renderer_interleave_rows(map, s->height, order == ROWS_INTERLEAVE ? tiles_row_band(s) : 0,
				 classes);
}

/* Gives p the job's row map. */
static void apply_rows(const struct tiles_job *t, struct rt_piece *p)
{
	p->row_band = t->row_map.row_band;
	p->row_bands = t->row_map.row_bands;
	p->row_classes = t->row_map.row_classes;
}

int tiles_band_count(int height, int rows)
{
	return (height + rows - 1) / rows;
}

struct rt_piece tiles_band(const struct render_settings *s, int rows, int index, int begin, int end)
{
	int y0 = index * rows;
	int height = s->height - y0 < rows ? s->height - y0 : rows;

	return renderer_rows(s, y0, height, begin, end);
}

struct rt_piece tiles_job_band(const struct tiles_job *t, int index, int begin, int end)
{
	struct rt_piece p = tiles_band(t->settings, t->rows, index, begin, end);

	apply_rows(t, &p);
	return p;
}

void tiles_pack_piece(const struct rt_piece *p, int image_width, const float *from, float *to,
		      int unpack)
{
	size_t row_bytes = 3 * (size_t)p->width * sizeof(float);

	for (int j = 0; j < p->height; j++) {
		size_t image = 3 * ((size_t)rt_piece_row(p, p->y0 + j) * image_width + p->x0);
		size_t packed = 3 * (size_t)j * p->width;
		if (unpack)
			memcpy(to + image, from + packed, row_bytes);
		else
			memcpy(to + packed, from + image, row_bytes);
	}
}

int tiles_piece_launches(const struct render_settings *s, const struct rt_piece *piece, int gpu)
{
	return renderer_pass_count(s, piece, gpu);
}

/* The work-items a device keeps in flight: a GPU about 2048 per compute
 * unit (NVIDIA's SMs), a CPU one work-group per compute unit. */
static double resident_items(const struct device *dev, int group)
{
	return dev->is_gpu ? 2048.0 * dev->compute_units : (double)group * dev->compute_units;
}

/* Each device's smallest piece: TILES_GPU_LAUNCHES times what it keeps in
 * flight for a GPU (one launch's worth for a CPU), but not more than its
 * share of the image by that measure, so that several GPUs all get work. */
static void set_min_pieces(struct tiles_job *t, int group)
{
	double pixels = (double)t->settings->width * t->settings->height, all = 0;

	for (int k = 0; k < t->count; k++)
		all += resident_items(&t->devs[k], group);
	for (int k = 0; k < t->count; k++) {
		double resident = resident_items(&t->devs[k], group);
		double launches = t->devs[k].is_gpu ? TILES_GPU_LAUNCHES : 1;
		double share = pixels * resident / all;
		adapt_set_min_pixels(&t->adapt, k,
				     launches * resident < share ? launches * resident : share);
		adapt_set_fill_pixels(&t->adapt, k, launches * resident);
	}
}

/* The adaptive dispenser's cells: one work-group, so a piece wastes no
 * work-items of the naive kernel's rounded-up NDRange. */
static void init_adaptive(struct tiles_job *t, const struct render_settings *s)
{
	int cell_w = s->workgroup[0] > 0 ? s->workgroup[0] : 8;
	int cell_h = s->workgroup[1] > 0 ? s->workgroup[1] : 8;

	adapt_init(&t->adapt, s->width, s->height, settings_samples(s), cell_w, cell_h, t->count);
	set_min_pieces(t, cell_w * cell_h);
	t->piece_cap = t->adapt.cells_x * t->adapt.cells_y;
	t->piece_count = 0;
}

int tiles_job_init(struct tiles_job *t, const struct scene *scene, const struct render_settings *s,
		   int rows, int adaptive, const struct rt_piece *map, struct device *devs,
		   int count, char *err, size_t err_size)
{
	size_t pixels = (size_t)s->width * s->height;

	memset(t, 0, sizeof(*t));
	t->settings = s;
	t->scene = scene;
	t->devs = devs;
	t->count = count;
	t->rows = rows;
	t->bands = tiles_band_count(s->height, rows);
	t->adaptive = adaptive;
	t->row_map = *map;
	t->piece_cap = t->piece_count = t->bands;
	if (t->piece_cap < count) /* SPLIT_SAMPLES: one piece per device */
		t->piece_cap = count;
	if (adaptive)
		init_adaptive(t, s);
	pthread_mutex_init(&t->lock, NULL);
	pthread_cond_init(&t->asked, NULL);
	t->pieces = malloc((size_t)t->piece_cap * sizeof(*t->pieces));
	t->owner = malloc((size_t)t->piece_cap * sizeof(int));
	t->piece_ms = calloc((size_t)t->piece_cap * 3, sizeof(double));
	t->expected = s->check_writes ? calloc(pixels, sizeof(uint32_t)) : NULL;
	if (!t->pieces || !t->owner || !t->piece_ms || (s->check_writes && !t->expected)) {
		snprintf(err, err_size, "out of host memory for %d pieces", t->piece_cap);
		return -1;
	}
	for (int b = 0; b < t->piece_count; b++) {
		t->pieces[b] = tiles_job_band(t, b, 0, settings_samples(s));
		t->owner[b] = -1;
	}
	return 0;
}

/* Under t->lock: waits, at most TILES_FRONT_WAIT_MS, until the devices that
 * keep more pixels in flight than k have asked for their first piece of the
 * frame (adapt_fronts_asked). Their threads start with k's, so the wait is
 * short; the limit covers a thread that never asks (a failed job). */
static void wait_for_fronts(struct tiles_job *t, int k)
{
	struct timespec until;

	clock_gettime(CLOCK_REALTIME, &until);
	until.tv_nsec += TILES_FRONT_WAIT_MS * 1000000L;
	until.tv_sec += until.tv_nsec / 1000000000L;
	until.tv_nsec %= 1000000000L;
	while (!adapt_fronts_asked(&t->adapt, k))
		if (pthread_cond_timedwait(&t->asked, &t->lock, &until) != 0)
			break;
}

int tiles_take_piece(struct tiles_job *t, int k)
{
	int index = -1;
	struct rt_piece piece;

	pthread_mutex_lock(&t->lock);
	wait_for_fronts(t, k);
	if (t->piece_count < t->piece_cap && adapt_take(&t->adapt, k, timing_now() * 1e3, &piece)) {
		apply_rows(t, &piece);
		index = t->piece_count++;
		t->pieces[index] = piece;
		t->owner[index] = k;
	}
	pthread_cond_broadcast(&t->asked);
	pthread_mutex_unlock(&t->lock);
	return index;
}

void tiles_job_free(struct tiles_job *t)
{
	for (int k = 0; k < t->count; k++) {
		if (t->dev[k].open)
			renderer_close(&t->dev[k].renderer);
		render_result_free(&t->dev[k].result);
		pages_free(t->dev[k].block, t->sums_header);
		device_pinned_free(&t->devs[k], t->dev[k].pinned, t->dev[k].sums);
		t->dev[k].pinned = NULL;
		t->dev[k].block = NULL;
		t->dev[k].sums = NULL;
		t->dev[k].open = 0;
	}
	free(t->owner);
	free(t->pieces);
	free(t->piece_ms);
	t->piece_ms = NULL;
	free(t->expected);
	t->owner = NULL;
	t->pieces = NULL;
	t->expected = NULL;
	pthread_mutex_destroy(&t->lock);
	pthread_cond_destroy(&t->asked);
}

int tiles_alloc_sums(struct tiles_job *t, int k, char *err, size_t err_size)
{
	size_t bytes = t->sums_header + image_sum_bytes(t->settings->width, t->settings->height);
	struct tiles_device *d = &t->dev[k];

	if (d->block || d->pinned)
		return 0;
	/* One process: pinned memory, where the device reads back at the
	 * speed of its link (under --mpi the sums travel behind a header). */
	if (t->sums_header == 0 && t->dev[k].open) {
		d->sums = device_pinned_alloc(&t->devs[k], bytes, &d->pinned);
		if (d->sums) {
			memset(d->sums, 0, bytes); /* mapped now, not in the first frame */
			return 0;
		}
	}
	d->block = pages_alloc(t->sums_header, bytes - t->sums_header);
	if (!d->block) {
		snprintf(err, err_size, "out of host memory for the sample sums of a %dx%d image",
			 t->settings->width, t->settings->height);
		return -1;
	}
	memset(d->block, 0, bytes); /* zeroes and maps it (not merged into calloc) */
	d->sums = (cl_long *)(d->block + t->sums_header);
	return 0;
}

static void expect_writes(struct tiles_job *t, int k, const struct rt_piece *p, int sign);

/* For the default split (tiles_prefer_samples), before the clock: one pass
 * of the whole image, its first tiles_sample_unit samples, twice, the
 * faster counting with its profiled kernels (a first pass may pay once for
 * what the frames' do not), and a read-back of all the sums, each timed (the
 * read-back twice, the faster kept). The passes leave sums that the render's
 * first pass over each pixel replaces (it starts the buffer's samples) and
 * no image; with check_writes their launches are expected in the counts. */
static int probe_device(struct tiles_job *t, int k, char *err, size_t err_size)
{
	const struct render_settings *s = t->settings;
	struct tiles_device *d = &t->dev[k];
	int unit = tiles_sample_unit(s, t->devs, t->count);
	struct rt_piece pass = renderer_whole_image(s, 0, unit < settings_samples(s) ? unit : 1);
	struct piece_result out;
	double lap = timing_now();

	for (int i = 0; i < 2; i++) {
		if (renderer_all_samples(&d->renderer, &pass, &out, err, err_size))
			return -1;
		double ms = timing_lap_ms(&lap);
		if (i == 0 || ms < d->probe_ms) {
			d->probe_ms = ms;
			d->probe_kernel_ms = out.kernel_ms;
		}
		pthread_mutex_lock(&t->lock); /* the devices' threads probe at once */
		expect_writes(t, k, &pass, 1);
		pthread_mutex_unlock(&t->lock);
	}
	/* Each pass writes a pixel once: a wavefront pass is several launches. */
	d->probe_passes = 2 * tiles_piece_launches(s, &pass, t->devs[k].is_gpu);
	/* Twice, the faster counting: a first transfer may pay once for what
	 * a frame's does not (the pinned memory's first use). */
	for (int i = 0; i < 2; i++) {
		if (renderer_read_sums(&d->renderer, d->sums, err, err_size))
			return -1;
		hook_sums_delay();
		double ms = timing_lap_ms(&lap);
		d->sums_ms = i == 0 || ms < d->sums_ms ? ms : d->sums_ms;
	}
	return 0;
}

int tiles_open(struct tiles_job *t, int k, char *err, size_t err_size)
{
	struct tiles_device *d = &t->dev[k];

	if (d->open)
		return 0;
	if (renderer_open(&d->renderer, &t->devs[k], t->scene, t->settings, &d->result, err,
			  err_size))
		return -1;
	d->open = 1;
	/* SPLIT_SAMPLES: the host copy of its sums, touched now, before the
	 * frames' clock, not in the frame that first reads into it. */
	if (t->by_samples && tiles_alloc_sums(t, k, err, err_size))
		return -1;
	return t->probe ? probe_device(t, k, err, err_size) : 0;
}

/* Adds piece's launches to the expected write counts (check_writes). */
static void expect_writes(struct tiles_job *t, int k, const struct rt_piece *p, int sign)
{
	int launches = tiles_piece_launches(t->settings, p, t->devs[k].is_gpu) * sign;

	for (int v = p->y0; t->expected && v < p->y0 + p->height; v++)
		for (int x = p->x0; x < p->x0 + p->width; x++)
			t->expected[(size_t)rt_piece_row(p, v) * t->settings->width + x] += launches;
}

/* SPLIT_SAMPLES: reads device k's sums into its host copy, as part of the
 * frame (the image is not done before). */
static int read_sums(struct tiles_job *t, int k, char *err, size_t err_size)
{
	return renderer_read_sums(&t->dev[k].renderer, t->dev[k].sums, err, err_size);
}

int tiles_render_band(struct tiles_job *t, int k, int band, struct piece_work *done, char *err,
		      size_t err_size)
{
	struct rt_piece whole;
	struct piece_result out;

	/* Adaptive: other threads add pieces meanwhile, under the lock; this
	 * one's index was handed out already. */
	int known = t->adaptive ? t->piece_cap : t->piece_count;

	if (band < 0 || band >= known) {
		snprintf(err, err_size, "internal error: piece %d of %d", band, known);
		return -1;
	}
	whole = t->pieces[band];
	double start = timing_now();
	/* Every sample of the piece on this device, in order: the running
	 * sums stay in its buffer. */
	if (renderer_all_samples(&t->dev[k].renderer, &whole, &out, err, err_size))
		return -1;
	if (t->by_samples && !t->sums_later && read_sums(t, k, err, err_size))
		return -1;
	t->piece_ms[3 * band] = (start - t->frame_start) * 1e3;
	t->piece_ms[3 * band + 1] = (timing_now() - t->frame_start) * 1e3;
	t->piece_ms[3 * band + 2] = out.kernel_ms;
	done->kernel_ms += out.kernel_ms;
	done->launches += out.launches;
	t->owner[band] = k; /* pieces are distinct: no two threads write one */
	if (t->by_samples)
		__atomic_add_fetch(&t->frame_samples, out.samples, __ATOMIC_RELAXED);
	expect_writes(t, k, &whole, 1);
	/* A range of every pixel's samples counts as that share of the pixels. */
	done->pixels += (long long)((double)whole.width * whole.height *
					    (whole.sample_end - whole.sample_begin) / whole.samples +
				    0.5);
	return 0;
}

int tiles_collect(struct tiles_job *t, int k, char *err, size_t err_size)
{
	struct tiles_device *d = &t->dev[k];

	if (d->collected)
		return 0;
	if (renderer_read_back(&d->renderer, err, err_size))
		return -1;
	if (t->settings->check_writes && !d->result.guards_intact) {
		snprintf(err, err_size, "internal error: a kernel wrote outside the image");
		return -1;
	}
	d->collected = 1;
	return 0;
}

void tiles_copy_rows(const struct rt_piece *p, int image_width, const float *from, float *to)
{
	for (int v = p->y0; v < p->y0 + p->height; v++) {
		size_t first = 3 * ((size_t)rt_piece_row(p, v) * image_width + p->x0);
		memcpy(to + first, from + first, 3 * (size_t)p->width * sizeof(float));
	}
}

void tiles_copy_piece(const struct tiles_job *t, int piece, const struct render_result *from,
		      struct render_result *to)
{
	const struct rt_piece *p = &t->pieces[piece];

	tiles_copy_rows(p, t->settings->width, from->rgb, to->rgb);
	if (!from->pixel_flops || !to->pixel_flops)
		return;
	for (int v = p->y0; v < p->y0 + p->height; v++) {
		size_t first = (size_t)rt_piece_row(p, v) * t->settings->width + p->x0;
		memcpy(to->pixel_flops + first, from->pixel_flops + first,
		       (size_t)p->width * sizeof(uint64_t));
	}
}

int tiles_check_counts(const uint32_t *counts, int width, int height, uint32_t expected, char *err,
		       size_t err_size)
{
	for (int y = 0; y < height; y++)
		for (int x = 0; x < width; x++)
			if (counts[(size_t)y * width + x] != expected) {
				snprintf(err, err_size,
					 "internal error: pixel (%d, %d) of a band was written %u "
					 "times, not %u",
					 x, y, counts[(size_t)y * width + x], expected);
				return -1;
			}
	return 0;
}

/* RTCL_TEST_DOUBLE_BAND=1 (base/test_hooks.h): piece 0 rendered once more by another
 * device, as a dispenser that handed it out twice would (unknowingly: not
 * in the expected counts). */
static int double_band(struct tiles_job *t, char *err, size_t err_size)
{
	int owner = t->owner[0];
	struct piece_work pixels = {0};

	if (!hook_double_band())
		return 0;
	int other = (owner + 1) % t->count;
	if (tiles_render_band(t, other, 0, &pixels, err, err_size))
		return -1;
	expect_writes(t, other, &t->pieces[0], -1);
	t->owner[0] = owner;
	return 0;
}

int tiles_check_device(const struct tiles_job *t, int k, char *err, size_t err_size)
{
	const struct render_settings *s = t->settings;
	const uint32_t *counts = t->dev[k].result.write_counts;
	/* Set-up's probe (probe_device) wrote every pixel too. */
	uint32_t probed = (uint32_t)t->dev[k].probe_passes;

	if (counts && t->by_samples) { /* every pixel, once a pass of its pieces */
		uint32_t expected = probed;
		for (int b = 0; b < t->piece_count; b++)
			if (t->owner[b] == k)
				expected += (uint32_t)tiles_piece_launches(s, &t->pieces[b],
									    t->devs[k].is_gpu);
		return tiles_check_counts(counts, s->width, s->height, expected, err, err_size);
	}
	for (int b = 0; counts && b < t->piece_count; b++) {
		const struct rt_piece *p = &t->pieces[b];
		uint32_t expected =
			probed +
			(t->owner[b] == k ? (uint32_t)tiles_piece_launches(s, p, t->devs[k].is_gpu)
					  : 0);
		for (int v = p->y0; v < p->y0 + p->height; v++)
			if (tiles_check_counts(counts + (size_t)rt_piece_row(p, v) * s->width + p->x0,
					       p->width, 1,
					       expected, err, err_size))
				return -1;
	}
	return 0;
}

/* ---- one image on several devices of this process ----------------------- */

static int open_tile_device(void *context, int k, char *err, size_t err_size)
{
	return tiles_open(context, k, err, err_size);
}

static int render_band(void *context, int k, int band, struct piece_work *done, char *err,
		       size_t err_size)
{
	return tiles_render_band(context, k, band, done, err, err_size);
}

static int take_tile_piece(void *context, int k)
{
	return tiles_take_piece(context, k);
}

/* Every pixel written once per launch of the piece that covered it in each
 * frame, over all devices together: the sum of the devices' counts against
 * what the pieces handed out add up to (check_writes). */
static int check_summed_counts(const struct tiles_job *t, uint32_t *sum, char *err, size_t err_size)
{
	const struct render_settings *s = t->settings;
	size_t pixels = (size_t)s->width * s->height;

	for (int k = 0; k < t->count; k++)
		for (size_t i = 0; i < pixels; i++)
			sum[i] += t->dev[k].result.write_counts[i];
	for (size_t i = 0; i < pixels; i++) {
		if (sum[i] == t->expected[i] && sum[i] > 0)
			continue;
		if (t->expected[i] == 0)
			snprintf(err, err_size, "internal error: pixel (%d, %d) is in no piece",
				 (int)(i % s->width), (int)(i / s->width));
		else
			snprintf(err, err_size,
				 "internal error: pixel (%d, %d) of a band was written %u times, "
				 "not %u",
				 (int)(i % s->width), (int)(i / s->width), sum[i], t->expected[i]);
		return -1;
	}
	return 0;
}

/* The per-work-item counts of every device, one after the other. */
static int join_item_counts(const struct tiles_job *t, struct render_result *out)
{
	size_t n = 0;

	for (int k = 0; k < t->count; k++)
		n += t->dev[k].result.item_count;
	out->item_flops = calloc(n ? n : 1, sizeof(uint64_t));
	if (!out->item_flops)
		return -1;
	for (int k = 0; k < t->count; k++) {
		const struct render_result *r = &t->dev[k].result;
		memcpy(out->item_flops + out->item_count, r->item_flops,
		       r->item_count * sizeof(uint64_t));
		out->item_count += r->item_count;
		out->total_flops += r->total_flops;
		out->total_rays += r->total_rays;
		out->total_node_visits += r->total_node_visits;
		out->total_leaf_visits += r->total_leaf_visits;
		out->total_prim_tests += r->total_prim_tests;
		out->simd_measured |= r->simd_measured;
		for (int p = 0; p < RT_SIMD_PHASES; p++) {
			out->lane_steps[p] += r->lane_steps[p];
			out->warp_steps[p] += r->warp_steps[p];
		}
		path_counts_merge(&out->paths, &r->paths);
	}
	return 0;
}

void tiles_copy_facts(const struct render_result *from, struct render_result *to)
{
	memcpy(to->groups, from->groups, sizeof(to->groups));
	memcpy(to->global_size, from->global_size, sizeof(to->global_size));
	memcpy(to->local_size, from->local_size, sizeof(to->local_size));
	to->scene_in_local = from->scene_in_local;
	to->queues = from->queues;
	to->scene_bytes = from->scene_bytes;
	memcpy(to->build_options, from->build_options, sizeof(to->build_options));
	to->times.build = from->times.build;
	to->times.scene = from->times.scene;
	to->bvh_nodes = from->bvh_nodes;
	to->bvh_width = from->bvh_width;
	to->bvh_device_nodes = from->bvh_device_nodes;
	to->bvh_depth = from->bvh_depth;
	to->bvh_sah_cost = from->bvh_sah_cost;
	to->bvh_build_ms = from->bvh_build_ms;
	to->bvh_bytes = from->bvh_bytes;
}

/* The last frame's pieces into out (render_result's piece records). */
static int record_pieces(const struct tiles_job *t, struct render_result *out)
{
	out->pieces = calloc((size_t)(t->piece_count ? t->piece_count : 1), sizeof(*out->pieces));
	if (!out->pieces)
		return -1;
	for (int b = 0; b < t->piece_count; b++)
		out->pieces[b] = (struct piece_record){.piece = t->pieces[b],
						       .device = t->owner[b],
						       .start_ms = t->piece_ms[3 * b],
						       .end_ms = t->piece_ms[3 * b + 1],
						       .kernel_ms = t->piece_ms[3 * b + 2]};
	out->piece_count = t->piece_count;
	return 0;
}

/* Part of combine_sums: pixels [begin, end) of the parts' sums. */
struct sums_range {
	const cl_long *const *parts;
	int count;
	cl_long *to;
	float *rgb;
	float scale;
	size_t begin, end;
};

static void *combine_range(void *arg)
{
	const struct sums_range *r = arg;

	/* One part's sums into `to`: a copy (--mpi's first device's sums into
	 * its rank's slot), which memcpy makes with streaming stores where the
	 * range is large, not reading `to` first as the loop's stores do. */
	if (r->count == 1 && r->to && !r->rgb) {
		memcpy(r->to + 4 * r->begin, r->parts[0] + 4 * r->begin,
		       4 * sizeof(cl_long) * (r->end - r->begin));
		return NULL;
	}
	for (size_t i = r->begin; i < r->end; i++) {
		cl_long sum[4] = {0, 0, 0, 0};
		for (int k = 0; k < r->count; k++) {
			const cl_long *part = r->parts[k] + 4 * i;
			sum[0] += part[0];
			sum[1] += part[1];
			sum[2] += part[2];
			sum[3] |= part[3];
		}
		if (r->to)
			memcpy(r->to + 4 * i, sum, sizeof(sum));
		for (int c = 0; r->rgb && c < 3; c++)
			r->rgb[3 * i + c] = sum[3] & (1 << c) ? INFINITY : (float)sum[c] * r->scale;
	}
	return NULL;
}

/* The sum of `count` parts' sums of `pixels` pixels (4 cl_long each, as the
 * kernels leave them: cl/sample.cl) into to and/or their means into rgb,
 * over up to TILES_SUM_THREADS threads (a 2000 x 2000 image is 4 million
 * pixels' sums; on two H200s' host the image was assembled in 10-13 ms, 139
 * ms on one thread with both images read back first). */
static void combine_on(const cl_long *const *parts, int count, cl_long *to, float *rgb,
		       float scale, size_t pixels, int threads)
{
	struct sums_range ranges[TILES_SUM_THREADS];
	pthread_t ids[TILES_SUM_THREADS];
	int started[TILES_SUM_THREADS] = {0};

	threads = threads < 1 ? 1 : threads > TILES_SUM_THREADS ? TILES_SUM_THREADS : threads;
	if (pixels < ((size_t)1 << 14))
		threads = 1;
	for (int i = 0; i < threads; i++) {
		ranges[i] = (struct sums_range){parts, count, to, rgb, scale, pixels * i / threads,
						pixels * (i + 1) / threads};
		started[i] = i > 0 && pthread_create(&ids[i], NULL, combine_range, &ranges[i]) == 0;
	}
	for (int i = 0; i < threads; i++)
		if (!started[i]) /* the first, and any the system would not start */
			combine_range(&ranges[i]);
	for (int i = 1; i < threads; i++)
		if (started[i])
			pthread_join(ids[i], NULL);
}

static void combine_sums(const cl_long *const *parts, int count, cl_long *to, float *rgb,
			 float scale, size_t pixels)
{
	long cores = sysconf(_SC_NPROCESSORS_ONLN);

	combine_on(parts, count, to, rgb, scale, pixels, cores < 1 ? 1 : (int)cores);
}

void tiles_sum_parts(const cl_long *const *parts, int count, cl_long *to, size_t pixels,
		     int threads)
{
	combine_on(parts, count, to, NULL, 0, pixels, threads);
}

void tiles_add_sums(cl_long *to, const cl_long *from, size_t pixels)
{
	const cl_long *parts[2] = {to, from};

	combine_sums(parts, 2, to, NULL, 0, pixels);
}

void tiles_mean_of_parts(const struct render_settings *s, const cl_long *const *parts, int count,
			 float *rgb)
{
	combine_sums(parts, count, NULL, rgb, settings_mean_scale(settings_samples(s)),
		     (size_t)s->width * s->height);
}

void tiles_mean_of_sums(const struct render_settings *s, const cl_long *sums, float *rgb)
{
	combine_sums(&sums, 1, NULL, rgb, settings_mean_scale(settings_samples(s)),
		     (size_t)s->width * s->height);
}

/* SPLIT_SAMPLES: the image from the devices' sums of the last frame, the
 * mean of the samples they traced (all, or fewer when stopped). */
static void add_sums(const struct tiles_job *t, float *rgb)
{
	const cl_long *parts[DEVICES_MAX];

	for (int k = 0; k < t->count; k++)
		parts[k] = t->dev[k].sums;
	combine_sums(parts, t->count, NULL, rgb, settings_mean_scale(t->frame_samples),
		     (size_t)t->settings->width * t->settings->height);
}

/* Reads every device back and assembles the image (and counts) in out. */
static int assemble(struct tiles_job *t, struct render_result *out, char *err, size_t err_size)
{
	const struct render_settings *s = t->settings;
	size_t pixels = (size_t)s->width * s->height;

	out->rgb = malloc(image_float_bytes(s->width, s->height));
	out->pixel_flops = s->count_flops ? malloc(pixels * sizeof(uint64_t)) : NULL;
	out->write_counts = s->check_writes ? calloc(pixels, sizeof(uint32_t)) : NULL;
	if (!out->rgb || (s->count_flops && !out->pixel_flops) ||
	    (s->check_writes && !out->write_counts)) {
		snprintf(err, err_size, "out of host memory for a %dx%d image", s->width,
			 s->height);
		return -1;
	}
	/* Split samples leave no image on the devices: only the write counts
	 * and guards, when checked, are read. */
	for (int k = 0; k < t->count && (!t->by_samples || s->check_writes); k++)
		if (tiles_collect(t, k, err, err_size))
			return -1;
	if (t->by_samples)
		add_sums(t, out->rgb);
	else
		for (int b = 0; b < t->piece_count; b++)
			tiles_copy_piece(t, b, &t->dev[t->owner[b]].result, out);
	if (s->count_flops && join_item_counts(t, out)) {
		snprintf(err, err_size, "out of host memory for the flop counts");
		return -1;
	}
	if (record_pieces(t, out)) {
		snprintf(err, err_size, "out of host memory for %d pieces' records", t->piece_count);
		return -1;
	}
	out->guards_intact = 1;
	tiles_copy_facts(&t->dev[0].result, out);
	return s->check_writes ? check_summed_counts(t, out->write_counts, err, err_size) : 0;
}

int tiles_open_all(struct tiles_job *t, struct device_work *setup, char *err, size_t err_size)
{
	struct multidev_job job = {.piece_count = 0,
				   .split = SPLIT_STATIC,
				   .begin = open_tile_device,
				   .render_piece = render_band,
				   .context = t};

	return multidev_run(&job, t->devs, t->count, setup, err, err_size);
}

int tiles_split_samples(struct tiles_job *t, int total, int unit, const double *rate)
{
	const struct render_settings *s = t->settings;
	int n = settings_samples(s);
	double weight_sum = 0, sum = 0;

	if (total > t->piece_cap) {
		struct rt_piece *pieces = realloc(t->pieces, (size_t)total * sizeof(*pieces));
		if (pieces)
			t->pieces = pieces;
		int *owner = realloc(t->owner, (size_t)total * sizeof(int));
		if (owner)
			t->owner = owner;
		double *ms = realloc(t->piece_ms, (size_t)total * 3 * sizeof(double));
		if (ms)
			t->piece_ms = ms;
		if (!pieces || !owner || !ms)
			return -1;
		memset(t->piece_ms, 0, (size_t)total * 3 * sizeof(double));
		t->piece_cap = total;
	}
	if ((n + unit - 1) / unit < total)
		unit = 1; /* tiles_samples_fit: n >= total */
	int units = (n + unit - 1) / unit, first = 0;
	for (int k = 0; k < total; k++)
		weight_sum += rate ? rate[k] : 1;
	for (int k = 0; k < total; k++) {
		sum += rate ? rate[k] : 1;
		int end = k == total - 1 ? units : (int)(units * sum / weight_sum + 0.5);
		if (end < first + 1)
			end = first + 1;
		if (end > units - (total - 1 - k))
			end = units - (total - 1 - k);
		int begin = first * unit, stop = end * unit < n ? end * unit : n;
		t->pieces[k] = renderer_whole_image(s, begin, stop);
		t->pieces[k].sum_begin = begin;
		t->owner[k] = -1;
		first = end;
	}
	t->piece_count = total;
	t->by_samples = 1;
	return 0;
}

int tiles_sample_unit(const struct render_settings *s, const struct device *devs, int count)
{
	int unit = 1;

	for (int k = 0; k < count; k++) {
		int pass = renderer_pass_samples(s, (long long)s->width * s->height,
						 devs[k].is_gpu);
		unit = pass > unit ? pass : unit;
	}
	return unit;
}

/* SPLIT_SAMPLES in this process: device k's range is piece k, shared by the
 * rates of the last frame (equal in the first). */
static void split_samples(struct tiles_job *t)
{
	int known = 1;

	for (int k = 0; k < t->count; k++)
		known &= t->sample_rate[k] > 0;
	/* The pieces hold one per device already (tiles_job_init). */
	tiles_split_samples(t, t->count, tiles_sample_unit(t->settings, t->devs, t->count),
			    known ? t->sample_rate : NULL);
	for (int k = 0; k < t->count; k++)
		t->owner[k] = k;
}

/* The frames (a warm-up and -r N timed ones, or one), each every band over
 * every device; each frame's wall time recorded in out. Returns the frames
 * rendered, or -1. */
static int render_tile_frames(struct tiles_job *t, int split_static, struct device_work *work,
			      struct render_result *out, char *err, size_t err_size)
{
	struct multidev_job job = {.piece_count = t->by_samples ? t->count : t->bands,
				   .split = split_static ? SPLIT_STATIC : SPLIT_DYNAMIC,
				   .render_piece = render_band,
				   .take_piece = t->adaptive ? take_tile_piece : NULL,
				   .context = t};
	int frames = repeats_begin(t->settings, out, err, err_size);
	char devices[32];

	snprintf(devices, sizeof(devices), "%d device%s", t->count, t->count == 1 ? "" : "s");
	/* The line is the caller's without progress (--frames' last frames,
	 * render_shared_frames), as for render(). */
	if (frames > 0 && t->settings->progress)
		repeats_progress_begin(t->settings, frames, devices);
	for (int f = 0; f < frames; f++) {
		double start = timing_now();
		t->frame_start = start;
		if (t->settings->progress)
			repeats_progress_step(t->settings, out, f, frames);
		if (t->adaptive) {
			adapt_new_frame(&t->adapt);
			t->piece_count = 0;
		}
		if (t->by_samples)
			split_samples(t);
		t->frame_samples = 0;
		if (multidev_run(&job, t->devs, t->count, work, err, err_size))
			return -1;
		/* The next frame's split: each device's samples over its busy
		 * time in all frames so far: one frame's rates are noisy (on four
		 * H100s, batch 95, they moved the shares by up to 5 passes of 4
		 * samples a frame and left one GPU 25 ms behind the others). */
		for (int k = 0; t->by_samples && k < t->count; k++) {
			if (work[k].last_piece_ms <= 0)
				continue;
			t->samples_done[k] += t->pieces[k].sample_end - t->pieces[k].sample_begin;
			t->samples_ms[k] += work[k].last_piece_ms;
			t->sample_rate[k] = t->samples_done[k] / t->samples_ms[k];
		}
		double wall_ms = (timing_now() - start) * 1e3;
		repeats_record(out, f, frames, wall_ms, wall_ms);
	}
	return frames;
}

int tiles_adaptive(enum split split, int piece_rows)
{
	return split == SPLIT_DYNAMIC && piece_rows <= 0;
}


int tiles_check_sample_split(const struct render_settings *s, int count, char *err,
			     size_t err_size)
{
	int n = settings_samples(s);

	if (n >= 2 && n >= count)
		return 0;
	snprintf(err, err_size,
		 "--split samples shares each pixel's samples between the %d devices: it needs "
		 "at least %d samples per pixel (--spp or image.samples), and this render has %d",
		 count, count > 2 ? count : 2, n);
	return -1;
}

int tiles_samples_fit(const struct render_settings *s, int count, int piece_rows)
{
	return tiles_check_sample_split(s, count, NULL, 0) == 0 && !settings_instrumented(s) &&
	       piece_rows <= 0;
}

int tiles_choose_split(const struct tiles_request *r, const struct render_settings *s, int given,
		       enum split *split, int *measure, char *err, size_t err_size)
{
	int gpus = 0;

	*split = r->split;
	*measure = 0;
	if (r->split == SPLIT_SAMPLES)
		return tiles_check_sample_split(s, r->count, err, err_size);
	for (int k = 0; k < r->count; k++)
		gpus += r->devs[k].is_gpu != 0 || hook_devices_as_gpus();
	if (!given && r->count >= 2 && gpus == r->count &&
	    tiles_samples_fit(s, r->count, r->piece_rows)) {
		*split = SPLIT_SAMPLES;
		*measure = 1;
	}
	return 0;
}

int tiles_prefer_samples(const double *pass_ms, const double *kernel_ms, const double *sums_ms,
			 int count, int pass_samples, int samples, double add_ms, double move_ms,
			 struct split_choice *c)
{
	double rate = 0; /* samples of the whole image per ms, all devices */
	double host = 0; /* the slowest device's pass beyond its kernels */

	memset(c, 0, sizeof(*c));
	c->measured = 1;
	c->pass_samples = pass_samples;
	for (int k = 0; k < count; k++) {
		c->pass_ms = pass_ms[k] > c->pass_ms ? pass_ms[k] : c->pass_ms;
		c->sums_ms = sums_ms[k] > c->sums_ms ? sums_ms[k] : c->sums_ms;
		rate += pass_ms[k] > 0 ? pass_samples / pass_ms[k] : 0;
		/* No profiled kernels (0): nothing known beyond them. */
		double beyond = kernel_ms[k] > 0 ? pass_ms[k] - kernel_ms[k] : 0;
		host = beyond > host ? beyond : host;
	}
	c->add_ms = add_ms;
	c->render_ms = rate > 0 ? samples / rate : 0;
	c->overhead_ms = count > 0 && pass_samples > 0
				 ? host * ((double)samples / pass_samples) * (1 - 1.0 / count)
				 : 0;
	c->move_ms = move_ms;
	c->penalty_ms = TILES_SHARE_PENALTY * c->render_ms + c->overhead_ms + c->move_ms;
	return c->sums_ms + c->add_ms <= c->penalty_ms;
}

/* For the default split, after the probes: times the host's add of the
 * devices' sums (what the probes left) into an image, which the sample
 * split does once after its frames. Returns 0, or -1 with one message in
 * err. */
static int time_add(struct tiles_job *t, char *err, size_t err_size)
{
	const struct render_settings *s = t->settings;
	size_t bytes = image_float_bytes(s->width, s->height);
	float *rgb = malloc(bytes);

	if (!rgb) {
		snprintf(err, err_size, "out of host memory for a %dx%d image", s->width, s->height);
		return -1;
	}
	memset(rgb, 0, bytes);
	pages_touch(rgb, bytes); /* the image's own pages are touched before the clock too */
	double lap = timing_now();
	add_sums(t, rgb);
	t->add_ms = timing_lap_ms(&lap);
	free(rgb);
	return 0;
}

/* r->measure: keeps the sample split if the probes favour it
 * (tiles_prefer_samples), else turns t into the dynamic split's adaptive
 * job, as tiles_job_init would have made it. */
static void choose_by_probes(struct tiles_request *r, struct tiles_job *t)
{
	double pass_ms[DEVICES_MAX], kernel_ms[DEVICES_MAX], sums_ms[DEVICES_MAX];
	const struct render_settings *s = t->settings;
	int unit = tiles_sample_unit(s, t->devs, t->count);

	for (int k = 0; k < t->count; k++) {
		pass_ms[k] = t->dev[k].probe_ms;
		kernel_ms[k] = t->dev[k].probe_kernel_ms;
		sums_ms[k] = t->dev[k].sums_ms;
	}
	if (tiles_prefer_samples(pass_ms, kernel_ms, sums_ms, t->count,
				 unit < settings_samples(s) ? unit : 1, settings_samples(s), t->add_ms,
				 0, &r->choice)) {
		t->adaptive = 0;
		return;
	}
	r->split = SPLIT_DYNAMIC;
	t->adaptive = 1; /* tiles_render made the job adaptive for this */
	tiles_drop_sums(t);
}

void tiles_drop_sums(struct tiles_job *t)
{
	t->by_samples = 0;
	t->probe = 0;
	for (int k = 0; k < t->count; k++) { /* no sums to read */
		device_pinned_free(&t->devs[k], t->dev[k].pinned, t->dev[k].sums);
		pages_free(t->dev[k].block, t->sums_header);
		t->dev[k].pinned = NULL;
		t->dev[k].block = NULL;
		t->dev[k].sums = NULL;
	}
}

int tiles_render(struct tiles_request *r, const struct render_settings *s,
		 struct device_work *work, struct render_result *out, char *err, size_t err_size)
{
	struct device_work setup[DEVICES_MAX];
	struct tiles_job t;
	int rows = tiles_band_rows(s, r->piece_rows, r->count, r->split), frames;
	struct rt_piece map = {0};

	memset(out, 0, sizeof(*out));
	tiles_row_map(&map, s, r->row_order,
		      r->row_classes ? r->row_classes : tiles_row_classes(r->devs, r->count));
	/* A split still to be measured may turn out the dynamic one: adaptive
	 * until then (the pieces' room is the cells', enough for either). */
	if (tiles_job_init(&t, r->scene, s, rows,
			   r->measure || tiles_adaptive(r->split, r->piece_rows), &map,
			   r->devs, r->count, err, err_size))
		return -1;
	t.by_samples = r->split == SPLIT_SAMPLES;
	t.probe = r->measure && t.by_samples; /* in tiles_open, before the clock */
	if (tiles_open_all(&t, setup, err, err_size))
		goto out_free;
	if (t.probe) {
		if (time_add(&t, err, err_size))
			goto out_free;
		choose_by_probes(r, &t);
		r->measure = 0; /* once per request: another render keeps the choice */
	}
	double lap = timing_now();
	frames = render_tile_frames(&t, r->split != SPLIT_DYNAMIC, work, out, err, err_size);
	if (s->progress)
		progress_end();
	if (frames < 0 || repeats_end(out, err, err_size) || double_band(&t, err, err_size))
		goto out_free;
	out->times.kernels = timing_lap_ms(&lap);
	out->passes = tiles_piece_launches(s, &t.pieces[0], t.devs[t.owner[0]].is_gpu);
	out->samples_done = t.by_samples ? t.frame_samples : settings_samples(s);
	out->passes_done = out->passes;
	if (assemble(&t, out, err, err_size))
		goto out_free;
	out->times.read_back = timing_lap_ms(&lap);
	for (int k = 0; k < r->count; k++)
		work[k].setup_ms = setup[k].setup_ms;
	tiles_job_free(&t);
	return 0;

out_free:
	tiles_job_free(&t);
	render_result_free(out);
	return -1;
}
