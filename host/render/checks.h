/* The write checks of the kernel tests, kept out of the production path:
 * the image buffer with guard zones and the poison written over it before a
 * checked launch (the per-pixel write counts are the probe's, probe.h).
 * Active only with render_settings.check_writes; the faults CLI tests inject
 * are base/test_hooks.h's. */
#ifndef RTCL_CHECKS_H
#define RTCL_CHECKS_H

#include "render/settings.h"

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

int checks_create_image(struct device *dev, const struct render_settings *s,
			struct guarded_image *g, char *err, size_t err_size);

void checks_release_image(struct guarded_image *g);

/* With check_writes, enqueues the poison over the image and its guard zones;
 * otherwise does nothing. */
cl_int checks_poison(struct device *dev, const struct render_settings *s,
		     const struct guarded_image *g);

/* With check_writes: checks the guard zones (result->guards_intact). */
cl_int checks_read_guards(struct device *dev, const struct render_settings *s,
			  const struct guarded_image *g, struct render_result *result);

#endif
