/* The one clock of the host, and the summary of repeated timings. */
#ifndef RTCL_TIMING_H
#define RTCL_TIMING_H

#include <stddef.h>

/* Seconds on a monotonic clock, for intervals. */
double timing_now(void);

/* Milliseconds since *since, which it then sets to now: the laps of a
 * sequence of steps. */
double timing_lap_ms(double *since);

/* Sets *median, *min and *max of ms[0 .. n), n ≥ 1. Returns 0, or -1 with a
 * message when out of memory. */
int timing_summarize(const double *ms, int n, double *median, double *min, double *max,
		     char *err, size_t err_size);

#endif
