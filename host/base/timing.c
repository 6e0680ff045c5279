#include "base/timing.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

double timing_now(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

double timing_lap_ms(double *since)
{
	double now = timing_now(), ms = (now - *since) * 1e3;

	*since = now;
	return ms;
}

static int compare_doubles(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;

	return (x > y) - (x < y);
}

int timing_summarize(const double *ms, int n, double *median, double *min, double *max,
		     char *err, size_t err_size)
{
	double *sorted = malloc((size_t)n * sizeof(double));

	if (!sorted) {
		snprintf(err, err_size, "out of host memory");
		return -1;
	}
	memcpy(sorted, ms, (size_t)n * sizeof(double));
	qsort(sorted, (size_t)n, sizeof(double), compare_doubles);
	*min = sorted[0];
	*max = sorted[n - 1];
	*median = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
	free(sorted);
	return 0;
}
