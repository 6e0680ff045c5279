/* The kernels rtcl knows, and render(): each frame as passes over the whole
 * image through the chosen kernel's renderer (renderer.h), or the CPU
 * reference. */
#include "render/render.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/interrupt.h"
#include "render/repeats.h"
#include "base/progress.h"
#include "device/clerror.h"
#include "layout/scene_block.h"
#include "render/block.h"
#include "render/buffers.h"
#include "render/reference.h"
#include "render/renderer.h"
#include "render/singlepass.h"
#include "base/timing.h"
#include "render/stages.h"
#include "render/wavefront.h"

const char *accel_name(int accel)
{
	return accel == ACCEL_BVH ? "bvh" : accel == ACCEL_BVH_COMPACT ? "bvh-compact" : "none";
}

const char *fetch_name(int fetch)
{
	return fetch == FETCH_GROUP ? "group" : fetch == FETCH_SUBGROUP ? "subgroup" : "item";
}

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

int render_check_integrator(const struct scene *scene, const struct render_settings *s,
			    char *err, size_t err_size)
{
	/* Every kernel and the reference render both integrators; path
	 * regeneration (docs/wavefront.md: a ray tree regenerated per pixel lost
	 * to coherence, performance.md step 4) and the wavefront's stages form
	 * are the path integrator's. */
	if (s->regenerate && scene->integrator != SCENE_INTEGRATOR_PATH) {
		snprintf(err, err_size,
			 "--regenerate restarts paths of the path integrator; this render is "
			 "Whitted's (give --integrator path or a scene with \"integrator\": "
			 "\"path\")");
		return -1;
	}
	if ((s->wavefront_stages || s->wavefront_form_given) &&
	    scene->integrator != SCENE_INTEGRATOR_PATH) {
		snprintf(err, err_size,
			 "--wavefront-form chooses how -k wavefront splits the paths of the path "
			 "integrator; this render uses the Whitted integrator (give --integrator "
			 "path, or leave --wavefront-form out)");
		return -1;
	}
	return 0;
}

int render_pass_samples(const struct render_settings *s)
{
	return renderer_pass_samples(s, (long long)s->width * s->height, 0);
}

/* render()'s frames on the open renderer r, into r->result (res): the
 * passes of each, the auxiliary images, the read-back (not with read_back
 * 0: the image stays in the renderer's buffer). Returns 0, or -1 with one
 * message in err (res then still holds what it held). */
static int render_passes(struct renderer *r, const struct render_settings *s,
			 struct render_result *res, int read_back, char *err, size_t err_size)
{
	struct device *dev = r->dev;
	struct rt_piece whole = renderer_whole_image(s, 0, settings_samples(s));
	double lap = timing_now();
	int frames = repeats_begin(s, res, err, err_size);
	if (frames < 0)
		return -1;
	res->passes = renderer_pass_count(s, &whole, dev->is_gpu);
	if (s->progress)
		repeats_progress_begin(s, frames, NULL);
	for (int frame = 0; frame < frames; frame++) {
		struct piece_result out;
		if (s->progress)
			repeats_progress_step(s, res, frame, frames);
		double start = timing_now();
		if (renderer_all_samples(r, &whole, &out, err, err_size))
			return -1;
		repeats_record(res, frame, frames, out.kernel_ms, (timing_now() - start) * 1e3);
		res->samples_done = out.samples;
		res->passes_done = out.passes;
	}
	if (s->progress)
		progress_end();
	if (repeats_end(res, err, err_size))
		return -1;
	res->times.kernels = timing_lap_ms(&lap);
	if (s->aov && renderer_aov(r, err, err_size))
		return -1;
	res->times.aov = timing_lap_ms(&lap);
	if (!read_back)
		return 0;
	if (renderer_read_back(r, err, err_size))
		return -1;
	/* Stopped: the image buffer holds no means yet, the sums hold the
	 * samples done. */
	if (res->samples_done < settings_samples(s) &&
	    renderer_read_mean(r, res->samples_done, res->rgb, err, err_size))
		return -1;
	res->times.read_back = timing_lap_ms(&lap);
	return 0;
}

int render(struct device *dev, const struct scene *scene, const struct render_settings *s,
	   struct render_result *res, char *err, size_t err_size)
{
	struct renderer r;

