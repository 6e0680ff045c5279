/* A renderer of pieces (renderer.h): hands each to the chosen kernel's
 * functions (singlepass.c or wavefront.c), and the passes that cover every
 * sample of a piece. */
#include "render/renderer.h"
#include "render/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/interrupt.h"
#include "base/progress.h"
#include "base/timing.h"
#include "render/stages.h"

int renderer_open(struct renderer *r, struct device *dev, const struct scene *scene,
		  const struct render_settings *s, struct render_result *res, char *err,
		  size_t err_size)
{
	memset(r, 0, sizeof(*r));
	memset(res, 0, sizeof(*res));
	r->ops = s->wavefront_stages ? &stages_ops : s->kernel->ops;
	r->dev = dev;
	r->settings = s;
	r->result = res;
	r->queues = renderer_queues(s, dev);
	res->queues = 1;
	if (render_check_integrator(scene, s, err, err_size))
		return -1;
	if (r->ops->open(r, scene, err, err_size) == 0)
		return 0;
	r->ops->close(r);
	return -1;
}

int renderer_piece(struct renderer *r, const struct rt_piece *p, struct piece_result *out,
		   char *err, size_t err_size)
{
	const struct render_settings *s = r->settings;
	int samples = settings_samples(s);

	if (p->x0 < 0 || p->y0 < 0 || p->width < 1 || p->height < 1 ||
	    p->width > s->width - p->x0 || p->height > s->height - p->y0 || p->samples != samples ||
	    p->sample_begin < 0 || p->sample_end <= p->sample_begin || p->sample_end > samples ||
	    (p->row_band && (p->row_band < 1 || p->row_bands > s->height / p->row_band ||
			     p->row_classes < 2 || p->row_classes > p->row_bands))) {
		snprintf(err, err_size,
			 "internal error: piece %dx%d at (%d, %d), samples [%d, %d) of %d, does "
			 "not fit a %dx%d image of %d samples per pixel",
			 p->width, p->height, p->x0, p->y0, p->sample_begin, p->sample_end,
			 p->samples, s->width, s->height, samples);
		return -1;
	}
	if (r->ops->piece(r, p, out, err, err_size))
		return -1;
	progress_add(r->dev, (double)p->width * p->height * (p->sample_end - p->sample_begin));
	progress_draw();
	return 0;
}

int renderer_read_back(struct renderer *r, char *err, size_t err_size)
{
	return r->ops->read_back(r, err, err_size);
}

int renderer_read_sums(struct renderer *r, cl_long *to, char *err, size_t err_size)
{
	const struct render_settings *s = r->settings;

	return r->ops->read_sums(r, to, 0, (size_t)s->width * s->height, NULL, err, err_size);
}

int renderer_read_sums_part(struct renderer *r, cl_long *to, size_t first, size_t count,
			    cl_event *event, char *err, size_t err_size)
{
	return r->ops->read_sums(r, to, first, count, event, err, err_size);
}

int renderer_read_rows(struct renderer *r, const struct rt_piece *piece, float *to, int packed,
		       char *err, size_t err_size)
{
	return r->ops->read_rows(r, piece, to, packed, err, err_size);
}

int renderer_aov(struct renderer *r, char *err, size_t err_size)
{
	return r->ops->aov(r, err, err_size);
}

void renderer_close(struct renderer *r)
{
	if (r->ops)
		r->ops->close(r);
	r->ops = NULL;
}

struct rt_piece renderer_rows(const struct render_settings *s, int y0, int height, int begin,
			      int end)
{
	struct rt_piece p = {.x0 = 0,
			     .y0 = y0,
			     .width = s->width,
			     .height = height,
			     .sample_begin = begin,
			     .sample_end = end,
			     .samples = settings_samples(s)};
	return p;
}

void renderer_interleave_rows(struct rt_piece *p, int height, int band, int classes)
{
	int bands = band > 0 ? height / band : 0;

	p->row_band = p->row_bands = p->row_classes = 0;
	if (classes < 2 || bands < classes) /* nothing to deal */
		return;
	p->row_band = band;
	p->row_bands = bands;
	p->row_classes = classes;
}

struct rt_piece renderer_launch_piece(const struct rt_piece *piece)
{
	struct rt_piece p = *piece;

	p.mean_scale = settings_mean_scale(p.samples);
	return p;
}

struct rt_piece renderer_whole_image(const struct render_settings *s, int begin, int end)
{
	return renderer_rows(s, 0, s->height, begin, end);
}

int renderer_pass_samples(const struct render_settings *s, long long pixels, int gpu)
{
	int samples = settings_samples(s);
	double per_pass = s->samples_per_pass > 0
				  ? s->samples_per_pass
				  : floor(RENDER_PASS_PIXEL_SAMPLES / (double)pixels);

	if (gpu && s->samples_per_pass <= 0 && per_pass < RENDER_GPU_PASS_SAMPLES)
		per_pass = RENDER_GPU_PASS_SAMPLES;

	return per_pass < 1 ? 1 : per_pass > samples ? samples : (int)per_pass;
}

int renderer_pass_count(const struct render_settings *s, const struct rt_piece *piece, int gpu)
{
	int per_pass = renderer_pass_samples(s, (long long)piece->width * piece->height, gpu);

	return (piece->sample_end - piece->sample_begin + per_pass - 1) / per_pass;
}

int renderer_queues(const struct render_settings *s, const struct device *dev)
{
	const struct kernel_info *k = s->kernel;

	if (!k || !k->ops->passes || k->single_item || s->count_flops || s->record_schedule)
		return 1;
	return s->queues > 0 ? s->queues : dev->is_gpu ? RENDER_GPU_QUEUES_SHARE : 1;
}

