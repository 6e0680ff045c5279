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

/* Renders with the CPU reference, settings->repeat times, each timed by the
 * host clock like a single launch. Returns 0, or -1 with one message in err. */
int render_reference(const struct scene *scene, const struct render_settings *settings,
		     struct render_result *result, char *err, size_t err_size);

void render_result_free(struct render_result *result);

#endif