	if (renderer_open(&r, dev, scene, s, res, err, err_size))
		goto out_free;
	if (render_passes(&r, s, res, 1, err, err_size)) {
		renderer_close(&r);
		goto out_free;
	}
	renderer_close(&r);
	return 0;

out_free:
	if (s->progress)
		progress_end();
	render_result_free(res);
	return -1;
}

/* ---- a renderer kept from frame to frame (--frames) ----------------------
 *
 * Each frame of an animation opened its renderer (the scene packed and
 * uploaded, the program built or loaded, the image and sums buffers made)
 * and closed it: on four H100s a 2000x2000 frame of the default scene took
 * its device 240 ms for 141 ms of kernels (docs/results/h100x4, batch 98c).
 * Only the camera moves from frame to frame, but the scene is packed
 * relative to the eye (scene_from_eye), so each frame packs it again and
 * writes it into the open renderer's scene buffer: the same bytes render()
 * uploads, the same program, so the same image. When the packed scene
 * changes size (a BVH built otherwise from another eye) the renderer is
 * opened again. Instrumented renders (counts, schedule, write checks, AOVs,
 * checkpoints) open a renderer a frame, as render() does. */

static int keeps_renderer(const struct render_settings *s)
{
	return !s->count_flops && !s->record_schedule && !s->check_writes && !s->aov &&
	       !s->checkpoint;
}

/* The open renderer's facts (plan, build, scene) into a frame's result,
 * which holds no memory of theirs. */
static void copy_facts(const struct render_result *facts, struct render_result *res)
{
	*res = *facts;
	res->rgb = NULL;
	res->aov = NULL;
	res->kernel_ms = res->frame_ms = NULL;
	res->item_flops = res->pixel_flops = NULL;
	res->schedule = NULL;
	res->write_counts = NULL;
	res->pieces = NULL;
	res->piece_count = 0;
	memset(&res->times, 0, sizeof(res->times));
}

/* The scene packed for this frame's eye into the kept renderer's scene
 * buffer; res the frame's result with its image's memory. Returns 0, 1
 * when the packed scene differs in size (the renderer must be opened
 * again), or -1 with one message in err. */
static int pack_again(struct render_keeper *k, const struct scene *scene,
		      const struct render_settings *s, struct render_result *res, char *err,
		      size_t err_size)
{
	struct render_result packed;
	void *block = NULL;
	double lap = timing_now();

	memset(&packed, 0, sizeof(packed));
	if (block_prepare_scene(k->r.dev, scene, s, &packed, &block, err, err_size)) {
		free(block);
		render_result_free(&packed);
		return -1;
	}
	const struct render_result *f = &k->facts;
	if (packed.scene_bytes != f->scene_bytes || packed.scene_in_local != f->scene_in_local ||
	    packed.bvh_nodes != f->bvh_nodes || packed.bvh_width != f->bvh_width) {
		free(block);
		render_result_free(&packed);
		return 1;
	}
	cl_int status = clEnqueueWriteBuffer(k->r.dev->queue, k->r.buffers->scene, CL_TRUE, 0,
					     scene_block_head_bytes(block), block, 0, NULL, NULL);
	free(block);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "writing the scene's %zu bytes to %s failed: %s",
			 f->scene_bytes, k->r.dev->name, cl_error_name(status));
		render_result_free(&packed);
		return -1;
	}
	copy_facts(f, res);
	res->rgb = packed.rgb;
	res->bvh_depth = packed.bvh_depth;
	res->bvh_sah_cost = packed.bvh_sah_cost;
	res->bvh_build_ms = packed.bvh_build_ms;
	res->times.scene = timing_lap_ms(&lap);
	return 0;
}

int render_keeps(const struct render_settings *s)
{
	return keeps_renderer(s);
}

/* k's renderer open on dev for scene's eye: packed again, or opened; res
 * (zeroed first) then holds the frame's facts and memory for its image.
 * Returns 0, or -1 with one message in err, res freed and k closed. */
static int keep_open(struct render_keeper *k, struct device *dev, const struct scene *scene,
		     const struct render_settings *s, struct render_result *res, char *err,
		     size_t err_size)
{
	int packed = 1;

	memset(res, 0, sizeof(*res));
	if (k->open && k->r.dev == dev)
		packed = pack_again(k, scene, s, res, err, err_size);
	if (packed < 0) {
		render_keeper_close(k);
		return -1;
	}
	if (packed) {
		render_keeper_close(k);
		double lap = timing_now();
		if (renderer_open(&k->r, dev, scene, s, &k->facts, err, err_size)) {
			render_result_free(&k->facts); /* the renderer holds nothing */
			return -1;
		}
		k->open_ms += timing_lap_ms(&lap);
		k->open = 1;
		k->opened++;
		copy_facts(&k->facts, res);
		res->times = k->facts.times; /* the opening's */
		res->rgb = k->facts.rgb;     /* the image's memory, the frame's */
		k->facts.rgb = NULL;
	}
	return 0;
}

