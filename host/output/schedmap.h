/* The --schedule-map picture: every pixel coloured by the work-group that
 * traced it (docs/RENDERING.md, "The schedule map"); the .npy form is the
 * output plan's (npy.h). */
#ifndef RTCL_SCHEDMAP_H
#define RTCL_SCHEDMAP_H

#include <stddef.h>
#include <stdint.h>

struct staged_file;

/* The colour of work-group `group` (linear RGB in [0, 1]): a fixed hash of
 * the number, so neighbouring groups differ, each channel 0.15 + 0.8 of one
 * byte of it, lifted where its brightest channel is below
 * SCHEDMAP_MIN_BRIGHTEST; black for a pixel no group started (0xffffffff).
 * tools/rtcl_tools/commands/schedule_replay.py computes the same. */
#define SCHEDMAP_MIN_BRIGHTEST 0.45f
void schedmap_group_colour(uint32_t group, float rgb[3]);

/* Stages the picture of schedule (RT_SCHEDULE_WORDS per pixel, row-major) in
 * the format path's name asks for. Returns 0, or -1 with one message in err. */
int schedmap_stage(struct staged_file *staged, const char *path, const uint32_t *schedule,
		   int width, int height, char *err, size_t err_size);

#endif
