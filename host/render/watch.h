/* What the progress line reads while a launch runs: the single-pass
 * kernels' work counter, and the ticker thread that reads it and redraws
 * the line while launches are waited for. */
#ifndef RTCL_WATCH_H
#define RTCL_WATCH_H

#include "rtcl_shared.h"
#include "device/device.h"

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
	cl_command_queue queue;		/* the one its launches run on, which zeroes it */
	int watched;			/* read during launches */
	cl_uint *mapped;		/* unified memory: the words in place */
	cl_command_queue side_queue;	/* else: the reads' queue */
	cl_event reset;			/* the last zeroing, which reads wait for */
	cl_event reading;		/* the read in flight, or NULL */
	cl_uint copy[RT_COUNTER_WORDS]; /* what the last finished read brought */
};

/* Creates c's buffer on dev for the launches of queue, watched (readable
 * during launches) or not, with extra_bytes after the counter's words for
 * the kernel's own use (the persistent kernel's group blocks). Returns 0,
 * or -1 with one message in err. */
int watch_create_counter(struct device *dev, cl_command_queue queue, int watched,
			 size_t extra_bytes, struct work_counter *c, char *err,
			 size_t err_size);

/* Zeroes the counter before a launch. */
cl_int watch_reset_counter(struct work_counter *c);

void watch_release_counter(struct work_counter *c);

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

/* Waits for the launch's event; with the progress line on, the ticker reads
 * the watch's counter (when watch is not NULL) meanwhile. */
cl_int watch_wait(cl_event event, const struct launch_watch *watch);

#endif
