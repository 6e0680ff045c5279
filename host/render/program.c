/* The OpenCL program of a render: the sources of cl/ (embedded at build time,
 * or read from RTCL_CL_DIR), the build options, the build with its log, and
 * RTCL_DUMP_BINARY. */
#include "render/program.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/embedded.h"
#include "base/files.h"
#include "base/interrupt.h"
#include "device/progcache.h"
#include "base/progress.h"

/* The tracer's sources, in the order the compiler sees them; the kernel's own
 * cl/NAME.cl follows. */
const char *const program_tracer_sources[] = {
	"rtcl_shared.h", "tracer.cl", "sample.cl", "texture.cl", "intersect.cl", "traverse.cl",
	"shade.cl",	 "walk.cl",   "bsdf.cl",   "light.cl",	 "path.cl",	 "pixel.cl",
	"scheduling.cl", "aov.cl"};
const int program_tracer_source_count =
	sizeof(program_tracer_sources) / sizeof(program_tracer_sources[0]);

/* The tracer's sources and the kernel's own. */
#define MAX_SOURCES 16

/* A kernel source read from RTCL_CL_DIR is at most this large. */
#define KERNEL_SOURCE_MAX_BYTES ((size_t)16 << 20)

/* Returns the text of cl/NAME, from dir or from the copy embedded at build
 * time; a loaded file is malloc'd and must be freed when *loaded is set. */
static const char *load_source(const char *dir, const char *name, int *loaded, char *err,
			       size_t err_size)
{
	char path[4096], *text;
	size_t length;

	*loaded = 0;
	if (!dir) {
		const char *embedded = embedded_file(name);
		if (!embedded)
			snprintf(err, err_size, "internal error: cl/%s is not embedded", name);
		return embedded;
	}
	snprintf(path, sizeof(path), "%s/%s", dir, name);
	if (files_read(path, "kernel source", KERNEL_SOURCE_MAX_BYTES, &text, &length, err,
		       err_size))
		return NULL;
	*loaded = 1;
	return text;
}

/* -v: the compiler's messages for a program that built, if it had any (with
 * RTCL_BUILD_OPTIONS=-cl-nv-verbose, NVIDIA's register and spill report). */
static void print_build_log(cl_program program, const struct device *dev)
{
	char log[32768] = "";

	clGetProgramBuildInfo(program, dev->id, CL_PROGRAM_BUILD_LOG, sizeof(log) - 1, log, NULL);
	if (log[strspn(log, " \t\r\n")] != '\0')
		fprintf(stderr, "rtcl: build log:\n%s\n", log);
}

/* The binary of the last program built, kept for RTCL_DUMP_BINARY until the
 * outputs are committed (the devices' threads build side by side). */
static struct {
	pthread_mutex_t lock;
	unsigned char *data;
	size_t size;
} dumped = {PTHREAD_MUTEX_INITIALIZER, NULL, 0};

const char *program_dump_path(void)
{
	const char *path = getenv("RTCL_DUMP_BINARY");

	return path && *path ? path : NULL;
}

/* RTCL_DUMP_BINARY=FILE: keeps the built program's binary (PTX on NVIDIA's
 * OpenCL), for reading what the compiler made of the tracer. It is written
 * with the other outputs (program_stage_dump), not now: a debug output
 * follows the same rules as the others. */
static int keep_binary(cl_program program, char *err, size_t err_size)
{
	size_t size = 0;

	if (!program_dump_path())
		return 0;
	if (clGetProgramInfo(program, CL_PROGRAM_BINARY_SIZES, sizeof(size), &size, NULL) !=
		    CL_SUCCESS ||
	    size == 0) {
		snprintf(err, err_size, "RTCL_DUMP_BINARY: the device gives no program binary");
		return -1;
	}
	unsigned char *binary = malloc(size);
	if (!binary) {
		snprintf(err, err_size, "out of memory for a %zu-byte program binary", size);
		return -1;
	}
	if (clGetProgramInfo(program, CL_PROGRAM_BINARIES, sizeof(binary), &binary, NULL) !=
	    CL_SUCCESS) {
		snprintf(err, err_size, "RTCL_DUMP_BINARY: cannot read the program binary");
		free(binary);
		return -1;
	}
	pthread_mutex_lock(&dumped.lock);
	free(dumped.data);
	dumped.data = binary;
	dumped.size = size;
	pthread_mutex_unlock(&dumped.lock);
	return 0;
}

static int write_binary(FILE *file, const void *unused)
{
	(void)unused;
	return fwrite(dumped.data, 1, dumped.size, file) == dumped.size ? 0 : -1;
}

