/* What every renderer does around its kernels: the NDRange plan and its
 * checks against the device, the scene block, launches with their profiled
 * time and progress, and the frame timings. */
#ifndef RTCL_LAUNCH_H
#define RTCL_LAUNCH_H

#include "rtcl_shared.h"
#include "render/settings.h"

/* Bytes of a buffer or __local argument that a kernel takes but does not
 * use in this build (OpenCL wants a non-empty one). */
#define UNUSED_BUFFER_BYTES 16

/* Bytes of __local memory the kernels need besides the scene. */
#define LOCAL_MEM_RESERVE 256
/* The scene goes into __local memory when it takes at most 1/LOCAL_MEM_SHARE
 * of it (launch_prepare_scene says why). */
#define LOCAL_MEM_SHARE 3

/* The most work-items one launch may have: the kernels index them with
 * 32-bit uints (launch.c says where). */
#define LAUNCH_MAX_WORK_ITEMS (1ull << 31)

/* The groups used when --groups is not given: enough work-groups of the given
 * size to fill the device, shaped to cover the image's chunks. */
void launch_default_groups(const struct device *dev, const struct render_settings *settings,
			   int groups[2]);

/* Checks the work-group size against the device's limits. */
int launch_check_workgroup(const struct device *dev, const struct render_settings *settings,
			   char *err, size_t err_size);

/* Chooses the 2D NDRange of a single-pass kernel (result->local_size,
 * global_size and groups) and checks it against the device and against what
 * the kernels can index (LAUNCH_MAX_WORK_ITEMS, the persistent kernel's
 * pixel counter). */
int launch_plan(const struct device *dev, const struct render_settings *settings,
		struct render_result *result, char *err, size_t err_size);

/* Checks the kernel's own work-group limit, known only once it is built. */
int launch_check_kernel(const struct device *dev, cl_kernel kernel,
			const struct render_result *result, const char *name, char *err,
			size_t err_size);

struct bvh;
struct mesh_block;

/* Refuses a scene whose device block (scene_block_bytes, with its indexed
 * triangles and bvh or NULL) is larger than one buffer on dev may be, naming
 * the size and the limit. */
int launch_check_scene_fits(const struct device *dev, const struct scene *scene,
			    const struct mesh_block *mesh, const struct bvh *bvh, char *err,
			    size_t err_size);

/* Builds the BVH (--accel bvh), packs the scene into *block
 * (result->scene_bytes), allocates result->rgb and decides whether the scene
 * lives in __local memory. */
int launch_prepare_scene(struct device *dev, const struct scene *scene,
			 const struct render_settings *settings, struct render_result *result,
			 void **block, char *err, size_t err_size);

/* What every renderer does first: launch_plan, the image checked against the
 * device, launch_prepare_scene, and the program built. Returns 0, or -1 with
 * one message in err; the caller frees *scene_block and releases *program. */
int launch_setup(struct device *dev, const struct scene *scene,
		 const struct render_settings *settings, struct render_result *result,
		 void **scene_block, cl_program *program, char *err, size_t err_size);

/* Allocates result->kernel_ms for the timed frames and returns how many
 * frames to render in all (a warm-up, then the timed ones; one for a counting
 * run), or -1 with a message. */
int launch_begin_timing(const struct render_settings *settings, struct render_result *result,
			char *err, size_t err_size);

/* Records frame `frame` of `frames` as taking ms; the warm-up is dropped. */
void launch_record_frame(struct render_result *result, int frame, int frames, double ms);

/* Sets the median, min and max of the recorded frames. */
int launch_end_timing(struct render_result *result, char *err, size_t err_size);

/* Starts the progress line (progress.h) of `frames` frames of the whole
 * image: "rendering (KERNEL)", or "counting flops (KERNEL)" for a counting
 * run, with `devices` ("3 devices") after the kernel when not NULL. */
void launch_progress_begin(const struct render_settings *settings, int frames, const char *devices);

/* Names frame `frame` of `frames` on the progress line: "warm-up launch" or
 * "timed launch k of N" (-r), nothing for a single frame. */
void launch_progress_frame(const struct render_settings *settings,
			   const struct render_result *result, int frame, int frames);

/* Pixel samples of the whole image: a frame's work on the progress line. */
double launch_image_work(const struct render_settings *settings);

/* The single-pass kernels' work counter (cl/rtcl_shared.h, RT_COUNTER_*)
 * and, with the progress line on, the host's view of it while a launch
 * runs. A device that shares the host's memory (CL_DEVICE_HOST_UNIFIED_MEMORY,
 * a CPU) has it mapped once and read in place: PoCL runs another queue's
 * read only once every work-group of the running kernel is taken, so a read
 * would wait for the launch's end. On other devices (a discrete GPU) a
 * non-blocking read on a second in-order queue copies it while the kernel
 * runs, at most once per PROGRESS_TICK_MS: 8 bytes, next to nothing. */
struct work_counter {
	cl_mem buffer;
	cl_command_queue queue;		/* the device's, which zeroes it */
	int watched;			/* read during launches */
	cl_uint *mapped;		/* unified memory: the words in place */
	cl_command_queue side_queue;	/* else: the reads' queue */
	cl_event reset;			/* the last zeroing, which reads wait for */
	cl_event reading;		/* the read in flight, or NULL */
	cl_uint copy[RT_COUNTER_WORDS]; /* what the last finished read brought */
};

/* Creates c's buffer on dev, watched (readable during launches) or not.
 * Returns 0, or -1 with one message in err. */
int launch_create_counter(struct device *dev, int watched, struct work_counter *c, char *err,
			  size_t err_size);

/* Zeroes the counter before a launch. */
cl_int launch_reset_counter(struct work_counter *c);

void launch_release_counter(struct work_counter *c);

/* What a waiting launch shows on the progress line: how far its work
 * counter is, as a share of its work. */
struct launch_watch {
	struct work_counter *counter; /* NULL: nothing to read during the launch */
	int word;		      /* RT_COUNTER_NEXT or RT_COUNTER_DONE */
	double pixels_per_count;      /* a chunk's pixels when the word counts chunks */
	double pixels;		      /* the count when done: the pixels of whole chunks */
	double work;		      /* the launch's pixel samples */
	const void *slot;	      /* its device, for progress_partial */
};

/* Enqueues one launch, waits for it (drawing the progress line, with the
 * share that watch reads when not NULL) and adds its profiled time to *ms.
 * On failure *call names what failed. */
cl_int launch_run(struct device *dev, cl_kernel kernel, cl_uint dims, const size_t *global,
		  const size_t *local, const struct launch_watch *watch, double *ms,
		  const char **call);

#endif