/* A frame's passes on k's open renderer, into res (read back or not). */
static int kept_passes(struct render_keeper *k, const struct render_settings *s,
		       struct render_result *res, int read_back, char *err, size_t err_size)
{
	k->r.result = res;
	int failed = render_passes(&k->r, s, res, read_back, err, err_size);
	k->r.result = &k->facts;
	return failed;
}

/* After a kept frame failed: its progress line ended, the renderer closed. */
static void kept_failed(struct render_keeper *k, const struct render_settings *s)
{
	if (s->progress)
		progress_end();
	render_keeper_close(k);
}

int render_kept(struct render_keeper *k, struct device *dev, const struct scene *scene,
		const struct render_settings *s, float *rgb, struct render_result *res, char *err,
		size_t err_size)
{
	if (!keeps_renderer(s)) {
		k->opened++;
		return render(dev, scene, s, res, err, err_size);
	}
	if (keep_open(k, dev, scene, s, res, err, err_size))
		return -1;
	if (rgb) { /* the caller's memory instead (never touched: no cost) */
		free(res->rgb);
		res->rgb = rgb;
	}
	if (kept_passes(k, s, res, 1, err, err_size)) {
		kept_failed(k, s);
		if (rgb)
			res->rgb = NULL; /* the caller's */
		render_result_free(res);
		return -1;
	}
	return 0;
}

int render_kept_on_device(struct render_keeper *k, struct device *dev, const struct scene *scene,
			  const struct render_settings *s, cl_mem to, cl_event *copied,
			  struct render_result *res, char *err, size_t err_size)
{
	*copied = NULL;
	if (!keeps_renderer(s)) {
		snprintf(err, err_size, "internal error: an instrumented frame kept on its device");
		return -1;
	}
	if (keep_open(k, dev, scene, s, res, err, err_size))
		return -1;
	free(res->rgb); /* never touched: the image stays on the device */
	res->rgb = NULL;
	int failed = kept_passes(k, s, res, 0, err, err_size);
	if (!failed && res->samples_done >= settings_samples(s)) {
		double lap = timing_now();
		cl_int status = clEnqueueCopyBuffer(dev->queue, k->r.buffers->image.image, to, 0, 0,
						    image_float_bytes(s->width, s->height), 0, NULL,
						    copied);
		if (status == CL_SUCCESS)
			status = clFlush(dev->queue);
		if (status != CL_SUCCESS) {
			snprintf(err, err_size, "copying the frame's image on %s failed: %s",
				 dev->name, cl_error_name(status));
			if (*copied)
				clReleaseEvent(*copied);
			*copied = NULL;
			failed = 1;
		}
		res->times.read_back = timing_lap_ms(&lap);
	}
	if (failed) {
		kept_failed(k, s);
		render_result_free(res);
		return -1;
	}
	return 0;
}

int render_kept_samples(struct render_keeper *k, struct device *dev, const struct scene *scene,
			const struct render_settings *s, int begin, int end, cl_long *sums,
			struct piece_result *out, char *err, size_t err_size)
{
	struct render_result res;
	struct rt_piece piece = renderer_whole_image(s, begin, end);

	if (!keeps_renderer(s)) {
		snprintf(err, err_size, "internal error: an instrumented frame's samples shared");
		return -1;
	}
	if (keep_open(k, dev, scene, s, &res, err, err_size))
		return -1;
	piece.sum_begin = begin; /* the sums hold this range alone */
	k->r.result = &res;
	int failed = renderer_all_samples(&k->r, &piece, out, err, err_size) ||
		     (out->samples == end - begin && renderer_read_sums(&k->r, sums, err, err_size));
	k->r.result = &k->facts;
	render_result_free(&res);
	if (failed) {
		render_keeper_close(k);
		return -1;
	}
	return 0;
}

void render_keeper_close(struct render_keeper *k)
{
	if (!k->open)
		return;
	renderer_close(&k->r);
	render_result_free(&k->facts);
	k->open = 0;
}

