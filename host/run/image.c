/* One image: on the CPU reference, on one device, or cut into pieces over
 * several (schedule/tiles.h); with --flops or --work-map a counting run
 * first, then the timed run. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/interrupt.h"
#include "base/test_hooks.h"
#include "base/version.h"
#include "base/timing.h"
#include "output/denoise.h"
#include "render/render.h"
#include "report/simd.h"
#include "report/summary.h"
#include "run/mode.h"
#include "schedule/tiles.h"

/* The devices of one image, open until the summary has named them. */
struct image_devices {
	struct device devs[DEVICES_MAX];
	struct device_work work[DEVICES_MAX];
	int count;
	struct tiles_request tiles;
};

/* Renders one image with settings s into out: render() on one device, or
 * tiles_render() over several. */
typedef int (*render_fn)(struct image_devices *d, const struct job *job,
			 const struct render_settings *s, struct render_result *out, char *err,
			 size_t err_size);

static int render_one(struct image_devices *d, const struct job *job,
		      const struct render_settings *s, struct render_result *out, char *err,
		      size_t err_size)
{
	return render(&d->devs[0], job->scene, s, out, err, err_size);
}

static int render_pieces(struct image_devices *d, const struct job *job,
			 const struct render_settings *s, struct render_result *out, char *err,
			 size_t err_size)
{
	(void)job;
	return tiles_render(&d->tiles, s, d->work, out, err, err_size);
}

/* SIMD efficiency from the instrumented run's flops and schedule. */
static int model_simd(const struct job *job, struct record *record, char *err, size_t err_size)
{
	const struct render_result *c = &record->counted;
	struct simd_model model;

	if (simd_model_compute(c->schedule, c->pixel_flops,
			       (size_t)job->settings.width * job->settings.height,
			       SIMD_WARP_WIDTH, &model)) {
		snprintf(err, err_size, "out of host memory to model the SIMD efficiency");
		return -1;
	}
	record->simd = (struct simd_figures){1, model.efficiency, model.warp_steps, model.width,
					     model.items_used};
	return 0;
}

/* With --flops, --work-map or --schedule-map, a separate instrumented run
 * first (counting, recording the schedule, or both); then the timed run.
 * Returns 0, or -1 with one message in err. */
static int render_counted(struct image_devices *d, const struct job *job,
			  const struct render_settings *s, render_fn fn, struct record *record,
			  char *err, size_t err_size)
{
	int failed;

	if (job->counting || job->mapping) {
		struct render_settings counting = *s;
		double lap = timing_now();

		counting.count_flops = job->counting;
		counting.record_schedule = job->mapping;
		counting.stoppable = 0;
		counting.checkpoint = NULL;
		failed = fn(d, job, &counting, &record->counted, err, err_size);
		record->counting_ms = timing_lap_ms(&lap);
		if (failed)
			return -1;
		if (job->counting)
			record_count_flops(record);
		if (job->counting && job->mapping && model_simd(job, record, err, err_size))
			return -1;
	}
	failed = fn(d, job, s, &record->result, err, err_size);
	/* An interrupt from now on ends the run (interrupt.h). */
	interrupt_allow_stop(0);
	return failed;
}

/* One image on the devices the job names; several share it in pieces.
 * timed: the job's settings for the timed run, with its stop and
 * checkpoints. */
