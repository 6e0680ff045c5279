/* The kernels rtcl knows; the renderer of a piece (renderer.h), which hands
 * it to the chosen kernel's functions (singlepass.c or wavefront.c); and
 * render(), a frame as passes over the whole image, or the CPU reference. */
#include "render/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/launch.h"
#include "base/progress.h"
#include "render/reference.h"
#include "render/renderer.h"
#include "render/singlepass.h"
#include "base/timing.h"
#include "render/wavefront.h"

const struct kernel_info render_kernels[] = {
	{"serial", "one work-item renders every pixel in row-major order", 0, 1, 0, 0, 0,
	 &singlepass_ops},
	{"naive", "one work-item per pixel, a 2D NDRange over the image", 0, 0, 0, 0, 0,
	 &singlepass_ops},
	{"cyclic", "persistent work-groups, chunk (cx,cy) to group (cx mod GX, cy mod GY)", 1, 0, 0,
	 0, 0, &singlepass_ops},
	{"dynamic", "persistent work-groups fetch chunks from a global atomic counter", 1, 0, 0, 0,
	 1, &singlepass_ops},
	{"persistent",
	 "persistent work-groups whose work-items each fetch --batch pixels, no barrier", 1, 0, 0,
	 1, 1, &singlepass_ops},
	{"wavefront", "one launch per bounce over a queue of live rays: paths split in pieces", 0,
	 0, 1, 0, 0, &wavefront_ops},
};
const int render_kernel_count = sizeof(render_kernels) / sizeof(render_kernels[0]);

const struct kernel_info *render_find_kernel(const char *name)
{
	for (int i = 0; i < render_kernel_count; i++)
		if (strcmp(render_kernels[i].name, name) == 0)
			return &render_kernels[i];
	return NULL;
}

int renderer_open(struct renderer *r, struct device *dev, const struct scene *scene,
		  const struct render_settings *s, struct render_result *res, char *err,
		  size_t err_size)
{
	memset(r, 0, sizeof(*r));
	memset(res, 0, sizeof(*res));
	r->ops = s->kernel->ops;
	r->dev = dev;
	r->settings = s;
	r->result = res;
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
	    p->sample_begin < 0 || p->sample_end <= p->sample_begin || p->sample_end > samples) {
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

void renderer_close(struct renderer *r)
{
	if (r->ops)
		r->ops->close(r);
	r->ops = NULL;
}

struct rt_piece renderer_rows(const struct render_settings *s, int y0, int height, int begin,
			      int end)
{
	struct rt_piece p = {0, y0, s->width, height, begin, end, settings_samples(s), 0};
	return p;
}

struct rt_piece renderer_whole_image(const struct render_settings *s, int begin, int end)
{
	return renderer_rows(s, 0, s->height, begin, end);
}

int render_pass_samples_for(const struct render_settings *s, long long pixels)
{
	int samples = settings_samples(s);
	double per_pass = s->samples_per_pass > 0
				  ? s->samples_per_pass
				  : floor(RENDER_PASS_PIXEL_SAMPLES / (double)pixels);

	return per_pass < 1 ? 1 : per_pass > samples ? samples : (int)per_pass;
}

int render_pass_samples(const struct render_settings *s)
{
	return render_pass_samples_for(s, (long long)s->width * s->height);
}

int renderer_pass_count(const struct render_settings *s, const struct rt_piece *piece)
{
	int per_pass = render_pass_samples_for(s, (long long)piece->width * piece->height);

	return (piece->samples + per_pass - 1) / per_pass;
}

int renderer_all_samples(struct renderer *r, const struct rt_piece *whole, struct piece_result *out,
			 char *err, size_t err_size)
{
	int per_pass =
		render_pass_samples_for(r->settings, (long long)whole->width * whole->height);

	out->kernel_ms = 0;
	out->launches = 0;
	for (int begin = 0; begin < whole->samples; begin += per_pass) {
		struct rt_piece piece = *whole;
		struct piece_result pass;
		piece.sample_begin = begin;
		piece.sample_end =
			whole->samples - begin > per_pass ? begin + per_pass : whole->samples;
		if (renderer_piece(r, &piece, &pass, err, err_size))
			return -1;
		out->kernel_ms += pass.kernel_ms;
		out->launches += pass.launches;
	}
	return 0;
}

int render(struct device *dev, const struct scene *scene, const struct render_settings *s,
	   struct render_result *res, char *err, size_t err_size)
{
	struct renderer r;
	struct rt_piece whole = renderer_whole_image(s, 0, settings_samples(s));

	if (renderer_open(&r, dev, scene, s, res, err, err_size))
		goto out_free;
	double lap = timing_now();
	int frames = launch_begin_timing(s, res, err, err_size);
	if (frames < 0)
		goto out_close;
	res->passes = renderer_pass_count(s, &whole);
	if (s->progress)
		launch_progress_begin(s, frames, NULL);
	for (int frame = 0; frame < frames; frame++) {
		struct piece_result out;
		if (s->progress)
			launch_progress_frame(s, res, frame, frames);
		if (renderer_all_samples(&r, &whole, &out, err, err_size))
			goto out_close;
		launch_record_frame(res, frame, frames, out.kernel_ms);
	}
	if (s->progress)
		progress_end();
	if (launch_end_timing(res, err, err_size))
		goto out_close;
	res->times.kernels = timing_lap_ms(&lap);
	if (renderer_read_back(&r, err, err_size))
		goto out_close;
	res->times.read_back = timing_lap_ms(&lap);
	renderer_close(&r);
	return 0;

out_close:
	renderer_close(&r);
out_free:
	if (s->progress)
		progress_end();
	render_result_free(res);
	return -1;
}

int render_reference(const struct scene *scene, const struct render_settings *s,
		     struct render_result *res, char *err, size_t err_size)
{
	memset(res, 0, sizeof(*res));
	res->rgb = malloc(image_float_bytes(s->width, s->height));
	res->kernel_ms = calloc((size_t)s->repeat, sizeof(double));
	if (!res->rgb || !res->kernel_ms) {
		snprintf(err, err_size, "out of host memory for a %dx%d image", s->width,
			 s->height);
		goto out_free;
	}
	for (int i = 0; i < s->repeat; i++) {
		double start = timing_now();
		if (reference_render_samples(scene, s->width, s->height, s->max_depth,
					     settings_samples(s), res->rgb)) {
			snprintf(err, err_size,
				 "the CPU reference renderer failed (out of memory)");
			goto out_free;
		}
		res->kernel_ms[i] = (timing_now() - start) * 1e3;
	}
	res->repeat = s->repeat;
	res->launches = s->repeat;
	for (int i = 0; i < s->repeat; i++)
		res->times.kernels += res->kernel_ms[i];
	res->groups[0] = res->groups[1] = 1;
	if (timing_summarize(res->kernel_ms, res->repeat, &res->kernel_ms_median,
			     &res->kernel_ms_min, &res->kernel_ms_max, err, err_size) == 0)
		return 0;

out_free:
	render_result_free(res);
	return -1;
}

void render_result_free(struct render_result *res)
{
	free(res->rgb);
	free(res->kernel_ms);
	free(res->item_flops);
	free(res->pixel_flops);
	free(res->write_counts);
	res->pixel_flops = NULL;
	res->rgb = NULL;
	res->kernel_ms = NULL;
	res->item_flops = NULL;
	res->write_counts = NULL;
}
