/* What every --mpi rank must share to render one job, as numbers: the
 * scene's digest and every setting that changes the image or how it is cut
 * into pieces, so that a rank that differs is told which setting first.
 * Ranks that disagreed rendered an image spliced from two jobs (or failed on
 * a piece of the wrong size). The devices may differ from rank to rank.
 * Plain data, sent as bytes between ranks (mpi_render.c); no MPI here. */
#ifndef RTCL_JOB_DIGEST_H
#define RTCL_JOB_DIGEST_H

#include <stddef.h>

#include "job/job.h"

/* The settings, one number each in struct job_digest. */
enum job_setting {
	JOB_WIDTH,
	JOB_HEIGHT,
	JOB_SAMPLES,
	JOB_DEPTH,
	JOB_FRAMES_GIVEN,
	JOB_FRAME_FIRST,
	JOB_FRAME_LAST,
	JOB_PIECE_ROWS,
	JOB_SPLIT_STATIC,
	JOB_ROW_ORDER,
	JOB_ROW_CLASSES,
	JOB_KERNEL,
	JOB_WORKGROUP_X,
	JOB_WORKGROUP_Y,
	JOB_GROUPS_X,
	JOB_GROUPS_Y,
	JOB_BATCH,
	JOB_ACCEL,
	JOB_FETCH,
	JOB_REGENERATE,
	JOB_WAVEFRONT_STAGES,
	JOB_PATHS_IN_FLIGHT,
	JOB_SETTINGS
};

#define JOB_SOURCE_SIZE 256

struct job_digest {
	unsigned long long scene_digest;
	long long setting[JOB_SETTINGS];
	char source[JOB_SOURCE_SIZE]; /* the scene's file name, for the message */
};

/* Fills d from job: its scene's digest and file name, and its settings. */
void job_digest_fill(const struct job *job, struct job_digest *d);

/* Writes into message what rank's digest d differs in from rank 0's, the
 * scene first, then the settings as the options name them ("rank 1 renders
 * another job: --spp 4 against rank 0's --spp 2"), and returns 1; returns 0
 * when d is the same job as root. */
int job_digest_differs(const struct job_digest *root, const struct job_digest *d, int rank,
		       char *message, size_t size);

#endif