/* How many queues piece takes: --queues, else (RENDER_GPU_QUEUES_*) none
 * for a single pass, whose one launch keeps the kernel's schedule over the
 * whole piece (the paper's measurements are of single passes), 2 for the
 * whole image and 4 for a share of it; at most the queues open. */
static int piece_queues(const struct renderer *r, const struct rt_piece *piece, int passes)
{
	const struct render_settings *s = r->settings;
	int whole = piece->width == s->width && piece->height == s->height;
	int want = s->queues > 0  ? s->queues
		   : passes < 2	  ? 1
		   : whole	  ? RENDER_GPU_QUEUES_WHOLE
				  : RENDER_GPU_QUEUES_SHARE;

	return want < r->queues ? want : r->queues;
}

/* Cuts piece's columns into at most `queues` parts of whole work-groups
 * (the last takes the rest); returns how many. */
static int split_columns(const struct renderer *r, const struct rt_piece *piece, int queues,
			 struct rt_piece parts[RENDER_MAX_QUEUES])
{
	int group = (int)r->result->local_size[0];
	int groups = (piece->width + group - 1) / group;
	int count = queues < groups ? queues : groups;
	int x = piece->x0;

	for (int i = 0; i < count; i++) {
		int width = (groups * (i + 1) / count - groups * i / count) * group;
		parts[i] = *piece;
		parts[i].x0 = x;
		parts[i].width = i == count - 1 ? piece->x0 + piece->width - x : width;
		x += width;
	}
	return count;
}

int renderer_stopping(const struct renderer *r)
{
	if (!r->settings->stoppable)
		return 0;
	/* From the first pass on an interrupt asks to stop, no more ends the
	 * process (interrupt.h): the caller ends allowing it. */
	interrupt_allow_stop(1);
	return interrupt_stop_signal() != 0;
}

int renderer_checkpoint_due(const struct renderer *r)
{
	return r->settings->checkpoint && r->next_checkpoint > 0 &&
	       timing_now() >= r->next_checkpoint;
}

void renderer_mean_of_sums(const cl_long *sums, size_t pixels, int samples, float *rgb)
{
	float scale = settings_mean_scale(samples);

	for (size_t i = 0; i < pixels; i++) {
		const cl_long *sum = sums + 4 * i;
		for (int c = 0; c < 3; c++)
			rgb[3 * i + c] = sum[3] & (1 << c) ? INFINITY : (float)sum[c] * scale;
	}
}

int renderer_read_mean(struct renderer *r, int samples, float *rgb, char *err, size_t err_size)
{
	const struct render_settings *s = r->settings;
	cl_long *sums = malloc(image_sum_bytes(s->width, s->height));

	if (!sums) {
		snprintf(err, err_size, "out of host memory for the sums of a %dx%d image",
			 s->width, s->height);
		return -1;
	}
	int failed = renderer_read_sums(r, sums, err, err_size);
	if (!failed)
		renderer_mean_of_sums(sums, (size_t)s->width * s->height, samples, rgb);
	free(sums);
	return failed;
}

int renderer_checkpoint(struct renderer *r, int samples, char *err, size_t err_size)
{
	const struct render_settings *s = r->settings;
	const struct render_checkpoint *c = s->checkpoint;
	float *rgb = malloc(image_float_bytes(s->width, s->height));
	int failed = -1;

	if (!rgb)
		snprintf(err, err_size, "out of host memory for a %dx%d checkpoint", s->width,
			 s->height);
	else if (renderer_read_mean(r, samples, rgb, err, err_size) == 0)
		failed = c->write(c->context, rgb, samples, err, err_size);
	free(rgb);
	r->next_checkpoint = timing_now() + c->seconds;
	return failed;
}

int renderer_all_samples(struct renderer *r, const struct rt_piece *whole, struct piece_result *out,
			 char *err, size_t err_size)
{
	int per_pass =
		renderer_pass_samples(r->settings, (long long)whole->width * whole->height,
				      r->dev->is_gpu);

	if (r->settings->checkpoint && r->next_checkpoint == 0)
		r->next_checkpoint = timing_now() + r->settings->checkpoint->seconds;
	int queues = piece_queues(
		r, whole, (whole->sample_end - whole->sample_begin + per_pass - 1) / per_pass);
	if (queues > 1) {
		struct rt_piece parts[RENDER_MAX_QUEUES];
		int count = split_columns(r, whole, queues, parts);
		if (count > r->result->queues)
			r->result->queues = count;
		if (count > 1)
			return r->ops->passes(r, parts, count, per_pass, out, err, err_size);
	}
	out->kernel_ms = 0;
	out->launches = 0;
	out->samples = 0;
	out->passes = 0;
	for (int begin = whole->sample_begin; begin < whole->sample_end; begin += per_pass) {
		struct rt_piece piece = *whole;
		struct piece_result pass;
		if (begin > whole->sample_begin && renderer_stopping(r))
			break;
		if (begin > whole->sample_begin && renderer_checkpoint_due(r) &&
		    renderer_checkpoint(r, begin - whole->sample_begin, err, err_size))
			return -1;
		piece.sample_begin = begin;
		piece.sample_end =
			whole->sample_end - begin > per_pass ? begin + per_pass : whole->sample_end;
		if (renderer_piece(r, &piece, &pass, err, err_size))
			return -1;
		out->kernel_ms += pass.kernel_ms;
		out->launches += pass.launches;
		out->samples = piece.sample_end - whole->sample_begin;
		out->passes++;
	}
	return 0;
}
