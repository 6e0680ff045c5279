#include "report/summary.h"

#include <stdio.h>

#include "base/quote.h"
#include "base/timing.h"
#include "report/devstats.h"
#include "report/simd.h"
#include "render/stages.h"

/* The counting run's SIMD efficiency: measured where the device lets
 * software see it, modelled where the schedule was recorded too. */
static void print_simd(FILE *out, const struct record *record)
{
	const struct render_result *c = &record->counted;
	static const char *const phase[RT_SIMD_PHASES] = {"intersection steps", "traversal steps",
							  "shading steps"};

	fprintf(out, "simd:    %s", c->simd_measured ? "measured " : "not measurable on this device");
	for (int p = 0, shown = 0; c->simd_measured && p < RT_SIMD_PHASES; p++) {
		if (!c->warp_steps[p])
			continue;
		fprintf(out, "%s%.1f%% in %s", shown++ ? ", " : "",
			100 * simd_measured(c, p), phase[p]);
	}
	if (c->simd_measured)
		fprintf(out, ", %.1f%% in both", 100 * simd_measured_all(c));
	if (c->simd_measured && c->warp_steps[RT_SIMD_SHADE])
		fprintf(out, ", %.1f%% in all three", 100 * simd_measured_first(c, RT_SIMD_PHASES));
	if (record->simd.modelled) {
		fprintf(out, "; modelled %.1f%% (warps of %d in lock-step, %llu warp-steps",
			100 * record->simd.efficiency, record->simd.warp_width,
			(unsigned long long)record->simd.warp_steps);
		if (c->simd_measured)
			fprintf(out, "; %+.1f points from the measured",
				100 * (record->simd.efficiency - simd_measured_all(c)));
		fprintf(out, "); %llu of %zu work-items traced pixels\n",
			(unsigned long long)record->simd.items_used,
			c->global_size[0] * c->global_size[1]);
	} else
		fprintf(out, "; modelled with --schedule-map\n");
}

/* The counting run's paths (RENDERING.md, "Paths per bounce"): their
 * number and lengths, and the share of them still live at each bounce. */
static void print_paths(FILE *out, const struct path_counts *p)
{
	uint64_t count = 0, live = 0;
	int bounces = p->max < RT_PATH_LENGTH_BINS ? (int)p->max : RT_PATH_LENGTH_BINS;

	for (int b = 0; b < RT_PATH_LENGTH_BINS; b++)
		count += p->lengths[b];
	fprintf(out,
		"paths:   %llu, %.2f segments each on average, at most %llu; live at bounce 0, 1, "
		"...:",
		(unsigned long long)count, count ? (double)p->segments / (double)count : 0.0,
		(unsigned long long)p->max);
	for (int b = 0; b < bounces; b++) {
		fprintf(out, "%s %.1f%%", b ? "," : "",
			count ? 100.0 * (double)(count - live) / (double)count : 0.0);
		live += p->lengths[b];
	}
	fprintf(out, "\n");
}

/* The end of the summary's time line: the whole run's time, from the start
 * of the process to now (the outputs written), and the program build in it
 * when the build was not cached: a first render's time is mostly that
 * (issue 44: "737 ms" printed, 7.6 s taken). */
static void print_time_in_all(FILE *out, const struct record *record)
{
	const struct render_result *r = &record->result;
	double build = r->times.build + record->counted.times.build;

	fprintf(out, "; %.2f s in all", timing_now() - record->start);
	if (build > 0 && !r->build_cached)
		fprintf(out, ", %.2f s of it the program build (not cached)", build * 1e-3);
	fprintf(out, "\n");
}

