/* The output plan: every file a run writes, in every mode (one image,
 * --frames, --mpi). The image (or each frame's), and with the options that
 * ask for them the work map and its bar, the --flops counts and their
 * sidecar, the --stats document, and RTCL_DUMP_BINARY's program. They are
 * checked before any work (output_plan_check), staged as they are ready,
 * and renamed over their targets together in one commit
 * (output_plan_commit, base/files.h), so that a failure or an interrupt
 * leaves the previous files untouched or every new one in place. */
#ifndef RTCL_PLAN_H
#define RTCL_PLAN_H

#include <limits.h>
#include <stddef.h>
#include <stdio.h>

#include "base/files.h"
#include "job/job.h"
#include "job/record.h"

/* What to write: from the options (cmd/), read only by this layer. */
struct output_request {
	const char *image;	  /* -o: the image, or the frames' name (output_frame_name) */
	const char *stats;	  /* --stats */
	const char *flops;	  /* --flops FILE.npy (and FILE.npy.json) */
	const char *work_map;	  /* --work-map */
	int work_map_log;	  /* --work-map-scale log */
	const char *work_map_bar; /* --work-map-bar */
	const char *schedule_map; /* --schedule-map */
	int linear_encoding;	  /* --encoding linear */
	int aov;		  /* --aov: OUTPUT_AOV_* bits */
	int denoise;		  /* --denoise */
};

/* The auxiliary images --aov writes (docs/GUIDE.md, "Denoising and
 * auxiliary images"), each beside -o as output_aov_name says. */
enum {
	OUTPUT_AOV_ALBEDO = 1,
	OUTPUT_AOV_NORMAL = 2,
	OUTPUT_AOV_DEPTH = 4,
	OUTPUT_AOV_KINDS = 3,
};

/* The name of auxiliary image `kind` (0 albedo, 1 normal, 2 depth) of image
 * path: its extension replaced by ".KIND.pfm" (out.png -> out.albedo.pfm).
 * Returns 0, or -1 when it does not fit in name[PATH_MAX]. */
int output_aov_name(const char *path, int kind, char *name);

/* "albedo", "normal" or "depth". */
const char *output_aov_kind_name(int kind);

/* The most frames one run writes (each stays staged until all are done). */
#define FRAMES_MAX 1000

/* output_plan_check's result when two outputs name the same file, or an
 * output names a file the scene was read from: a usage error in every mode. */
#define OUTPUT_CLASH (-2)

struct output_plan {
	const struct output_request *request;
	const struct job *job;
	int frames;		 /* image files: 1, or the animation's frames */
	char (*names)[PATH_MAX]; /* each one's name */
	int names_too_long;	 /* a frame's name does not fit in PATH_MAX */
	float **held;		 /* --mpi: frames kept in memory until all arrived */
	struct staged_file *staged; /* the images, then the other outputs */
	int frames_written;	    /* an animation's frames staged (fewer than frames
				       when an interrupt stopped it) */
	int checkpoints;	    /* written by output_plan_write_checkpoint */
	int checkpoint_samples;	    /* the last one's samples per pixel */
	char aov_names[OUTPUT_AOV_KINDS][PATH_MAX]; /* --aov's files, those asked for */
	int aov_names_too_long;
};

/* Prepares the plan of job's outputs (no file touched). Returns 0, or -1
 * with one message in err (out of memory). */
int output_plan_open(struct output_plan *plan, const struct output_request *request,
		     const struct job *job, char *err, size_t err_size);

/* Checks, before any work, that the outputs name distinct files, that none
 * is a file the run reads (scene->inputs: the scene file, its mesh files and
 * every file those read; compared by identity), and that each can be
 * written. Returns 0, OUTPUT_CLASH, or -1 with one message in err. */
int output_plan_check(const struct output_plan *plan, char *err, size_t err_size);

/* Whether two paths name one file (through links and "./"). */
int output_same_file(const char *a, const char *b);

/* The image name of frame f: "_NNNN" (the frame number, at least four
 * digits) before path's extension: out.png -> out_0007.png, out -> out_0007.
 * Returns 0, or -1 when it does not fit in name[PATH_MAX]. */
int output_frame_name(const char *path, int frame, char *name);

/* Stages image i (0 for one image; frame first + i of an animation), of
 * `samples` samples per pixel (fewer than the job's: an interrupted render,
 * which its description says), for the commit; the samples are recorded in
 * the file's metadata (image.h). Thread-safe for distinct i. Returns 0, or
 * -1 with one message in err. */
int output_plan_stage_image(struct output_plan *plan, int i, const float *rgb, int samples,
			    char *err, size_t err_size);

/* --checkpoint: writes the one image now, of `samples` samples per pixel
 * so far, staged and committed alone (the run's other outputs come at its
 * end, with the final image). Returns 0, or -1 with one message in err. */
int output_plan_write_checkpoint(struct output_plan *plan, const float *rgb, int samples, char *err,
				 size_t err_size);

/* Under --mpi, rank 0 keeps every frame in host memory and creates nothing
 * in the output folder until all have arrived, because a rank that dies makes
 * mpirun kill the others (SIGTERM, then SIGKILL) and a killed rank 0 cannot
 * remove what it has staged (run/mpi_render.c). Checks up front that the
 * frames fit: at most half of this host's memory. Returns 0, or -1 with one
 * message in err giving the numbers. */
int output_plan_check_memory(const struct output_plan *plan, char *err, size_t err_size);

/* Keeps image i's pixels (malloc'd; the plan takes them, also on a
 * failure). Returns 0, or -1 with one message in err when it had arrived
 * already. Not thread-safe: the caller serialises. */
int output_plan_hold(struct output_plan *plan, int i, float *rgb, char *err, size_t err_size);

/* Every held image arrived. Returns 0, or -1 with one message in err naming
 * the first missing. */
int output_plan_check_held(const struct output_plan *plan, char *err, size_t err_size);

/* Writes every output, or none: stages the held images (each freed once
 * staged) or, for one image, record->result's; then the work map, the
 * --flops files and the --stats document from the record; then commits
 * everything at once. Returns 0, or -1 with one message in err and nothing
 * written. */
int output_plan_commit(struct output_plan *plan, struct record *record, char *err,
		       size_t err_size);

/* The summary's "output:" line. */
void output_plan_print(const struct output_plan *plan, FILE *out);

/* Discards what is still staged, frees the held images and the plan. */
void output_plan_close(struct output_plan *plan);

#endif
