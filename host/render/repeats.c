#include "render/repeats.h"

#include <stdio.h>
#include <stdlib.h>

#include "base/progress.h"
#include "base/timing.h"

int repeats_begin(const struct render_settings *s, struct render_result *res, char *err,
		  size_t err_size)
{
	/* Instrumented runs are not timed: one run is enough. */
	int timed = settings_instrumented(s) ? 1 : s->repeat;
	int warm_up = !settings_instrumented(s) && s->warm_up;

	res->kernel_ms = calloc((size_t)timed, sizeof(double));
	res->frame_ms = calloc((size_t)timed, sizeof(double));
	if (!res->kernel_ms || !res->frame_ms) {
		snprintf(err, err_size, "out of host memory");
		return -1;
	}
	res->repeat = timed;
	res->launches = timed + warm_up;
	return res->launches;
}

void repeats_record(struct render_result *res, int frame, int frames, double ms, double wall_ms)
{
	int slot = frame - (frames - res->repeat);

	if (slot >= 0) {
		res->kernel_ms[slot] = ms;
		res->frame_ms[slot] = wall_ms;
	}
}

int repeats_end(struct render_result *res, char *err, size_t err_size)
{
	double min, max;

	return timing_summarize(res->kernel_ms, res->repeat, &res->kernel_ms_median,
				&res->kernel_ms_min, &res->kernel_ms_max, err, err_size) ||
	       timing_summarize(res->frame_ms, res->repeat, &res->frame_ms_median, &min, &max, err,
				err_size);
}

void repeats_progress_begin(const struct render_settings *s, int frames, const char *devices)
{
	char what[64];

	snprintf(what, sizeof(what), "%s (%s%s%s)",
		 s->count_flops		? "counting flops"
		 : s->record_schedule ? "recording the schedule"
				      : "rendering",
		 s->kernel->name, devices ? ", " : "", devices ? devices : "");
	progress_begin(what, frames * repeats_image_work(s));
}

void repeats_progress_step(const struct render_settings *s, const struct render_result *res,
			   int frame, int frames)
{
	char step[48];
	int timed = frame - (frames - res->repeat); /* -1: the warm-up */

	if (frames == 1)
		return;
	if (timed < 0)
		snprintf(step, sizeof(step), "warm-up launch");
	else
		snprintf(step, sizeof(step), "timed launch %d of %d", timed + 1, res->repeat);
	progress_step(step, repeats_image_work(s));
}

double repeats_image_work(const struct render_settings *s)
{
	return (double)s->width * s->height * settings_samples(s);
}