void report_print_image(FILE *out, const struct job *job, const struct record *record)
{
	const struct render_settings *s = &job->settings;
	const struct render_result *r = &record->result;

	fprintf(out, "device:  %s\n", record->device.name);
	if (!s->kernel)
		fprintf(out, "kernel:  reference\n");
	else if (s->kernel->single_item)
		fprintf(out, "kernel:  %s (one work-item)\n", s->kernel->name);
	else
		fprintf(out, "kernel:  %s, work-group %dx%d, %dx%d groups (global %zux%zu)\n",
		       s->kernel->name, s->workgroup[0], s->workgroup[1], r->groups[0],
		       r->groups[1], r->global_size[0], r->global_size[1]);
	if (r->stages)
		fprintf(out, "stages:  %d paths in flight, %d iterations a frame (docs/wavefront.md)\n",
			r->stages->slots, r->stages->iterations);
	fprintf(out, "image:   %dx%d, max depth %d, scene %s\n", s->width, s->height, s->max_depth,
	       quote_text(job->scene->source));
	if (record_samples_done(&job->settings, record) < settings_samples(s))
		fprintf(out,
			"samples: %d of %d per pixel (interrupted; the image holds the "
			"samples done)\n",
			r->samples_done, s->samples);
	else if (s->samples > 1)
		fprintf(out, "samples: %d per pixel in %d pass%s\n", s->samples, r->passes,
		       r->passes == 1 ? "" : "es");
	if (r->repeat > 1)
		fprintf(out, "time:    %.3f ms median of %d launches (min %.3f, max %.3f)",
			r->kernel_ms_median, r->repeat, r->kernel_ms_min, r->kernel_ms_max);
	else
		fprintf(out, "time:    %.3f ms %s", r->kernel_ms_median,
			s->kernel ? "in the kernels" : "rendering");
	print_time_in_all(out, record);
	if (job->denoise)
		fprintf(out,
			"denoise: Open Image Denoise, RT filter with albedo and normal, on the "
			"host's CPU: %.0f ms\n",
			record->denoise_ms);
	if (job->counting) {
		const struct flop_summary *f = &record->flops;
		fprintf(out, "work:    %.3f GFLOP, %.1f GFLOP/s; per work-item mean %.0f, max %.0f, min "
		       "%.0f flops: parallel efficiency %.1f%%\n",
		       f->total * 1e-9, f->total * 1e-6 / r->kernel_ms_median, f->mean, f->max,
		       f->min, 100 * f->parallel_efficiency);
		fprintf(out, "rays:    %llu (primary, secondary and shadow), %.1f Mrays/s\n",
		       (unsigned long long)f->rays, f->rays * 1e-3 / r->kernel_ms_median);
		if (s->accel != ACCEL_NONE)
			fprintf(out,
				"nodes:   %llu BVH node visits, %.2f per ray; %.2f leaf visits and "
				"%.2f sphere and triangle tests per ray\n",
				(unsigned long long)f->node_visits,
				f->rays ? (double)f->node_visits / f->rays : 0.0,
				f->rays ? (double)f->leaf_visits / f->rays : 0.0,
				f->rays ? (double)f->prim_tests / f->rays : 0.0);
	}
	if (job->counting && job->scene->integrator == SCENE_INTEGRATOR_PATH)
		print_paths(out, &record->counted.paths);
	if (job->counting)
		print_simd(out, record);
}

void report_print_frames(FILE *out, const struct job *job, const struct record *record)
{
	const struct render_settings *s = &job->settings;
	const struct device_shares *d = &record->shares;
	int n = job_frame_count(job);

	fprintf(out, "frames:  %d..%d (%d), camera orbit, %dx%d, max depth %d, scene %s, kernel %s\n",
		job->first_frame, job->last_frame, n, s->width, s->height, s->max_depth,
		quote_text(job->scene->source), s->kernel->name);
	devstats_print(out, d->devs, d->ranks, d->work, d->count, d->piece);
	fprintf(out, "time:    %.1f ms for %d frame%s (%.1f ms each), %s split", d->wall_ms, n,
		n == 1 ? "" : "s", d->wall_ms / n, split_name(d->split));
	print_time_in_all(out, record);
}

void report_print_shares(FILE *out, const struct record *record)
{
	const struct device_shares *d = &record->shares;

	const struct split_choice *c = &d->choice;

	if (d->count)
		devstats_print(out, d->devs, d->ranks, d->work, d->count, d->piece);
	if (c->measured)
		fprintf(out,
			"split:   %s, measured: the samples %.1f ms over the devices (one pass of "
			"%d took %.1f ms), the sums' read-back %.1f ms and add %.1f ms against "
			"%.1f ms for a share of the pixels (its passes' host time %.1f ms, "
			"to rank 0 %.1f ms)\n",
			split_name(d->split), c->render_ms, c->pass_samples, c->pass_ms, c->sums_ms,
			c->add_ms, c->penalty_ms, c->overhead_ms, c->move_ms);
}

void report_print_times(const struct record *record)
{
	const struct render_times *t = &record->result.times;
	double now = timing_now();
	char aov[64] = "";

	/* Only where --aov or --denoise asked for them. */
	if (record->result.aov)
		snprintf(aov, sizeof(aov), ", auxiliary images %.1f ms", t->aov);
	fprintf(stderr,
		"rtcl: time: device set-up %.1f ms, scene and upload %.1f ms, build %.1f ms%s, "
		"kernels %.1f ms (%d launch%s)%s, read-back %.1f ms, counting run %.1f ms, encoding "
		"and writing %.1f ms; total %.1f ms\n",
		record->device_ms, t->scene, t->build, record->result.build_cached ? " (cached)" : "",
		t->kernels, record->result.launches, record->result.launches == 1 ? "" : "es", aov,
		t->read_back, record->counting_ms, (now - record->write_start) * 1e3,
		(now - record->start) * 1e3);
}