static int render_on_devices(struct image_devices *d, const struct job *job,
			     const struct render_settings *timed, struct record *record, char *err,
			     size_t err_size)
{
	double lap = timing_now();

	if (job_open_devices(job, d->devs, &d->count, err, err_size)) {
		d->count = 0; /* nothing left open */
		return -1;
	}
	record->device_ms = timing_lap_ms(&lap);
	if (!job_in_pieces(job, d->count)) {
		record_device(record, &d->devs[0]);
		if (job->verbose)
			fprintf(stderr, "rtcl: platform %d, device %d: %s\n",
				d->devs[0].platform_index, d->devs[0].device_index,
				record->device.name);
		return render_counted(d, job, timed, render_one, record, err, err_size);
	}
	if (timed->checkpoint) {
		snprintf(err, err_size,
			 "--checkpoint writes the image of a render on one device (or -k "
			 "reference): render on one (-p/-d, or a --devices list of one), or drop "
			 "--checkpoint");
		return -1;
	}
	struct render_settings s = *timed;
	s.check_writes |= hook_count_writes();
	d->tiles = (struct tiles_request){.scene = job->scene,
					  .devs = d->devs,
					  .count = d->count,
					  .split = job->split,
					  .piece_rows = job->piece_rows,
					  .row_order = job->row_order,
					  .row_classes = job->row_classes};
	/* The split the renders share: a counting run counts each pixel on
	 * one device, so it and the timed run split the pixels. */
	struct render_settings instrumented = s;
	instrumented.count_flops = job->counting;
	instrumented.record_schedule = job->mapping;
	/* A row order asked for asks for pieces of pixels, as a split does. */
	if (tiles_choose_split(&d->tiles, &instrumented, job->split_given || job->row_order_given,
			       &d->tiles.split, &d->tiles.measure, err, err_size))
		return -1;
	record_devices(record, d->devs, d->count);
	int adaptive = tiles_adaptive(d->tiles.split, job->piece_rows);
	int banded = !adaptive && d->tiles.split != SPLIT_SAMPLES;
	int rows = tiles_band_rows(&s, job->piece_rows, d->count, d->tiles.split);
	record->shares = (struct device_shares){
		.devs = d->devs,
		.work = d->work,
		.count = d->count,
		.split = d->tiles.split,
		.piece = d->tiles.split == SPLIT_SAMPLES ? "sample range"
			 : adaptive			  ? "rectangle"
							  : "band",
		.band_rows = banded ? rows : 0,
		.bands = banded ? tiles_band_count(s.height, rows) : 0,
		/* Split samples take whole images: no rows to order. */
		.row_order_given = d->tiles.split != SPLIT_SAMPLES,
	};
	tiles_row_map(&record->shares.rows, &s, job->row_order,
		      job->row_classes ? job->row_classes : tiles_row_classes(d->devs, d->count));
	/* Pieces of pixels stopped early would leave parts of the image
	 * unrendered: only a split of the samples keeps an interrupted
	 * render's (every device's samples so far, added). A split still to be
	 * chosen by measurement (d->tiles.measure) may turn into pieces of
	 * pixels after the probes, so it does not either. The write counts of
	 * tests expect every launch. */
	if (d->tiles.split != SPLIT_SAMPLES || d->tiles.measure || s.check_writes)
		s.stoppable = 0;
	if (render_counted(d, job, &s, render_pieces, record, err, err_size))
		return -1;
	/* The default split is chosen at set-up, by measurement. */
	if (d->tiles.choice.measured) {
		record->shares.split = d->tiles.split;
		record->shares.piece = d->tiles.split == SPLIT_SAMPLES ? "sample range" : "rectangle";
		record->shares.row_order_given = d->tiles.split != SPLIT_SAMPLES;
		record->shares.choice = d->tiles.choice;
	}
	return 0;
}

/* --denoise: the image denoised in place with the albedo and normal images,
 * timed for the summary. */
static int denoise_result(const struct job *job, struct record *record, char *err, size_t err_size)
{
	const struct render_settings *s = &job->settings;
	struct render_result *res = &record->result;
	size_t pixels = (size_t)s->width * s->height;
	double start = timing_now();

	if (denoise_image(res->rgb, res->aov, res->aov + 3 * pixels, s->width, s->height, err,
			  err_size))
		return -1;
	record->denoise_ms = (timing_now() - start) * 1e3;
	return 0;
}

/* --checkpoint's writer: the image so far, committed at once. */
static int write_checkpoint(void *context, const float *rgb, int samples, char *err,
			    size_t err_size)
{
	return output_plan_write_checkpoint(context, rgb, samples, err, err_size);
}

static int image_render(struct mode_run *run, int checked, char *err, size_t err_size)
{
	const struct job *job = run->job;
	struct record *record = run->record;
	struct image_devices *d = calloc(1, sizeof(*d));
	struct render_settings timed = job->settings;
	struct render_checkpoint checkpoint = {job->checkpoint_seconds, write_checkpoint,
					       run->plan};
	int failed;

	(void)checked; /* not called with a failed check */
	if (!d) {
		snprintf(err, err_size, "out of host memory");
		return EXIT_FAILED;
	}
	run->state = d;
	/* A missing library is said before the render, not after it. */
	if (job->denoise && denoise_load(err, err_size))
		return EXIT_FAILED;
	timed.stoppable = job_stoppable(job);
	timed.checkpoint = job->checkpoint_seconds > 0 ? &checkpoint : NULL;
	if (!job->settings.kernel) {
		snprintf(record->device.name, sizeof(record->device.name),
			 "CPU reference (C++, GLM, double precision, one core)");
		failed = render_reference(job->scene, &timed, &record->result, err, err_size);
		interrupt_allow_stop(0);
	} else {
		failed = render_on_devices(d, job, &timed, record, err, err_size);
	}
	if (!failed && job->denoise)
		failed = denoise_result(job, record, err, err_size);
	if (!failed && job->verbose && job->settings.kernel)
		fprintf(stderr, "rtcl: build options: %s\n", record->result.build_options);
	return failed ? EXIT_FAILED : 0;
}

void mode_summary_image(const struct mode_run *run, FILE *out)
{
	if (run->job->verbose)
		report_print_times(run->record);
	report_print_image(out, run->job, run->record);
	output_plan_print(run->plan, out);
	report_print_shares(out, run->record);
}

static void image_release(struct mode_run *run)
{
	struct image_devices *d = run->state;

	if (d)
		devices_close(d->devs, d->count);
	free(d);
	run->state = NULL;
}

const struct mode image_mode = {
	.name = "image",
	.render = image_render,
	.summary = mode_summary_image,
	.release = image_release,
};

const struct mode *mode_for(const struct job *job)
{
	if (job->mpi)
		return &mpi_mode;
	return job->animation ? &frames_mode : &image_mode;
}
