/* What a run reports: the summary on stdout, the --stats document, the
 * --flops file and its sidecar, and the figures of a counting run. Every
 * figure rtcl prints is computed here, for people and for scripts. */
#ifndef RTCL_STATS_H
#define RTCL_STATS_H

#include <stddef.h>
#include <stdint.h>

#include "cmd/cli.h"
#include "render/settings.h"

/* Figures of a counting run (RENDERING.md). */
struct flop_summary {
	uint64_t total;
	double mean, max, min;	    /* per launched work-item */
	double parallel_efficiency; /* mean / max */
	uint64_t rays;
	uint64_t node_visits; /* BVH nodes visited by all rays (0: --accel none) */
};

/* What one run produced, for the summary, --stats and the outputs. */
struct run {
	const struct options *opt;
	const struct scene *scene;
	struct render_settings settings;
	struct render_result result;  /* the timed, uncounted run */
	struct render_result counted; /* the counting run, with --flops/--work-map */
	int counting;
	struct flop_summary flops;
	char device_name[640];
	char device_version[256];
	char driver[256];
	int on_device;		/* an OpenCL device (not the CPU reference) */
	unsigned compute_units; /* CL_DEVICE_MAX_COMPUTE_UNITS */
	unsigned max_clock_mhz; /* CL_DEVICE_MAX_CLOCK_FREQUENCY */

	/* Where the process's time went (timing.h clock, seconds or ms). */
	double start;	    /* main began */
	double device_ms;   /* platform and device set-up */
	double counting_ms; /* the whole counting run, with --flops/--work-map */
	double write_start; /* the outputs began to be written */

	/* One image on several devices (tiles.h): devstats.h's "multidevice"
	 * part of the --stats document; NULL otherwise. Owned by the run. */
	struct json_t *multidevice;
};

void flop_summary_compute(struct flop_summary *summary, const uint64_t *item_flops, size_t items,
			  uint64_t rays);

/* -v: where the process's time went, on stderr. */
void stats_print_times(const struct run *run);

/* Prints the run's summary on stdout (unless -q). */
void stats_print_summary(const struct run *run);

/* The files below are staged for the caller to commit with the run's other
 * outputs (files.h). Each returns 0, or -1 with one message in err. */
struct staged_file;

/* Stages a JSON document (NULL: out of memory) and releases it. */
struct json_t;
int stats_stage_document(struct staged_file *staged, const char *path, struct json_t *doc,
			 char *err, size_t err_size);

/* The --stats document. */
int stats_stage_run(struct staged_file *staged, const char *path, const struct run *run,
		    char *err, size_t err_size);

/* The counting run's per-work-item flops as a .npy file of little-endian
 * uint64 (numpy.load reads it directly): shape (global y, global x), or (1,
 * every launch's work-items) for the wavefront. */
int stats_stage_flops(struct staged_file *staged, const char *path, const struct run *run,
		      char *err, size_t err_size);

/* The counting run's flops per pixel as a .npy file of little-endian
 * uint64, shape (height, width), row 0 at the top: --work-map FILE.npy. */
int stats_stage_pixel_counts(struct staged_file *staged, const char *path, const struct run *run,
			     char *err, size_t err_size);

/* The --flops sidecar: how the counts were launched, and the figures. */
int stats_stage_flops_sidecar(struct staged_file *staged, const char *path, const struct run *run,
			      char *err, size_t err_size);

#endif