int program_stage_dump(struct staged_file *file, char *err, size_t err_size)
{
	int ret = 0;

	pthread_mutex_lock(&dumped.lock);
	if (program_dump_path() && dumped.data)
		ret = files_stage_with(file, program_dump_path(), write_binary, NULL, err, err_size)
			      ? -1
			      : 1;
	pthread_mutex_unlock(&dumped.lock);
	return ret;
}

/* NVIDIA's compiler gives the tracer about 100 registers, which leaves 4-5
 * warps per scheduler; capped at 80 (60 bytes spilled) the same kernels run
 * 3-5 % faster on an H100 (docs/performance.md, step 9). RTCL_BUILD_OPTIONS can override
 * it: the last -cl-nv-maxrregcount given wins. */
#define NV_REGISTER_CAP "-cl-nv-maxrregcount=80"

/* RTCL_BUILD_OPTIONS may add this many characters: rtcl's own options take at
 * most about 260 of the BUILD_OPTIONS_SIZE (576) in render_result. */
#define BUILD_OPTIONS_EXTRA_MAX 256

/* The tracer's sources and cl/KERNEL.cl, in build order. */
struct sources {
	const char *texts[MAX_SOURCES];
	int loaded[MAX_SOURCES]; /* read from RTCL_CL_DIR: free the text */
	int count;
};

static void free_sources(struct sources *src)
{
	for (int i = 0; i < src->count; i++)
		if (src->loaded[i])
			free((char *)src->texts[i]);
}

static int load_sources(const char *dir, const char *kernel_name, struct sources *src, char *err,
			size_t err_size)
{
	char kernel_file[64];

	snprintf(kernel_file, sizeof(kernel_file), "%s.cl", kernel_name);
	memset(src, 0, sizeof(*src));
	for (int i = 0; i <= program_tracer_source_count; i++) {
		const char *name =
			i < program_tracer_source_count ? program_tracer_sources[i] : kernel_file;
		src->texts[i] = load_source(dir, name, &src->loaded[i], err, err_size);
		if (!src->texts[i])
			return -1;
		src->count++;
	}
	return 0;
}

int program_counts_progress(const struct render_settings *s)
{
	return progress_enabled() && !s->warm_up && !s->kernel->multi_pass &&
	       !s->kernel->counts_handed_out;
}

/* rtcl's build options for the settings, then RTCL_BUILD_OPTIONS. */
static int format_options(const struct device *dev, const struct render_settings *s,
			  const struct program_features *f, char *options, char *err,
			  size_t err_size)
{
	const char *extra = getenv("RTCL_BUILD_OPTIONS");

	if (s->fetch == FETCH_GROUP && !dev->int64_atomics) {
		snprintf(err, err_size,
			 "--fetch group keeps its work-group's block in one 64-bit __local word, "
			 "and %s has no 64-bit atomics (cl_khr_int64_base_atomics); choose --fetch "
			 "item or subgroup",
			 dev->name);
		return -1;
	}
	if (extra && strlen(extra) > BUILD_OPTIONS_EXTRA_MAX) {
		snprintf(err, err_size, "RTCL_BUILD_OPTIONS is too long (at most %d characters)",
			 BUILD_OPTIONS_EXTRA_MAX);
		return -1;
	}
	snprintf(options, BUILD_OPTIONS_SIZE,
		 "-cl-std=CL1.2 -DRTCL_MAX_DEPTH=%d -DRTCL_BATCH=%d%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s%s",
		 /* The path integrator reads max_depth from the scene block and
		  * needs no ray stack: one program for every depth. */
		 f->path ? 0 : s->max_depth, s->batch > 0 ? s->batch : 1,
		 /* The persistent kernel's fetch and regeneration (cl/persistent.cl;
		  * the other kernels do not read them). */
		 s->fetch == FETCH_GROUP ? " -DRTCL_FETCH_GROUP"
		 : s->fetch == FETCH_SUBGROUP ? " -DRTCL_FETCH_SUBGROUP"
					      : "",
		 s->fetch == FETCH_SUBGROUP && dev->simd_measurable ? " -DRTCL_WARP_PTX" : "",
		 s->regenerate ? " -DRTCL_REGENERATE" : "",
		 /* A CPU device: the box test in its vector unit's way
		  * (cl/traverse.cl, box_pair_hit); the same numbers. */
		 dev->is_gpu ? "" : " -DRTCL_CPU",
		 f->scene_in_local ? " -DRTCL_SCENE_IN_LOCAL" : "", f->use_bvh ? " -DRTCL_BVH" : "",
		 /* Four-wide nodes (a CPU outside the counting build, traverse.cl). */
		 f->bvh4 ? " -DRTCL_BVH4" : "",
		 f->has_triangles ? "" : " -DRTCL_NO_TRIANGLES",
		 /* Meshes without spheres: leaves of leaf triangles only (traverse.cl). */
		 f->leaf_triangles_only ? " -DRTCL_LEAF_TRIANGLES_ONLY" : "",
		 /* Pinhole scenes build without the lens: the same program, the same bits. */
		 f->thin_lens ? " -DRTCL_THIN_LENS" : "",
		 /* Point lights only: the program of before light samples. */
		 f->area_lights ? " -DRTCL_AREA_LIGHTS" : "",
		 /* Without Fresnel, weights stay numbers: the program of before. */
		 f->fresnel ? " -DRTCL_FRESNEL" : "",
		 /* Without textures or cut-outs: the program of before textures. */
		 f->textures ? " -DRTCL_TEXTURES" : "",
		 /* No light, no shadow rays: their code is left out. */
		 f->no_lights ? " -DRTCL_NO_LIGHTS" : "",
		 /* The path integrator's files (bsdf.cl, light.cl, path.cl) are
		  * empty without it: a Whitted program is the one of before. */
		 f->path ? " -DRTCL_PATH" : "",
		 s->samples > 1 ? "" : " -DRTCL_ONE_SAMPLE",
		 s->count_flops ? " -DRTCL_COUNT_FLOPS" : "",
		 /* SIMD efficiency, measured where the device lets software see it. */
		 s->count_flops && dev->simd_measurable ? " -DRTCL_SIMD_MEASURE" : "",
		 s->check_writes ? " -DRTCL_COUNT_WRITES" : "",
		 s->record_schedule ? " -DRTCL_SCHEDULE_MAP" : "",
		 /* The auxiliary images' kernel (cl/aov.cl), only when asked for. */
		 s->aov ? " -DRTCL_AOV" : "",
		 /* The chunks done, for the progress line (cl/scheduling.cl). */
		 program_counts_progress(s) ? " -DRTCL_PROGRESS" : "",
		 dev->nv_compiler_options ? " " NV_REGISTER_CAP : "", extra && *extra ? " " : "",
		 extra ? extra : "");
	return 0;
}

