/* What happened: the record of a run, filled by the mode that rendered the
 * job (run/) and read by the report and the outputs. */
#ifndef RTCL_RECORD_H
#define RTCL_RECORD_H

#include <stddef.h>
#include <stdint.h>

#include "device/device.h"
#include "render/settings.h"
#include "schedule/multidev.h"
#include "schedule/tiles.h"

/* Figures of a counting run (RENDERING.md). */
struct flop_summary {
	uint64_t total;
	double mean, max, min;	    /* per launched work-item */
	double parallel_efficiency; /* mean / max */
	uint64_t rays;
	uint64_t node_visits; /* BVH nodes visited by all rays (0: --accel none) */
	uint64_t leaf_visits; /* BVH leaves visited by all rays */
	uint64_t prim_tests;  /* spheres and triangles tested in those leaves */
};

/* The device that rendered, as the summary and --stats name it. */
struct device_identity {
	char name[640];
	char version[256];
	char driver[256];
	int on_device;		/* an OpenCL device (not the CPU reference) */
	unsigned compute_units; /* CL_DEVICE_MAX_COMPUTE_UNITS */
	unsigned max_clock_mhz; /* CL_DEVICE_MAX_CLOCK_FREQUENCY */
};

/* Several devices (schedule/): who did what. The arrays belong to the mode,
 * which keeps them until the run is reported. count 0: one device. */
struct device_shares {
	const struct device *devs;
	const int *ranks; /* each device's MPI rank, or NULL */
	const struct device_work *work;
	int count;
	int ranks_count;   /* MPI ranks; 0 without --mpi */
	const char *rank_sums; /* --mpi's sample split: how the ranks' sums were
				  added ("shared memory", "MPI_Reduce"), or
				  NULL */
	/* In shared memory, one device a rank: how its sums reached the rank's
	 * slot (RTCL_MPI_SUMS: "copy", "read", "host-ptr"), or NULL. */
	const char *rank_sums_into_slot;
	double rank_sums_ms;   /* on rank 0: in shared memory, the add after the
				  image time; by MPI_Reduce, from its devices'
				  end to the sum */
	/* An animation: how its frames came back to the host
	 * (RTCL_FRAMES_READ: "aside", "pageable", "inline"), or NULL. */
	const char *frames_read;
	enum split split;
	const char *piece; /* what a piece is: "band", "rectangle", "frame" */
	int band_rows, bands; /* bands of fixed rows; 0 for other pieces */
	struct rt_piece rows; /* one image: the row map every piece has (its
				 row_band, row_bands, row_classes); frames: 0 */
	int row_order_given;  /* one image: rows holds the job's row order */
	double wall_ms;	      /* an animation: all its frames */
	struct split_choice choice; /* one image: how the default split was
				       measured and chosen (tiles.h) */
};

/* SIMD efficiency modelled from the instrumented run's flops and schedule
 * (report/simd.h), when it recorded both. */
struct simd_figures {
	int modelled;
	double efficiency;
	uint64_t warp_steps;
	int warp_width;
	uint64_t items_used; /* work-items that traced at least one pixel */
};

struct record {
	struct render_result result;  /* the timed, uncounted render */
	struct render_result counted; /* the instrumented run (job->counting, mapping) */
	struct flop_summary flops;
	struct simd_figures simd;
	struct device_identity device;
	struct device_shares shares;

	/* Where the process's time went (base/timing.h clock, seconds or ms). */
	double start;	    /* main began */
	double device_ms;   /* platform and device set-up */
	double counting_ms; /* the whole counting run */
	double denoise_ms;  /* --denoise: the host's time in Open Image Denoise */
	double write_start; /* the outputs began to be written */
};

void flop_summary_compute(struct flop_summary *summary, const uint64_t *item_flops, size_t items,
			  uint64_t rays);

/* The counted render's figures into record->flops. */
void record_count_flops(struct record *record);

/* Names dev as the device that rendered. */
void record_device(struct record *record, const struct device *dev);

/* Names devs[count] as the devices that rendered: "N devices: a, b". */
void record_devices(struct record *record, const struct device *devs, int count);

/* Frees both results. */
void record_free(struct record *record);

/* The samples of every pixel the image holds: the job's, or fewer where an
 * interrupt stopped the render (render_result.samples_done; a mode that
 * does not set it rendered them all). */
static inline int record_samples_done(const struct render_settings *settings,
				      const struct record *record)
{
	int done = record->result.samples_done, samples = settings_samples(settings);

	return done > 0 && done < samples ? done : samples;
}

#endif
