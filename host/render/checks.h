/* The write checks of the kernel tests, kept out of the production path:
 * the image buffer with guard zones, the poison written over it before a
 * checked launch, and the per-pixel write counts read back. Active only with
 * render_settings.check_writes; the faults CLI tests inject are
 * base/test_hooks.h's. */
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

/* Creates the per-pixel write-count buffer (a small placeholder without
 * check_writes, since the kernels always take the argument). */
cl_mem checks_create_write_counts(struct device *dev, const struct render_settings *s, char *err,
				  size_t err_size);

/* With check_writes, enqueues the poison over the image and its guard zones
 * and zeroes the write counts; otherwise does nothing. */
cl_int checks_poison(struct device *dev, const struct render_settings *s,
		     const struct guarded_image *g, cl_mem write_counts);

/* With check_writes: reads the per-pixel write counts into
 * result->write_counts and checks the guard zones (result->guards_intact). */
cl_int checks_read(struct device *dev, const struct render_settings *s,
		   const struct guarded_image *g, cl_mem write_counts,
		   struct render_result *result);

#endif