/* Builds the program from its sources; returns 0, or -1 with the build log
 * in err. */
static int build_from_source(struct device *dev, const struct render_settings *s,
			     const struct sources *src, const char *options, cl_program *program,
			     char *err, size_t err_size)
{
	cl_int status;

	*program = clCreateProgramWithSource(dev->context, (cl_uint)src->count,
					     (const char **)src->texts, NULL, &status);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clCreateProgramWithSource failed: %s",
			 cl_error_name(status));
		return -1;
	}
	status = clBuildProgram(*program, 1, &dev->id, options, NULL, NULL);
	if (status != CL_SUCCESS) {
		char log[32768] = "";
		clGetProgramBuildInfo(*program, dev->id, CL_PROGRAM_BUILD_LOG, sizeof(log) - 1, log,
				      NULL);
		snprintf(err, err_size,
			 "building kernel '%s' for %s failed: %s\noptions: %s\nbuild log:\n%s",
			 s->kernel->name, dev->name, cl_error_name(status), options, log);
		return -1;
	}
	if (s->verbose)
		print_build_log(*program, dev);
	return 0;
}

int program_build(struct device *dev, const struct render_settings *s,
		  const struct program_features *features, cl_program *program, char *options,
		  int *cached, char *err, size_t err_size)
{
	struct progcache cache;
	struct sources src;
	int ret = -1;

	*cached = 0;
	if (load_sources(s->source_dir, s->kernel->name, &src, err, err_size) ||
	    format_options(dev, s, features, options, err, err_size))
		goto out_free_sources;
	/* The OpenCL compiler crashed under a small `ulimit -v` (PoCL: in the
	   build, or asked for the binary to cache): a message, not silence. */
	char doing[384];
	snprintf(doing, sizeof(doing), "building the kernels for %s (in its OpenCL compiler)",
		 dev->name);
	interrupt_guard_crashes(doing);
	progcache_init(&cache, dev, src.texts, src.count, options, s->verbose);
	*program = progcache_load(&cache, dev);
	if (*program) {
		*cached = 1;
	} else {
		if (build_from_source(dev, s, &src, options, program, err, err_size)) {
			interrupt_unguard_crashes();
			goto out_free_sources;
		}
		progcache_save(&cache, *program);
	}
	ret = keep_binary(*program, err, err_size);
	interrupt_unguard_crashes();

out_free_sources:
	free_sources(&src);
	return ret;
}

cl_kernel program_create_kernel(cl_program program, const char *name, char *err, size_t err_size)
{
	cl_int status;
	cl_kernel kernel = clCreateKernel(program, name, &status);

	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clCreateKernel(\"%s\") failed: %s", name,
			 cl_error_name(status));
		return NULL;
	}
	return kernel;
}
