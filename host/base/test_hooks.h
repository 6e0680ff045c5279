/* Test hooks: faults and delays that CLI tests inject through environment
 * variables, as a real device, rank, cache or file system would produce them
 * and as no test can provoke on demand. Each is off unless its variable is
 * set: RTCL_TEST_DEVICE_FAULT, RTCL_TEST_SLOW_DEVICE, RTCL_TEST_FAIL_DEVICE,
 * RTCL_TEST_RANK_DIES, RTCL_TEST_CHECK_WRITES, RTCL_TEST_AS_GPUS, RTCL_TEST_DOUBLE_BAND,
 * RTCL_TEST_FAIL_RENAME, RTCL_TEST_SLOW_CACHE_WRITE, RTCL_TEST_COMMIT_DELAY,
 * RTCL_TEST_SLOW_SUMS, RTCL_TEST_PASS_SAMPLES, RTCL_TEST_OIDN_FILTER. */
#ifndef RTCL_TEST_HOOKS_H
#define RTCL_TEST_HOOKS_H

/* RTCL_TEST_DEVICE_FAULT=1: the last launch of a frame fails as a device that
 * failed mid-render does (there is no way to make a real one fail on demand). */
int hook_device_fault(void);

/* RTCL_TEST_BVH2=1: CPU devices keep the binary BVH (host/render/block.c),
 * so that the tests can set its images beside the four-wide tree's. */
int hook_binary_bvh(void);

/* RTCL_TEST_SLOW_CACHE_WRITE=MS: the program cache sleeps MS milliseconds
 * with its temporary file written and not yet renamed, so that a test can
 * interrupt it there (host/device/progcache.c). */
void hook_cache_write_delay(void);

/* RTCL_TEST_SLOW_DEVICE=K:MS: device K of a several-device job (multidev.h)
 * sleeps MS milliseconds after each piece, inside its busy time, as a
 * slower device would take longer. K:xF: it sleeps F - 1 times what the
 * piece took (piece_ms), as a device F times slower would, whatever the
 * piece's size (the adaptive dispenser's pieces differ in size). */
void hook_piece_delay(int device, double piece_ms);

/* RTCL_TEST_FAIL_DEVICE=K:N: device K's N-th piece fails, as a device that
 * fails mid-render does. */
int hook_piece_fault(int device, int nth_piece);

/* RTCL_TEST_RANK_DIES=R:N: MPI rank R (not 0) dies (SIGKILL) when it is
 * given its N-th piece, as a node that goes down; or, having taken fewer
 * (taken so far, none_left: told there are no more), when told there are
 * none left, so that it dies before it reports whatever the timing. */
int hook_rank_dies(int rank, int taken, int none_left);

/* RTCL_TEST_CHECK_WRITES=1: one image over several devices or ranks
 * (tiles.h) counts every pixel's writes on every device and fails the run
 * unless each pixel was written once per launch of its band. */
int hook_count_writes(void);

/* RTCL_TEST_AS_GPUS=1: under --mpi every rank reports its devices as GPUs
 * when the ranks choose their bands (host/run/mpi_render.c), so that PoCL's
 * CPU devices take the bands two GPU ranks would; in one process the
 * devices count as GPUs when the default split is chosen (tiles_choose_split). */
int hook_devices_as_gpus(void);

/* RTCL_TEST_SLOW_SUMS=MS: reading a device's sample sums back at set-up,
 * where the default split is measured (tiles_prefer_samples), takes MS
 * milliseconds more, as over a slow link, so that the measured choice can
 * be made to take the pixels. */
void hook_sums_delay(void);

/* RTCL_TEST_DOUBLE_BAND=1: several devices in one process render band 0 a
 * second time on another device, which the write-count check must catch. */
int hook_double_band(void);

/* RTCL_TEST_FAIL_RENAME=N: the N-th rename of a new output over its target
 * in a commit fails (files_inject_rename_failure), as a target that cannot
 * be replaced (a bind-mounted file) makes it fail. Returns N, or 0. */
int hook_rename_fault(void);

/* RTCL_TEST_PASS_SAMPLES=N: every pass traces N samples of every pixel
 * (render_settings.samples_per_pass), as a device fast enough for short
 * passes does, so that a small test image is rendered in many passes that
 * an interrupt or a checkpoint can come between. Returns N, or 0. */
int hook_pass_samples(void);

/* RTCL_TEST_COMMIT_DELAY=MS: the commit of the outputs takes MS milliseconds
 * more after its renames, as on a slow file system, with interrupts held:
 * a signal then comes while the outputs are committed. */
void hook_commit_delay(void);

/* RTCL_TEST_OIDN_FILTER=NAME: --denoise asks Open Image Denoise for the
 * filter NAME instead of "RT", so that a test can make the library fail
 * (an unknown filter) as no input makes it fail on demand. NULL when unset. */
const char *hook_oidn_filter(void);

#endif
