/* Test instrumentation, kept out of the production path: the image buffer
 * with guard zones, the poison written over it before a checked launch, the
 * per-pixel write counts read back, and an injected device fault. Active
 * only with render_settings.check_writes (kernel tests) or
 * RTCL_TEST_DEVICE_FAULT=1, RTCL_TEST_SLOW_DEVICE, RTCL_TEST_FAIL_DEVICE and
 * RTCL_TEST_RANK_DIES, RTCL_TEST_CHECK_WRITES, RTCL_TEST_DOUBLE_BAND and
 * RTCL_TEST_FAIL_RENAME, RTCL_TEST_SLOW_CACHE_WRITE and RTCL_TEST_COMMIT_DELAY (CLI
 * tests). */
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

/* RTCL_TEST_DEVICE_FAULT=1: the last launch of a frame fails as a device that
 * failed mid-render does (there is no way to make a real one fail on demand). */
int checks_device_fault_injected(void);

/* RTCL_TEST_SLOW_CACHE_WRITE=MS: the program cache sleeps MS milliseconds
 * with its temporary file written and not yet renamed, so that a test can
 * interrupt it there (host/device/progcache.c). */
void checks_cache_write_delay(void);

/* RTCL_TEST_SLOW_DEVICE=K:MS: device K of a several-device job (multidev.h)
 * sleeps MS milliseconds after each piece, inside its busy time, as a
 * slower device would take longer. K:xF: it sleeps F - 1 times what the
 * piece took (piece_ms), as a device F times slower would, whatever the
 * piece's size (the adaptive dispenser's pieces differ in size). */
void checks_piece_delay(int device, double piece_ms);

/* RTCL_TEST_FAIL_DEVICE=K:N: device K's N-th piece fails, as a device that
 * fails mid-render does. */
int checks_piece_fault(int device, int nth_piece);

/* RTCL_TEST_RANK_DIES=R:N: MPI rank R (not 0) dies (SIGKILL) when it is
 * given its N-th piece, as a node that goes down; or, having taken fewer
 * (taken so far, none_left: told there are no more), when told there are
 * none left, so that it dies before it reports whatever the timing. */
int checks_rank_dies(int rank, int taken, int none_left);

/* RTCL_TEST_CHECK_WRITES=1: one image over several devices or ranks
 * (tiles.h) counts every pixel's writes on every device and fails the run
 * unless each pixel was written once per launch of its band. */
int checks_count_writes(void);

/* RTCL_TEST_DOUBLE_BAND=1: several devices in one process render band 0 a
 * second time on another device, which the write-count check must catch. */
int checks_double_band(void);

/* RTCL_TEST_FAIL_RENAME=N: the N-th rename of a new output over its target
 * in a commit fails (files_inject_rename_failure), as a target that cannot
 * be replaced (a bind-mounted file) makes it fail. Returns N, or 0. */
int checks_rename_fault(void);

/* RTCL_TEST_COMMIT_DELAY=MS: the commit of the outputs takes MS milliseconds
 * more after its renames, as on a slow file system, with interrupts held:
 * a signal then comes while the outputs are committed. */
void checks_commit_delay(void);

#endif
