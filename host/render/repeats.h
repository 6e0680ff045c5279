/* The repeats of a render (-r): a warm-up, then the timed ones, each a
 * launch-frame of the whole image; their times, and their steps on the
 * progress line. */
#ifndef RTCL_REPEATS_H
#define RTCL_REPEATS_H

#include "render/settings.h"

/* Allocates result->kernel_ms and frame_ms for the timed frames and returns how many
 * frames to render in all (a warm-up, then the timed ones; one for a counting
 * run), or -1 with a message. */
int repeats_begin(const struct render_settings *settings, struct render_result *result, char *err,
		  size_t err_size);

/* Records frame `frame` of `frames` as taking ms (kernel_ms) and wall_ms
 * (frame_ms); the warm-up is dropped. */
void repeats_record(struct render_result *result, int frame, int frames, double ms,
		    double wall_ms);

/* Sets the median, min and max of the recorded frames, and frame_ms's
 * median. */
int repeats_end(struct render_result *result, char *err, size_t err_size);

/* Starts the progress line (progress.h) of `frames` frames of the whole
 * image: "rendering (KERNEL)", or "counting flops (KERNEL)" for a counting
 * run, with `devices` ("3 devices") after the kernel when not NULL. */
void repeats_progress_begin(const struct render_settings *settings, int frames,
			    const char *devices);

/* Names frame `frame` of `frames` on the progress line: "warm-up launch" or
 * "timed launch k of N" (-r), nothing for a single frame. */
void repeats_progress_step(const struct render_settings *settings,
			   const struct render_result *result, int frame, int frames);

/* Pixel samples of the whole image: a frame's work on the progress line. */
double repeats_image_work(const struct render_settings *settings);

#endif
