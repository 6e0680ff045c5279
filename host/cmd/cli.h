/* The command line: options, their checks, and --help. */
#ifndef RTCL_CLI_H
#define RTCL_CLI_H

#include <stddef.h>
#include <stdio.h>

#include "base/version.h"
#include "device/devices.h"
#include "job/job.h"
#include "output/plan.h"
#include "scene/scene.h"


/* The options, composed of what each layer reads: the devices (job.h), the
 * outputs (the output plan's request), and the rest, which main resolves
 * into the job. */
struct options {
	const char *kernel;	/* serial, naive, cyclic, dynamic or reference */
	int workgroup[2];	/* -w WxH */
	int groups[2];		/* --groups GXxGY; 0x0 when not given */
	int batch;		/* --batch N for the persistent kernel */
	int batch_given;
	int fetch;		/* --fetch: enum fetch (render/settings.h) */
	int fetch_given;
	int regenerate;		/* --regenerate */
	int wavefront_stages; /* --wavefront-form stages */
	int wavefront_form_given;
	int paths_in_flight; /* --paths-in-flight N (0: the default) */
	int queues;		/* --queues N (0: the default) */
	const char *scene_path; /* -s or the argument; NULL: the built-in paper60 scene */
	int scene_is_argument;	/* the argument gave it: a scene or a model file */
	int size[2];		/* --size WxH; 0x0 when not given */
	int depth;		/* --depth N; -1 when not given */
	int spp;		/* --spp N; 0 when not given */
	int integrator;		/* --integrator: SCENE_INTEGRATOR_*; -1 when not given */
	struct camera_override camera; /* --eye, --look-at, --fov, --aperture, --focus-distance */
	struct device_choice devices; /* -p, -d (-1 when not given), -t, --devices */
	int list_devices;
	int split;	  /* --split: enum split (dynamic, static, samples) */
	int split_given;  /* --split given */
	int row_order;	     /* --row-order: enum row_order (schedule/tiles.h) */
	int row_classes;     /* --row-order interleave:S; 0: the devices */
	int row_order_given; /* --row-order given */
	int frames[2];	  /* --frames A:B */
	int frames_given;
	int mpi;	/* --mpi: rank 0 hands out the pieces (run/mpi_render.h) */
	int piece_rows; /* --piece-rows N; 0: chosen (schedule/tiles.h) */
	int repeat;	/* -r N; 0 when not given */
	int checkpoint_seconds;	       /* --checkpoint SECONDS; 0: none */
	int no_partial;		       /* --no-partial */
	struct output_request outputs; /* -o, --stats, --flops, --work-map, ... */
	int work_map_scale_given;      /* --work-map-scale given */
	int accel;		       /* --accel: enum accel (render/settings.h) */
	int quiet, verbose;
	int help, version;
	/* --mesh-time-limit SECONDS, --mesh-memory-limit MIB, or their
	 * environment variables (mesh.h); ULONG_MAX when neither is given. */
	unsigned long mesh_time_limit, mesh_memory_limit;
};

/* The longest --checkpoint interval: a week. */
#define CHECKPOINT_MAX_SECONDS 604800

/* Parses argv into o. Returns 0, or -1 with one message in err (the caller
 * exits with EXIT_USAGE). */
int cli_parse(int argc, char **argv, struct options *o, char *err, size_t err_size);

void cli_print_help(FILE *out);

#endif