/* The CPU reference's checkpoint: the mean of every pixel's first
 * `samples` samples from their sums. */
static int reference_checkpoint(const struct render_settings *s, const double *sums, int samples,
				char *err, size_t err_size)
{
	const struct render_checkpoint *c = s->checkpoint;
	size_t values = (size_t)s->width * s->height * 3;
	float *rgb = malloc(image_float_bytes(s->width, s->height));
	int failed;

	if (!rgb) {
		snprintf(err, err_size, "out of host memory for a %dx%d checkpoint", s->width,
			 s->height);
		return -1;
	}
	reference_mean(sums, values, samples, rgb);
	failed = c->write(c->context, rgb, samples, err, err_size);
	free(rgb);
	return failed;
}

/* One frame of the reference: every pixel's samples one at a time over the
 * image, added in sample order into sums (the same mean as one pixel's
 * samples at a time), with stops and checkpoints between them as
 * renderer_all_samples has between passes. Returns the samples done, or
 * -1 with one message in err. */
static int reference_frame(const struct scene *scene, const struct render_settings *s, double *sums,
			   char *err, size_t err_size)
{
	int samples = settings_samples(s);
	double next_checkpoint = s->checkpoint ? timing_now() + s->checkpoint->seconds : 0;

	memset(sums, 0, (size_t)s->width * s->height * 3 * sizeof(double));
	for (int k = 0; k < samples; k++) {
		if (k > 0 && s->stoppable && interrupt_stop_signal())
			return k;
		if (k > 0 && s->checkpoint && timing_now() >= next_checkpoint) {
			if (reference_checkpoint(s, sums, k, err, err_size))
				return -1;
			next_checkpoint = timing_now() + s->checkpoint->seconds;
		}
		if (reference_render_sample(scene, s->width, s->height, s->max_depth, k, samples,
					    sums)) {
			snprintf(err, err_size,
				 "the CPU reference renderer failed (out of memory)");
			return -1;
		}
		if (k == 0 && s->stoppable)
			interrupt_allow_stop(1);
	}
	return samples;
}

int render_reference(const struct scene *scene, const struct render_settings *s,
		     struct render_result *res, char *err, size_t err_size)
{
	size_t values = (size_t)s->width * s->height * 3;
	double *sums = malloc(values * sizeof(double));

	memset(res, 0, sizeof(*res));
	if (render_check_integrator(scene, s, err, err_size))
		return -1;
	res->rgb = malloc(image_float_bytes(s->width, s->height));
	res->kernel_ms = calloc((size_t)s->repeat, sizeof(double));
	if (!res->rgb || !res->kernel_ms || !sums) {
		snprintf(err, err_size, "out of host memory for a %dx%d image", s->width,
			 s->height);
		goto out_free;
	}
	for (int i = 0; i < s->repeat; i++) {
		double start = timing_now();
		int done = reference_frame(scene, s, sums, err, err_size);
		if (done < 0)
			goto out_free;
		reference_mean(sums, values, done, res->rgb);
		res->kernel_ms[i] = (timing_now() - start) * 1e3;
		res->samples_done = done;
		res->passes_done = done;
	}
	free(sums);
	sums = NULL;
	res->repeat = s->repeat;
	res->launches = s->repeat;
	res->passes = settings_samples(s);
	for (int i = 0; i < s->repeat; i++)
		res->times.kernels += res->kernel_ms[i];
	res->groups[0] = res->groups[1] = 1;
	if (timing_summarize(res->kernel_ms, res->repeat, &res->kernel_ms_median,
			     &res->kernel_ms_min, &res->kernel_ms_max, err, err_size) == 0)
		return 0;

out_free:
	free(sums);
	render_result_free(res);
	return -1;
}

void render_result_free(struct render_result *res)
{
	free(res->rgb);
	free(res->aov);
	res->aov = NULL;
	free(res->kernel_ms);
	free(res->frame_ms);
	free(res->item_flops);
	free(res->pixel_flops);
	free(res->write_counts);
	free(res->schedule);
	free(res->pieces);
	stages_stats_free(res->stages);
	res->stages = NULL;
	res->pieces = NULL;
	res->piece_count = 0;
	res->pixel_flops = NULL;
	res->schedule = NULL;
	res->rgb = NULL;
	res->kernel_ms = NULL;
	res->frame_ms = NULL;
	res->item_flops = NULL;
	res->write_counts = NULL;
}
