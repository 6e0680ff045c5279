/* Several devices rendering pieces of one job, one host thread per device.
 *
 * A job is a count of pieces (tiles or row bands of an image, or whole
 * frames of an animation). Each device's thread takes its next piece as
 * soon as its previous one is done: from a dispenser under a mutex
 * (dispenser.h: the dynamic or the static split), or from the job's
 * take_piece (the adaptive policy of tiles.c, rank 0 under --mpi). A thread
 * waits for its device in the blocking OpenCL calls (an in-order queue,
 * clFinish or a blocking read), never by polling. The first piece that fails
 * stops the job: the other devices take no further piece, and the job
 * reports that device's message. */
#ifndef RTCL_MULTIDEV_H
#define RTCL_MULTIDEV_H

#include <stddef.h>

#include "device/devices.h"
#include "schedule/dispenser.h"

/* What one piece took: the render_piece callback fills it. */
struct piece_work {
	long long pixels; /* the pixels it wrote */
	double kernel_ms; /* its launches' profiled time on the device */
	int launches;
};

/* What one device did. */
struct device_work {
	int pieces;
	long long pixels;
	double busy_ms;	  /* in the piece function, from taking a piece to done */
	double kernel_ms; /* of busy_ms, the device's kernels (profiling events): the
			     rest is the host's (launching, waiting, reading back) */
	int launches;
	double setup_ms;      /* in the begin function */
	double finish_ms;     /* from the job's start to its last piece done */
	double first_piece_ms; /* its first piece, from taking it to done */
	double last_piece_ms; /* its last piece, from taking it to done */
	int renderers_opened; /* --frames: renderers opened on it (kept open
				 from frame to frame, render_kept) */
	double open_ms; /* --frames: of busy_ms, opening those kept open */
};

/* The job's callbacks, each called in the device's own thread; `device` is
 * the index into the job's devices. Each returns 0, or -1 with one message in
 * err (the job adds which device it was). */
struct multidev_job {
	int piece_count;
	enum split split;
	/* Optional: once per device before its first piece (build, buffers). */
	int (*begin)(void *context, int device, char *err, size_t err_size);
	/* Renders piece `piece`, filling *done (zeroed by the caller). */
	int (*render_piece)(void *context, int device, int piece, struct piece_work *done,
			    char *err, size_t err_size);
	/* Optional: once per device after its last piece, also after a failure
	 * (releases what begin made). */
	void (*end)(void *context, int device);
	/* Optional: hands out device's next piece instead of the job's own
	 * dispenser (under MPI, rank 0 does); -1 when there is none. */
	int (*take_piece)(void *context, int device);
	/* Optional: told at once when a piece fails, with the job's message. */
	void (*failed)(void *context, int device, const char *message);
	void *context;
};

/* Runs the job on devs[0..count) and fills work[count]. Returns 0, or -1
 * with one message in err: "DEVICE (P:D): what failed". */
int multidev_run(const struct multidev_job *job, struct device *devs, int count,
		 struct device_work *work, char *err, size_t err_size);

/* Device-level efficiency: the mean busy time over the largest (1 when
 * every device was busy as long as the busiest; 1/n when one did it all). */
double multidev_efficiency(const struct device_work *work, int count);

#endif
