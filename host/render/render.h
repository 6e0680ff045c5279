/* Rendering a scene: on an OpenCL device with one of the scheduling kernels
 * of cl/, or with the CPU reference (reference.h). */
#ifndef RTCL_RENDER_H
#define RTCL_RENDER_H

#include "render/renderer.h"
#include "render/settings.h"

extern const struct kernel_info render_kernels[];
extern const int render_kernel_count;

/* Returns the kernel named `name`, or NULL. */
const struct kernel_info *render_find_kernel(const char *name);

/* Whether the settings' kernel (NULL: the CPU reference) renders the scene's
 * integrator: today every kernel and the reference render both (RENDERING.md,
 * "Path tracing"), so it returns 0; otherwise -1 with one message in err that
 * says what to use instead. Checked before any work, and again by the
 * renderers, so that a path-traced scene is never silently rendered by
 * Whitted's rules. */
int render_check_integrator(const struct scene *scene, const struct render_settings *settings,
			    char *err, size_t err_size);

/* renderer_pass_samples() for the whole image on a device that is not a
 * GPU: one pass of render() there. */
int render_pass_samples(const struct render_settings *settings);

/* Renders `scene` with `settings` (settings->kernel not NULL) on `dev`: each
 * frame in passes over the whole image (renderer.h), render_pass_samples()
 * samples of every pixel each.
 * Returns 0, or -1 with one message in err (a failed build puts the build log
 * and the options there) and nothing held in result. */
int render(struct device *dev, const struct scene *scene, const struct render_settings *settings,
	   struct render_result *result, char *err, size_t err_size);

/* A renderer kept open from frame to frame of an animation (render_kept);
 * zeroed: none open. */
struct render_keeper {
	struct renderer r;
	struct render_result facts; /* the renderer's: plan, build, scene */
	int open;
	int opened; /* renderers opened so far (render() a frame included) */
	double open_ms; /* the time those kept open took to open */
};

/* render() of a frame whose scene differs from the keeper's last only in
 * its camera (an animation's orbit, run/frames.c), on the renderer k keeps
 * open on dev: the scene packed for the frame's eye and written into its
 * buffer, the program and buffers kept; opened first when none is open on
 * dev or the packed scene's size changed. The same image as render(); an
 * instrumented render (counts, schedule, write checks, AOVs, checkpoints)
 * is render()'s. The image goes into rgb (width * height * 3 floats, the
 * caller's: result->rgb is rgb, not to be freed) when rgb is not NULL and
 * the renderer is kept, else into memory of result's own. Returns 0, or -1
 * with one message in err, nothing held in result and k closed. */
int render_kept(struct render_keeper *k, struct device *dev, const struct scene *scene,
		const struct render_settings *settings, float *rgb, struct render_result *result,
		char *err, size_t err_size);

/* render_kept whose image stays on the device: the frame's passes on k's
 * renderer, then its image copied on dev's queue into `to` (a buffer of
 * width * height * 3 floats of dev's context) and flushed, *copied that
 * copy's event (the caller's to wait for and release); nothing is read
 * back, result->rgb is NULL. A frame an interrupt stopped
 * (result->samples_done less than all) is not copied (*copied NULL).
 * render_keeps(settings) must hold. The caller reads the image from `to`
 * when it will, e.g. on a queue of its own while the next frame renders
 * (run/frames.c). Returns 0, or -1 with one message in err, nothing held in
 * result and k closed. */
int render_kept_on_device(struct render_keeper *k, struct device *dev, const struct scene *scene,
			  const struct render_settings *settings, cl_mem to, cl_event *copied,
			  struct render_result *result, char *err, size_t err_size);

/* Whether render_kept keeps a renderer open for these settings (not for an
 * instrumented render). */
int render_keeps(const struct render_settings *settings);

/* Samples [begin, end) of every pixel of the frame (scene, as render_kept's)
 * on k's renderer, their fixed-point sums (4 cl_long a pixel, cl/sample.cl)
 * read into sums: a share of a frame whose samples are split between
 * devices, which the caller adds (run/frames.c). render_keeps(settings)
 * must hold. Sets *out; out->samples < end - begin when an interrupt
 * stopped it (sums then not read). Returns 0, or -1 with one message in err
 * and k closed. */
int render_kept_samples(struct render_keeper *k, struct device *dev, const struct scene *scene,
			const struct render_settings *settings, int begin, int end, cl_long *sums,
			struct piece_result *out, char *err, size_t err_size);

/* Closes k's renderer, if open. */
void render_keeper_close(struct render_keeper *k);

/* Renders with the CPU reference, settings->repeat times, each timed by the
 * host clock like a single launch. Returns 0, or -1 with one message in err. */
int render_reference(const struct scene *scene, const struct render_settings *settings,
		     struct render_result *result, char *err, size_t err_size);

void render_result_free(struct render_result *result);

#endif
