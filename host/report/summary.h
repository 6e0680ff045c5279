/* What a run did, for people: the summary on stdout and -v's lines on
 * stderr. Every figure rtcl prints is computed here or in document.c. */
#ifndef RTCL_SUMMARY_H
#define RTCL_SUMMARY_H

#include <stdio.h>

#include "job/job.h"
#include "job/record.h"

/* One image: device, kernel, image, samples, time and, after a counting
 * run, the work and rays. */
void report_print_image(FILE *out, const struct job *job, const struct record *record);

/* An animation: the frames, each device's share and the time. */
void report_print_frames(FILE *out, const struct job *job, const struct record *record);

/* Several devices: one line per device and the device-level efficiency;
 * nothing for one device. */
void report_print_shares(FILE *out, const struct record *record);

/* -v: where the process's time went, on stderr. */
void report_print_times(const struct record *record);

#endif
