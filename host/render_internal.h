/* Between render.c and the multi-pass wavefront renderer (wavefront.c): the
 * shared pieces of building, allocating and timing. Not for the rest of the
 * host. */
#ifndef RTCL_RENDER_INTERNAL_H
#define RTCL_RENDER_INTERNAL_H

#include "render.h"

/* Bytes of __local memory the kernels need besides the scene. */
#define LOCAL_MEM_RESERVE 256

/* Poison written over the image and its guard zones before a checked launch:
 * a NaN no kernel computes. */
#define POISON_WORD 0x7fc0deadu

/* The image buffer; with check_writes, a sub-buffer of a larger one whose
 * guard zones on either side catch writes outside the image (under PoCL they
 * would silently corrupt the host heap). */
struct guarded_image {
	cl_mem parent;
	cl_mem image;
	size_t guard_bytes;
};

int render_create_image(struct device *dev, const struct render_settings *s,
			struct guarded_image *g, char *err, size_t err_size);

void render_release_image(struct guarded_image *g);

/* With check_writes: reads the per-pixel write counts into
 * result->write_counts and checks the guard zones (result->guards_intact). */
cl_int render_read_write_checks(struct device *dev, const struct render_settings *s,
				const struct guarded_image *g, cl_mem write_counts,
				struct render_result *result);

/* Packs the scene, allocates result->rgb and decides whether the scene lives
 * in __local memory. */
int render_prepare_scene(struct device *dev, const struct scene *scene,
			 const struct render_settings *s, struct render_result *result,
			 void **block, char *err, size_t err_size);

/* Builds cl/rtcl_shared.h + cl/tracer.cl + cl/KERNEL.cl with the settings'
 * options (recorded in result->build_options); a failure puts the build log
 * and the options in err. */
int render_build_program(struct device *dev, const struct render_settings *s,
			 struct render_result *result, cl_program *program, char *err,
			 size_t err_size);

cl_kernel render_create_kernel(cl_program program, const char *name, char *err, size_t err_size);

/* Checks that a buffer of `bytes` fits the device before asking for it. */
int render_check_fits(const struct device *dev, const char *what, double bytes, char *err,
		      size_t err_size);

cl_mem render_create_buffer(struct device *dev, cl_mem_flags flags, size_t bytes, void *host,
			    const char *what, char *err, size_t err_size);

/* Waits for a launch, showing the elapsed time on stderr when asked. */
cl_int render_wait(cl_event event, const char *label, int progress);

int render_compare_ms(const void *a, const void *b);

/* Allocates result->kernel_ms for the timed runs and returns how many runs to
 * make in all (a warm-up, then the timed ones; one for a counting run), or -1
 * with a message. */
int render_begin_timing(const struct render_settings *s, struct render_result *result, char *err,
			size_t err_size);

/* Enqueues one launch, waits for it (showing progress when asked) and adds its
 * profiled time to *ms. On failure *call names what failed. */
cl_int render_launch(struct device *dev, const struct render_settings *s, cl_kernel kernel,
		     cl_uint dims, const size_t *global, const size_t *local, const char *label,
		     double *ms, const char **call);

int render_wavefront(struct device *dev, const struct scene *scene, const struct render_settings *s,
		     struct render_result *result, char *err, size_t err_size);

#endif
