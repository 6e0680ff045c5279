/* Building the OpenCL program of a render. */
#ifndef RTCL_PROGRAM_H
#define RTCL_PROGRAM_H

#include "base/files.h"
#include "render/settings.h"

/* The tracer's sources in cl/, in the order they are built (the kernel's
 * cl/NAME.cl follows them). */
extern const char *const program_tracer_sources[];
extern const int program_tracer_source_count;

/* What of the scene a program is built for. */
struct program_features {
	int scene_in_local; /* the scene block in __local memory */
	int use_bvh;	    /* traverse the scene's BVH (else test every primitive) */
	int has_triangles;  /* without, the triangle code is left out */
	int leaf_triangles_only; /* every BVH leaf a range of leaf triangles (no
				    spheres, --accel bvh): the leaves' other
				    code is left out */
	int thin_lens;	    /* an aperture > 0: primary rays start on the lens */
	int area_lights;    /* a sphere or directional light: lights are sampled */
	int fresnel;	    /* a Fresnel material: ray weights are colours */
	int textures;	    /* a texture or an alpha cut-out (scene_has_textures) */
	int no_lights;	    /* no light: the shadow rays' code is left out */
	int bvh4;	    /* the BVH's nodes are four-wide (a CPU's, rt_bvh4_node) */
	int path;	    /* the path integrator (RENDERING.md, "Path tracing") */
};

/* Builds the tracer's sources and cl/KERNEL.cl for the settings, or loads
 * the program binary that rtcl's cache (progcache.h) holds for them (then
 * *cached is 1), for the scene's features, and writes the
 * options used to options[BUILD_OPTIONS_SIZE]. With settings->verbose the
 * compiler's messages go to stderr; RTCL_BUILD_OPTIONS adds options and
 * with RTCL_DUMP_BINARY=FILE the built binary is kept for program_stage_dump
 * (the last one built wins). Returns 0, or -1 with one
 * message in err (for a failed build, the build log and the options). */
int program_build(struct device *dev, const struct render_settings *settings,
		  const struct program_features *features, cl_program *program, char *options,
		  int *cached, char *err, size_t err_size);

/* RTCL_DUMP_BINARY's file, or NULL when it is not set: a debug output,
 * checked, staged and committed with the run's other outputs. */
const char *program_dump_path(void);

/* Stages the binary of the last program built for RTCL_DUMP_BINARY. Returns
 * 1 when staged, 0 when there is nothing to write (the variable unset, or no
 * program built), or -1 with one message in err. */
int program_stage_dump(struct staged_file *file, char *err, size_t err_size);

/* Whether the program counts the pixels it has done for the progress line
 * (-DRTCL_PROGRESS, one atomic per chunk in serial, naive and cyclic): only
 * while the line is shown, and never for timed launches (-r), which must
 * run the program that is timed off a terminal too (docs/results/h100-batch6,
 * run 23: up to 3 % on naive and 9 % on cyclic at one sample on the H100).
 * Dynamic and persistent need no count: their work counter says how far
 * they are. */
int program_counts_progress(const struct render_settings *settings);

/* clCreateKernel with one message naming the kernel on failure; NULL then. */
cl_kernel program_create_kernel(cl_program program, const char *name, char *err, size_t err_size);

#endif
