/* The --stats document and the --flops file: every figure rtcl prints, for
 * scripts, and the per-work-item flop counts. */
#ifndef RTCL_STATS_H
#define RTCL_STATS_H

#include <jansson.h>
#include <stddef.h>
#include <stdint.h>

/* Figures of a counting run (RENDERING.md). */
struct flop_summary {
	uint64_t total;
	double mean, max, min;	    /* per launched work-item */
	double parallel_efficiency; /* mean / max */
	uint64_t rays;
};

void flop_summary_compute(struct flop_summary *summary, const uint64_t *item_flops, size_t items,
			  uint64_t rays);

/* Writes a JSON document (atomically, see outfile.h). */
int stats_write_json(const char *path, const json_t *document, char *err, size_t err_size);

/* Writes counts as a .npy file of little-endian uint64 with shape (rows,
 * cols), which numpy.load reads directly. */
int stats_write_npy(const char *path, const uint64_t *counts, size_t rows, size_t cols, char *err,
		    size_t err_size);

#endif
