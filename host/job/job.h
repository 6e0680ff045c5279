/* What to render: the job, built once from the options and the scene
 * (cmd/main.c) and read-only after. Every mode (run/) renders a job; the
 * report and the outputs describe it. The options themselves stay in cmd/:
 * what the layers below need of them is here, resolved. */
#ifndef RTCL_JOB_H
#define RTCL_JOB_H

#include "device/devices.h"
#include "render/settings.h"
#include "scene/scene.h"
#include "schedule/multidev.h"
#include "schedule/tiles.h"

/* Which devices: -p/-d (and -t), or the --devices list. */
struct device_choice {
	int platform, device;	 /* -1: not given */
	enum device_kind kind;	 /* -t/--type */
	struct device_list list; /* --devices */
	int list_given;
};

struct job {
	const struct scene *scene;
	struct render_settings settings; /* resolved: options, else the scene's */
	int counting;			 /* a counting run first: --flops or --work-map */
	int mapping;			 /* the same run records the schedule: --schedule-map */
	struct device_choice devices;
	enum split split;	    /* --split */
	int split_given;	    /* --split given: no default chosen (tiles.h) */
	int row_order_given;	    /* --row-order given: pieces of pixels */
	int piece_rows;		    /* --piece-rows; 0: chosen (tiles.h) */
	enum row_order row_order;   /* --row-order */
	int row_classes;	    /* --row-order interleave:S; 0: the devices */
	int animation;		    /* --frames given */
	int first_frame, last_frame; /* --frames A:B */
	int mpi;		    /* --mpi */
	int all_or_nothing;	    /* --no-partial: an interrupt writes nothing */
	double checkpoint_seconds;  /* --checkpoint; 0: none */
	int denoise;		    /* --denoise: settings.aov is set too */
	int verbose, quiet;	    /* -v, -q */
};

/* The frames of an animation (1 for one image). */
static inline int job_frame_count(const struct job *job)
{
	return job->animation ? job->last_frame - job->first_frame + 1 : 1;
}

/* Whether one image is cut into pieces (schedule/tiles.h): over several
 * devices, or into --piece-rows bands on one (which measures what pieces
 * cost a device). */
static inline int job_in_pieces(const struct job *job, int device_count)
{
	return device_count > 1 || job->piece_rows > 0;
}

/* Whether an interrupt of the job's render keeps the samples done
 * (render_settings.stoppable): one frame of several samples, not timed
 * repeats (-r), unless --no-partial; the modes narrow it further. */
static inline int job_stoppable(const struct job *job)
{
	const struct render_settings *s = &job->settings;

	return !job->all_or_nothing && !job->mpi && settings_samples(s) > 1 && s->repeat == 1 &&
	       !s->warm_up && !s->check_writes;
}

/* Opens the devices the job names into devs[DEVICES_MAX], *count of them.
 * Returns 0, or -1 with one message in err and nothing left open. */
int job_open_devices(const struct job *job, struct device *devs, int *count, char *err,
		     size_t err_size);

#endif
