/* The command line: options, their checks, and --help. */
#ifndef RTCL_CLI_H
#define RTCL_CLI_H

#include <stddef.h>
#include <stdio.h>

#include "base/version.h"
#include "device/devices.h"


struct options {
	const char *kernel;	/* serial, naive, cyclic, dynamic or reference */
	int workgroup[2];	/* -w WxH */
	int groups[2];		/* --groups GXxGY; 0x0 when not given */
	int batch;		/* --batch N for the persistent kernel */
	const char *scene_path; /* -s or the argument; NULL: the built-in paper60 scene */
	const char *output;
	int size[2];		      /* --size WxH; 0x0 when not given */
	int depth;		      /* --depth N; -1 when not given */
	int spp;		      /* --spp N; 0 when not given */
	int platform, device;	      /* -p, -d; -1 when not given */
	enum device_kind device_kind; /* -t/--type gpu|cpu|all */
	int list_devices;
	struct device_list devices; /* --devices LIST|all */
	int devices_given;
	int split_static; /* --split static */
	int split_given;  /* --split given */
	int frames[2];	  /* --frames A:B */
	int frames_given;
	int mpi;	/* --mpi: rank 0 hands out the pieces (mpi_render.h) */
	int piece_rows; /* --piece-rows N; 0: chosen (tiles.h) */
	int repeat;	/* -r N; 0 when not given */
	const char *stats_path;
	const char *flops_path;	       /* --flops FILE.npy */
	const char *work_map_path;     /* --work-map IMAGE */
	int work_map_log;	       /* --work-map-scale log */
	const char *work_map_bar_path; /* --work-map-bar IMAGE */
	int linear_encoding;	       /* --encoding linear: 8-bit files hold round(255 c) */
	int accel;		       /* --accel: 1 bvh (ACCEL_BVH), 0 none */
	int quiet, verbose;
	int help, version;
	/* --mesh-time-limit SECONDS, --mesh-memory-limit MIB, or their
	 * environment variables (mesh.h); ULONG_MAX when neither is given. */
	unsigned long mesh_time_limit, mesh_memory_limit;
};

/* Parses argv into o. Returns 0, or -1 with one message in err (the caller
 * exits with EXIT_USAGE). */
int cli_parse(int argc, char **argv, struct options *o, char *err, size_t err_size);

void cli_print_help(FILE *out);

#endif
