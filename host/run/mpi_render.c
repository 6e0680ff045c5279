/* sched_getaffinity, CPU_COUNT (note_binding) */
#define _GNU_SOURCE
#include "run/mpi_render.h"

#include <limits.h>
#include <sched.h>
#include <mpi.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "base/envchoice.h"
#include "base/pages.h"
#include "base/test_hooks.h"
#include "base/version.h"
#include "run/frames.h"
#include "run/job_digest.h"
#include "run/mode.h"
#include "base/interrupt.h"
#include "render/repeats.h"
#include "base/progress.h"
#include "render/buffers.h"
#include "render/render.h"
#include "schedule/tiles.h"
#include "base/timing.h"

#define ROOT 0
#define MESSAGE_SIZE 8192

/* Messages to rank 0, and its answers (TAG_GIVE + the asking device). */
enum tag { TAG_TAKE = 1, TAG_RESULT, TAG_FAIL, TAG_DONE, TAG_MOVE, TAG_GIVE = 100 };

/* What a rank tells rank 0 of one of its devices once it is done. */
struct device_report {
	int device;
	int platform_index, device_index;
	char name[256], platform_name[256];
	struct device_work work;
};

struct mpi_job {
	const struct job *job;
	struct render_settings settings; /* the job's, for this rank */
	struct record *record;
	struct output_plan *plan;
	int rank, size;
	struct device devs[DEVICES_MAX]; /* this rank's */
	int count;
	struct device_work work[DEVICES_MAX];
	int taken;			/* pieces this rank took (the test-only rank death) */
	int image;			/* one image in bands (tiles.h), not --frames */
	int by_samples;			/* image: each device a range of the samples
					   (SPLIT_SAMPLES), not bands */
	int measure;			/* by_samples by default: kept only if the
					   devices' probes favour it (choose_measured) */
	struct split_choice choice;	/* how it was chosen */
	int pieces;			/* frames, or bands */
	struct tiles_job tiles;		/* image: this rank's devices and bands */
	int device_failed[DEVICES_MAX]; /* image: a piece of this device failed */
	pthread_mutex_t lock;

	/* Rank 0: the dispenser over every rank's devices, and the outputs. */
	int *first;   /* global index of each rank's first device */
	int *rank_of; /* each global device's rank */
	int total;    /* devices over every rank */
	struct dispenser dispenser;
	int *current; /* the piece each other rank's device renders, or -1 */
	int failed;
	char message[MESSAGE_SIZE];
	struct device *all_devs;
	struct device_work *all_work;
	int *arrived; /* image: how often each band arrived */
	cl_long *sums;	 /* by_samples: this rank's devices' sums added so far;
			    on rank 0 after reduce_sums, every rank's */
	int shared;	 /* by_samples: every rank on one node, each rank's sums
			    in the node's shared memory (win) */
	int node_ranks;	 /* by_samples: the ranks on this rank's node */
	int sums_added;	 /* by_samples: this rank's devices' sums in sums */
	MPI_Win win;
	cl_long **slots;      /* shared: each rank's sums, in win */
	MPI_Datatype pixel;   /* not shared: a pixel's sum, 4 int64 */
	MPI_Op add_op;	      /* not shared: sample_sums' add of two */
	pthread_mutex_t sums_lock; /* sums and arrived, by_samples: not `lock`,
				      which the other ranks' requests for
				      pieces wait on meanwhile */
	double wall_ms;
	int bound_ranks; /* ranks bound to one core of several (note_binding) */
	double setup_ms[DEVICES_MAX]; /* image: each device's set-up, before the
					 clock (open_before_clock) */
	int initialized; /* MPI_Init_thread succeeded */
	int threads;	 /* with MPI_THREAD_MULTIPLE */
	double reduce_ms; /* by_samples: reduce_sums on this rank; shared: its
			     add, from sums_in */
	double sums_in;	  /* shared: timing_now() once every rank's sums were
			     in its slot (reduce_sums' first barrier) */
	int slot_way;	  /* sums_later: how the device's sums reach the slot
			     (enum slot_way, RTCL_MPI_SUMS) */
	cl_mem slot_mem;  /* SLOT_HOST_PTR: a buffer on this rank's slot */
};

static int piece_count(const struct mpi_job *j)
{
	return j->pieces;
}

/* Rank 0: records the first failure; later ones are their consequences. */
static void record_failure(struct mpi_job *j, int rank, const char *message)
{
	pthread_mutex_lock(&j->lock);
	if (!j->failed)
		snprintf(j->message, sizeof(j->message), "rank %d, %.8000s", rank, message);
	j->failed = 1;
	pthread_mutex_unlock(&j->lock);
}

/* Rank 0: the next piece for global device g, or -1. */
static int central_take(struct mpi_job *j, int g)
{
	int piece = -1;

	pthread_mutex_lock(&j->lock);
	if (!j->failed)
		piece = dispenser_take(&j->dispenser, g);
	pthread_mutex_unlock(&j->lock);
	return piece;
}

/* ---- waiting without spinning --------------------------------------------
 *
 * Open MPI's blocking calls poll at full speed while they wait, each taking
 * a core that the ranks' PoCL devices render on. These wait in naps that
 * grow from MPI_NAP_MIN_NS to MPI_NAP_MAX_NS: a message waits at most about
 * a millisecond, against pieces of tens of milliseconds or more. */
#define MPI_NAP_MIN_NS 20000L
#define MPI_NAP_MAX_NS 1000000L
/* Rank 0's server, for one image: its longest nap (serve). */
#define MPI_SERVE_IMAGE_NS 50000L

static void nap(long *ns)
{
	struct timespec t = {0, *ns};

	nanosleep(&t, NULL);
	*ns = *ns * 2 < MPI_NAP_MAX_NS ? *ns * 2 : MPI_NAP_MAX_NS;
}

/* MPI_Probe for any message, in naps of at most max_ns. */
static int wait_probe(MPI_Status *status, long max_ns)
{
	long ns = MPI_NAP_MIN_NS;

	for (;;) {
		int arrived = 0;
		if (MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &arrived, status) !=
		    MPI_SUCCESS)
			return -1;
		if (arrived)
			return 0;
		nap(&ns);
		ns = ns < max_ns ? ns : max_ns;
	}
}

/* MPI_Wait, in naps. */
static int wait_request(MPI_Request *request)
{
	long ns = MPI_NAP_MIN_NS;

	for (;;) {
		int done = 0;
		if (MPI_Test(request, &done, MPI_STATUS_IGNORE) != MPI_SUCCESS)
			return -1;
		if (done)
			return 0;
		nap(&ns);
	}
}

/* MPI_Recv of count ints from rank 0, in naps. */
static int wait_recv_ints(int *data, int count, int tag)
{
	MPI_Request request;

	if (MPI_Irecv(data, count, MPI_INT, ROOT, tag, MPI_COMM_WORLD, &request) != MPI_SUCCESS)
		return -1;
	return wait_request(&request);
}

/* ---- the devices' threads, on every rank -------------------------------- */

static int take_rank_piece(void *context, int device)
{
	struct mpi_job *j = context;
	int piece;

	if (j->rank == ROOT)
		return central_take(j, device);
	if (MPI_Send(&device, 1, MPI_INT, ROOT, TAG_TAKE, MPI_COMM_WORLD) != MPI_SUCCESS ||
	    wait_recv_ints(&piece, 1, TAG_GIVE + device))
		return -1;
	pthread_mutex_lock(&j->lock);
	int taken = piece >= 0 ? ++j->taken : j->taken;
	pthread_mutex_unlock(&j->lock);
	if (hook_rank_dies(j->rank, taken, piece < 0))
		raise(SIGKILL); /* as a node that goes down */
	return piece;
}

/* A result message starts with the piece's number in a header of 8 bytes, so
 * that the floats or cl_long after it are aligned. */
#define RESULT_HEADER 8

/* A message to rank 0 of a piece's number and bytes of pixels, the pixels
 * left for the caller to write at result_pixels(message), on a page
 * (base/pages.h); NULL (with err set) when it cannot be made. Free it with
 * free_message. */
static char *result_message(int piece, size_t bytes, char *err, size_t err_size)
{
	char *message = bytes + RESULT_HEADER <= INT_MAX ? pages_alloc(RESULT_HEADER, bytes) : NULL;

	if (!message) {
		snprintf(err, err_size,
			 "cannot send a piece of %zu bytes to rank 0 (at most 2 GiB, and host "
			 "memory for a copy)",
			 bytes);
		return NULL;
	}
	memset(message, 0, RESULT_HEADER);
	memcpy(message, &piece, sizeof(int));
	return message;
}

static void free_message(char *message)
{
	pages_free(message, RESULT_HEADER);
}

static float *result_pixels(char *message)
{
	return (float *)(message + RESULT_HEADER);
}

/* Sends a message of a piece (its number in the header, then `bytes`) to
 * rank 0 and keeps it. */
static int send_kept(const char *message, size_t bytes, char *err, size_t err_size)
{
	int status = MPI_Send(message, (int)(RESULT_HEADER + bytes), MPI_BYTE, ROOT, TAG_RESULT,
			      MPI_COMM_WORLD);

	if (status != MPI_SUCCESS) {
		snprintf(err, err_size, "sending a piece to rank 0 failed (MPI error %d)", status);
		return -1;
	}
	return 0;
}

/* Sends and frees a result_message of `bytes` bytes of pixels. */
static int send_message(char *message, size_t bytes, char *err, size_t err_size)
{
	int failed = send_kept(message, bytes, err, err_size);

	free_message(message);
	return failed;
}

/* Sends a piece's pixels (a frame, or a band) to rank 0: the piece number,
 * then the floats. */
static int send_result(int piece, const float *rgb, size_t bytes, char *err, size_t err_size)
{
	char *message = result_message(piece, bytes, err, err_size);

	if (!message)
		return -1;
	memcpy(result_pixels(message), rgb, bytes);
	return send_message(message, bytes, err, err_size);
}

/* Rank 0: keeps a frame's pixels (malloc'd, taken) until every frame has
 * arrived; nothing goes to the output folder before (output/plan.h). */
static int hold_frame(struct mpi_job *j, int piece, float *rgb, char *err, size_t err_size)
{
	pthread_mutex_lock(&j->lock);
	int failed = output_plan_hold(j->plan, piece, rgb, err, err_size);
	pthread_mutex_unlock(&j->lock);
	return failed;
}

static int render_rank_piece(void *context, int device, int piece, struct piece_work *done,
			     char *err, size_t err_size)
{
	struct mpi_job *j = context;
	const struct render_settings *s = &j->settings;
	struct render_result result;
	int failed;

	if (j->image)
		return tiles_render_band(&j->tiles, device, piece, done, err, err_size);
	if (frames_render_frame(j->job, &j->settings, &j->devs[device], piece, &result, err, err_size))
		return -1;
	if (j->rank == ROOT) {
		failed = hold_frame(j, piece, result.rgb, err, err_size);
		result.rgb = NULL; /* held, or freed */
	} else {
		failed = send_result(piece, result.rgb, image_float_bytes(s->width, s->height), err,
				     err_size);
	}
	*done = frames_piece_work(s, &result);
	render_result_free(&result);
	return failed ? -1 : 0;
}

static void piece_failed(void *context, int device, const char *message)
{
	struct mpi_job *j = context;

	j->device_failed[device] = 1;
	if (j->rank == ROOT)
		record_failure(j, ROOT, message);
	else
		MPI_Send(message, (int)strlen(message) + 1, MPI_CHAR, ROOT, TAG_FAIL,
			 MPI_COMM_WORLD);
}

/* Image: opens the device's renderer once, before its first band. */
static int open_rank_device(void *context, int device, char *err, size_t err_size)
{
	struct mpi_job *j = context;

	return tiles_open(&j->tiles, device, err, err_size);
}

/* Rank 0: band b is in the image (its own device's or another rank's). */
static void mark_arrived(struct mpi_job *j, int band)
{
	pthread_mutex_lock(&j->lock);
	j->arrived[band]++;
	pthread_mutex_unlock(&j->lock);
}

/* Rank 0: band b's rows, rgb (packed, in split-row order), into the image. */
static void place_band(struct mpi_job *j, int band, const float *rgb)
{
	struct rt_piece p = tiles_job_band(&j->tiles, band, 0, 1);

	mark_arrived(j, band);
	tiles_pack_piece(&p, j->settings.width, rgb, j->record->result.rgb, 1);
}

/* By_samples: piece g's sums (device g's range of the samples) added to
 * this rank's (reduce_sums adds the ranks'). */
static void add_piece_sums(struct mpi_job *j, int piece, const cl_long *sums)
{
	const struct render_settings *s = &j->settings;
	const cl_long *parts[2] = {sums, j->sums};
	long cores = sysconf(_SC_NPROCESSORS_ONLN);

	pthread_mutex_lock(&j->sums_lock);
	/* The first copied, not added to the zeroes (a third less memory
	 * traffic), over this rank's share of the node's cores: the ranks of
	 * one node do this at about the same time. */
	tiles_sum_parts(parts, j->sums_added ? 2 : 1, j->sums, (size_t)s->width * s->height,
			(int)(cores / j->node_ranks));
	j->sums_added++;
	j->arrived[piece]++;
	pthread_mutex_unlock(&j->sums_lock);
}

/* A rank of one device, its sums into its slot of the node's shared memory
 * (sums_later), one of three ways (RTCL_MPI_SUMS, docs/GUIDE.md):
 *
 *   SLOT_HOST_PTR  (default) a buffer made on the slot
 *                  (CL_MEM_USE_HOST_PTR) before the clock; the device's
 *                  sums copied into it on the device and mapped for
 *                  reading, which leaves them in the slot: one transfer.
 *                  Four ranks of the path-traced box (2048x2048, 64 spp)
 *                  on four H200s: 113.3-113.5 ms, 3.86 times one rank
 *                  (batch 103: copy 119.0-120.4, read 120.5-122.8).
 *   SLOT_COPY      read back in SUMS_PARTS parts into the device's pinned
 *                  memory, each part copied into the slot once read while
 *                  the next are read. Read whole and then copied, the
 *                  read-back (2.4 ms for 2000x2000 on an H100) came before
 *                  the copy, inside the image's time (batch 98c). Four
 *                  H100 ranks' copies of the box's 134 MB each, at once,
 *                  ended the frame 10-12 ms after the devices (batch 100).
 *   SLOT_READ      read straight into the slot, ordinary memory: no copy,
 *                  but NVIDIA's OpenCL reads into unpinned memory through
 *                  a staging copy of its own (an image of 2000x2000 took
 *                  28-34 ms against 2.4 pinned).
 *
 * A way that cannot be set up falls back to SLOT_COPY before the clock,
 * and --stats says which way ran (multidevice.rank_sums.into_slot). */
#define SUMS_PARTS 8

enum slot_way { SLOT_COPY, SLOT_READ, SLOT_HOST_PTR, SLOT_WAYS };

static const char *const slot_way_names[SLOT_WAYS] = {"copy", "read", "host-ptr"};

/* The way RTCL_MPI_SUMS names (SLOT_HOST_PTR when unset or empty), or -1. */
static int slot_way_from_env(void)
{
	return env_choice("RTCL_MPI_SUMS", slot_way_names, SLOT_WAYS, SLOT_HOST_PTR);
}

/* One of read_sums_into_slot's threads: its slice of each part, copied once
 * the part is read. */
struct slot_copy {
	const cl_long *from;
	cl_long *to;
	cl_event *events;
	int parts;
	size_t pixels;
	int index, threads;
	int failed;
};

static void *copy_slices(void *arg)
{
	struct slot_copy *c = arg;

	for (int p = 0; p < c->parts; p++) {
		size_t first = c->pixels * p / SUMS_PARTS, end = c->pixels * (p + 1) / SUMS_PARTS;
		size_t begin = first + (end - first) * c->index / c->threads,
		       stop = first + (end - first) * (c->index + 1) / c->threads;
		if (clWaitForEvents(1, &c->events[p]) != CL_SUCCESS) {
			c->failed = 1;
			return NULL;
		}
		memcpy(c->to + 4 * begin, c->from + 4 * begin, (stop - begin) * 4 * sizeof(cl_long));
	}
	return NULL;
}

/* SLOT_HOST_PTR: the device's sums copied into j->slot_mem on the device's
 * queue and mapped for reading, which leaves them in the slot (the map of a
 * CL_MEM_USE_HOST_PTR buffer is its host memory; copied there should a
 * driver give other memory); unmapped without waiting (a read map writes
 * nothing back: the unmap is waited for when the buffer is released). */
static int sums_through_slot_buffer(struct mpi_job *j, int device)
{
	struct device *dev = &j->devs[device];
	size_t bytes = image_sum_bytes(j->settings.width, j->settings.height);
	cl_int status = clEnqueueCopyBuffer(dev->queue, j->tiles.dev[device].renderer.buffers->sums,
					    j->slot_mem, 0, 0, bytes, 0, NULL, NULL);
	void *p = NULL;

	if (status == CL_SUCCESS)
		p = clEnqueueMapBuffer(dev->queue, j->slot_mem, CL_TRUE, CL_MAP_READ, 0, bytes, 0,
				       NULL, NULL, &status);
	if (status != CL_SUCCESS)
		return -1;
	if (p != (void *)j->sums)
		memcpy(j->sums, p, bytes);
	status = clEnqueueUnmapMemObject(dev->queue, j->slot_mem, p, 0, NULL, NULL);
	if (status == CL_SUCCESS)
		status = clFlush(dev->queue);
	return status == CL_SUCCESS ? 0 : -1;
}

/* Before the clock, with the device's renderer open: the buffer that
 * SLOT_HOST_PTR copies through, made on this rank's slot and used once
 * (a driver may pin the memory, or pay other costs, at its first use; the
 * slot's contents then are the probe's, which the frame's sums replace).
 * Falls back to SLOT_COPY where it cannot be made or used. */
static void open_slot_buffer(struct mpi_job *j)
{
	struct tiles_device *d = &j->tiles.dev[0];
	size_t bytes = image_sum_bytes(j->settings.width, j->settings.height);
	cl_int status;

	if (!d->open || !d->renderer.buffers || !d->renderer.buffers->sums) {
		j->slot_way = SLOT_COPY;
		return;
	}
	j->slot_mem = clCreateBuffer(j->devs[0].context, CL_MEM_READ_WRITE | CL_MEM_USE_HOST_PTR,
				     bytes, j->sums, &status);
	if (status != CL_SUCCESS)
		j->slot_mem = NULL;
	if (!j->slot_mem || sums_through_slot_buffer(j, 0) ||
	    clFinish(j->devs[0].queue) != CL_SUCCESS) {
		if (j->slot_mem)
			clReleaseMemObject(j->slot_mem);
		j->slot_mem = NULL;
		j->slot_way = SLOT_COPY;
	}
}

/* The buffer on the slot, before the window goes (its queue done first). */
static void close_slot_buffer(struct mpi_job *j)
{
	if (!j->slot_mem)
		return;
	clFinish(j->devs[0].queue);
	clReleaseMemObject(j->slot_mem);
	j->slot_mem = NULL;
}

/* SLOT_COPY: read back in parts, each copied into the slot by this rank's
 * share of the node's cores as it arrives. */
static int copy_sums_into_slot(struct mpi_job *j, int device, char *err, size_t err_size)
{
	const struct render_settings *s = &j->settings;
	struct tiles_device *d = &j->tiles.dev[device];
	size_t pixels = (size_t)s->width * s->height;
	long cores = sysconf(_SC_NPROCESSORS_ONLN);
	int threads = (int)(cores / j->node_ranks);
	cl_event events[SUMS_PARTS];
	struct slot_copy copies[TILES_SUM_THREADS];
	pthread_t ids[TILES_SUM_THREADS];
	int started[TILES_SUM_THREADS] = {0};
	int made = 0, failed = 0, said = 0;

	threads = threads < 1 ? 1 : threads > TILES_SUM_THREADS ? TILES_SUM_THREADS : threads;
	for (; made < SUMS_PARTS; made++) {
		size_t first = pixels * made / SUMS_PARTS, end = pixels * (made + 1) / SUMS_PARTS;
		if (renderer_read_sums_part(&d->renderer, d->sums, first, end - first,
					    &events[made], err, err_size)) {
			failed = said = 1;
			break;
		}
	}
	pthread_mutex_lock(&j->sums_lock);
	/* The threads copy what was read, each its slice of every part. */
	for (int i = 0; i < threads && made == SUMS_PARTS; i++) {
		copies[i] = (struct slot_copy){d->sums, j->sums, events, made, pixels, i, threads, 0};
		started[i] = i > 0 && pthread_create(&ids[i], NULL, copy_slices, &copies[i]) == 0;
	}
	for (int i = 0; i < threads && made == SUMS_PARTS; i++)
		if (!started[i]) /* the first, and any the system would not start */
			copy_slices(&copies[i]);
	for (int i = 0; i < threads && made == SUMS_PARTS; i++) {
		if (started[i])
			pthread_join(ids[i], NULL);
		failed |= copies[i].failed;
	}
	if (clWaitForEvents(made, events) != CL_SUCCESS && made > 0)
		failed = 1;
	for (int p = 0; p < made; p++)
		clReleaseEvent(events[p]);
	if (failed && !said)
		snprintf(err, err_size, "reading the sample sums back from %s failed",
			 j->devs[device].name);
	if (!failed) {
		j->sums_added++;
		for (int g = 0; g < j->tiles.piece_count; g++)
			if (j->tiles.owner[g] == device)
				j->arrived[g]++;
	}
	pthread_mutex_unlock(&j->sums_lock);
	return failed ? -1 : 0;
}

/* Device's sums into the slot, the way j->slot_way says; then this rank's
 * sums and the device's pieces counted. */
static int read_sums_into_slot(struct mpi_job *j, int device, char *err, size_t err_size)
{
	int failed = 0;

	if (j->slot_way == SLOT_COPY)
		return copy_sums_into_slot(j, device, err, err_size);
	if (j->slot_way == SLOT_READ) {
		failed = renderer_read_sums(&j->tiles.dev[device].renderer, j->sums, err, err_size);
	} else if (sums_through_slot_buffer(j, device)) {
		snprintf(err, err_size,
			 "copying the sample sums from %s into the shared memory failed",
			 j->devs[device].name);
		failed = 1;
	}
	if (failed)
		return -1;
	pthread_mutex_lock(&j->sums_lock);
	j->sums_added++;
	for (int g = 0; g < j->tiles.piece_count; g++)
		if (j->tiles.owner[g] == device)
			j->arrived[g]++;
	pthread_mutex_unlock(&j->sums_lock);
	return 0;
}

/* Under check_writes: reads device's image and write counts; nonzero, with
 * one message in err, when a pixel was not written as its pieces say. */
static int writes_wrong(struct tiles_job *t, int device, char *err, size_t err_size)
{
	return t->settings->check_writes && (tiles_collect(t, device, err, err_size) ||
					     tiles_check_device(t, device, err, err_size));
}

/* By_samples: the device is done: its sums into this rank's, which
 * reduce_sums adds to the other ranks' once all of this rank's devices are
 * done. */
static int add_device_sums(struct mpi_job *j, int device, char *err, size_t err_size)
{
	struct tiles_job *t = &j->tiles;

	if (writes_wrong(t, device, err, err_size))
		return -1;
	if (t->sums_later)
		return read_sums_into_slot(j, device, err, err_size);
	for (int g = 0; g < t->piece_count; g++)
		if (t->owner[g] == device)
			add_piece_sums(j, g, t->dev[device].sums);
	return 0;
}

/* Image: the device is done: reads back the bands it rendered, and only
 * those, straight into the image (rank 0) or into each band's message to
 * rank 0: one copy of its pixels. Under check_writes the whole image and its
 * write counts are read first and checked. */
static int send_bands(struct mpi_job *j, int device, char *err, size_t err_size)
{
	struct tiles_job *t = &j->tiles;
	struct renderer *r = &t->dev[device].renderer;

	if (writes_wrong(t, device, err, err_size))
		return -1;
	for (int b = 0; b < t->bands; b++) {
		if (t->owner[b] != device)
			continue;
		struct rt_piece p = tiles_job_band(t, b, 0, 1);
		if (j->rank == ROOT) {
			if (renderer_read_rows(r, &p, j->record->result.rgb, 0, err, err_size))
				return -1;
			mark_arrived(j, b);
			continue;
		}
		size_t bytes = image_float_bytes(p.width, p.height);
		char *message = result_message(b, bytes, err, err_size);
		if (!message)
			return -1;
		if (renderer_read_rows(r, &p, result_pixels(message), 1, err, err_size)) {
			free_message(message);
			return -1;
		}
		if (send_message(message, bytes, err, err_size))
			return -1;
	}
	return 0;
}

/* Image: the device's bands to rank 0, or the failure. */
static void finish_bands(struct mpi_job *j, int device)
{
	char err[MESSAGE_SIZE], message[MESSAGE_SIZE + 600];
	const struct device *d = &j->devs[device];

	if (j->device_failed[device] ||
	    (j->by_samples ? add_device_sums(j, device, err, sizeof(err))
			   : send_bands(j, device, err, sizeof(err))) == 0)
		return;
	snprintf(message, sizeof(message), "device %d:%d (%s): %s", d->platform_index,
		 d->device_index, d->name, err);
	piece_failed(j, device, message);
}

/* A device is done: its bands (image), then, on ranks other than 0, what it
 * did, for the summary. */
static void device_done(void *context, int device)
{
	struct mpi_job *j = context;
	struct device_report r;

	if (j->image) {
		/* Its set-up came before the clock (open_before_clock). */
		j->work[device].setup_ms += j->setup_ms[device];
		finish_bands(j, device);
	}
	if (j->rank == ROOT)
		return;
	memset(&r, 0, sizeof(r));
	r.device = device;
	r.platform_index = j->devs[device].platform_index;
	r.device_index = j->devs[device].device_index;
	snprintf(r.name, sizeof(r.name), "%s", j->devs[device].name);
	snprintf(r.platform_name, sizeof(r.platform_name), "%s", j->devs[device].platform_name);
	r.work = j->work[device];
	MPI_Send(&r, (int)sizeof(r), MPI_BYTE, ROOT, TAG_DONE, MPI_COMM_WORLD);
}

/* ---- rank 0's server: the other ranks' requests, pixels and reports ----- */

/* The pixel samples of piece: a whole frame, or a band. */
static double piece_work(const struct mpi_job *j, int piece)
{
	const struct render_settings *s = &j->settings;

	if (!j->image)
		return repeats_image_work(s);
	if (j->by_samples) {
		const struct rt_piece *p = &j->tiles.pieces[piece];
		return (double)p->width * p->height * (p->sample_end - p->sample_begin);
	}
	struct rt_piece p = tiles_job_band(&j->tiles, piece, 0, 1);
	return (double)p.width * p.height * p.samples;
}

/* A device of another rank asks for a piece: its previous one is done,
 * which the progress line counts (rank 0's own devices add theirs as they
 * render). */
static void serve_take(struct mpi_job *j, int source)
{
	int device, piece;

	MPI_Recv(&device, 1, MPI_INT, source, TAG_TAKE, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
	int g = device >= 0 && device < j->total ? j->first[source] + device : -1;
	piece = g >= 0 ? central_take(j, g) : -1;
	MPI_Send(&piece, 1, MPI_INT, source, TAG_GIVE + device, MPI_COMM_WORLD);
	if (g < 0)
		return;
	if (j->current[g] >= 0)
		progress_add(NULL, piece_work(j, j->current[g]));
	j->current[g] = piece;
	progress_draw();
}

/* The bytes of piece's pixels: a whole frame, or a band. */
static size_t piece_bytes(const struct mpi_job *j, int piece)
{
	const struct render_settings *s = &j->settings;
	struct rt_piece p;

	if (!j->image)
		return image_float_bytes(s->width, s->height);
	p = tiles_job_band(&j->tiles, piece, 0, 1);
	return image_float_bytes(p.width, p.height);
}

static void serve_result(struct mpi_job *j, const MPI_Status *status)
{
	char *message, err[MESSAGE_SIZE];
	int bytes = 0, piece = -1;

	MPI_Get_count(status, MPI_BYTE, &bytes);
	message = malloc(bytes > 0 ? (size_t)bytes : 1);
	MPI_Recv(message, bytes, MPI_BYTE, status->MPI_SOURCE, TAG_RESULT, MPI_COMM_WORLD,
		 MPI_STATUS_IGNORE);
	if (message && (size_t)bytes >= RESULT_HEADER)
		memcpy(&piece, message, sizeof(int));
	const float *rgb = (const float *)(message + RESULT_HEADER);
	if (piece < 0 || piece >= piece_count(j) || j->by_samples) {
		/* By_samples: the sums travel in reduce_sums, not as pieces. */
		record_failure(j, status->MPI_SOURCE, "a piece number out of range arrived");
	} else if ((size_t)bytes != RESULT_HEADER + piece_bytes(j, piece)) {
		record_failure(j, status->MPI_SOURCE, "a piece arrived incomplete");
	} else if (j->image) {
		place_band(j, piece, rgb);
	} else {
		/* The frame's floats to the front: the buffer becomes the frame. */
		memmove(message, rgb, (size_t)bytes - RESULT_HEADER);
		if (hold_frame(j, piece, (float *)message, err, sizeof(err)))
			record_failure(j, status->MPI_SOURCE, err);
		return;
	}
	free(message);
}

static void serve_fail(struct mpi_job *j, const MPI_Status *status)
{
	char message[MESSAGE_SIZE];
	int length = 0;

	MPI_Get_count(status, MPI_CHAR, &length);
	char *text = malloc(length > 0 ? (size_t)length : 1);
	MPI_Recv(text, length, MPI_CHAR, status->MPI_SOURCE, TAG_FAIL, MPI_COMM_WORLD,
		 MPI_STATUS_IGNORE);
	snprintf(message, sizeof(message), "%.*s", text ? length : 0, text ? text : "");
	free(text);
	record_failure(j, status->MPI_SOURCE, message);
}

/* Returns 1 when a device's report arrived. */
static int serve_done(struct mpi_job *j, int source)
{
	struct device_report r;

	MPI_Recv(&r, (int)sizeof(r), MPI_BYTE, source, TAG_DONE, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
	int g = j->first[source] + r.device;
	if (r.device < 0 || g >= j->total || (source + 1 < j->size && g >= j->first[source + 1]))
		return 1;
	struct device *d = &j->all_devs[g];
	d->platform_index = r.platform_index;
	d->device_index = r.device_index;
	snprintf(d->name, sizeof(d->name), "%s", r.name);
	snprintf(d->platform_name, sizeof(d->platform_name), "%s", r.platform_name);
	j->all_work[g] = r.work;
	return 1;
}

/* Until every device of the other ranks has reported. */
static void *serve(void *context)
{
	struct mpi_job *j = context;
	int remaining = j->total - j->count;
	/* One image: the other ranks' devices ask for their next piece as they
	 * end, inside the image's clock; a nap of 1 ms here held each up to
	 * 1 ms (frames, of hundreds of ms each, keep the longer naps). */
	long max_ns = j->image ? MPI_SERVE_IMAGE_NS : MPI_NAP_MAX_NS;

	while (remaining > 0) {
		MPI_Status status;
		if (wait_probe(&status, max_ns)) {
			record_failure(j, ROOT, "waiting for the other ranks failed");
			MPI_Abort(MPI_COMM_WORLD, EXIT_FAILED);
		}
		switch (status.MPI_TAG) {
		case TAG_TAKE:
			serve_take(j, status.MPI_SOURCE);
			break;
		case TAG_RESULT:
			serve_result(j, &status);
			break;
		case TAG_FAIL:
			serve_fail(j, &status);
			break;
		case TAG_DONE:
			remaining -= serve_done(j, status.MPI_SOURCE);
			break;
		}
	}
	return NULL;
}

/* ---- start, run, finish -------------------------------------------------- */

/* Every rank learns whether all render the same job; rank 0 names the first
 * setting in which the lowest differing rank differs. Returns 0 when all
 * agree. */
static int agree_on_job(struct mpi_job *j)
{
	struct job_digest mine, *all = calloc((size_t)j->size, sizeof(*all));
	char message[MESSAGE_SIZE];

	job_digest_fill(j->job, &mine);
	if (!all || MPI_Allgather(&mine, (int)sizeof(mine), MPI_BYTE, all, (int)sizeof(mine),
				  MPI_BYTE, MPI_COMM_WORLD) != MPI_SUCCESS) {
		fprintf(stderr, "rtcl: rank %d: --mpi: the ranks could not compare their jobs\n",
			j->rank);
		MPI_Abort(MPI_COMM_WORLD, EXIT_FAILED);
	}
	for (int r = 1; r < j->size; r++) {
		if (!job_digest_differs(&all[0], &all[r], r, message, sizeof(message)))
			continue;
		if (j->rank == ROOT)
			fprintf(stderr, "rtcl: %s\n", message);
		free(all);
		return -1;
	}
	free(all);
	return 0;
}

/* Opens this rank's devices, unless rank 0's check of the outputs (checked)
 * failed. Returns 0, OUTPUT_CLASH, or -1 with one message in err. */
static int start_rank(struct mpi_job *j, int checked, char *err, size_t err_size)
{
	if (checked)
		return checked;
	if (j->rank == ROOT && j->job->animation &&
	    output_plan_check_memory(j->plan, err, err_size))
		return -1;
	if (job_open_devices(j->job, j->devs, &j->count, err, err_size)) {
		j->count = 0;
		return -1;
	}
	return 0;
}

/* Rank 0: where each rank's devices fall among all, and the dispenser. */
static int plan_devices(struct mpi_job *j, const int *counts)
{
	j->first = calloc((size_t)j->size + 1, sizeof(int));
	for (int r = 0; j->first && r < j->size; r++)
		j->first[r + 1] = j->first[r] + counts[r];
	j->total = j->first ? j->first[j->size] : 0;
	j->rank_of = calloc((size_t)j->total, sizeof(int));
	j->all_devs = calloc((size_t)j->total, sizeof(struct device));
	j->all_work = calloc((size_t)j->total, sizeof(struct device_work));
	j->current = malloc((size_t)j->total * sizeof(int));
	if (!j->rank_of || !j->all_devs || !j->all_work || !j->current ||
	    dispenser_init(&j->dispenser, piece_count(j), j->total,
			   j->by_samples ? SPLIT_STATIC : j->job->split))
		return -1;
	for (int g = 0; g < j->total; g++)
		j->current[g] = -1;
	for (int r = 0; r < j->size; r++)
		for (int g = j->first[r]; g < j->first[r + 1]; g++)
			j->rank_of[g] = r;
	return 0;
}

/* ---- the sample split's sums, added over the ranks ---------------------
 *
 * Each rank adds its devices' sums into its own; then the ranks' sums are
 * added together. Rank 0 receiving and adding the others' one after another
 * took 126-127 ms after the last device on four H100s (128 MB a rank at
 * 2000x2000, docs/results/h100x4, batch 95). With every rank on one node
 * (the usual case: one rank a GPU), each rank's sums lie in the node's
 * shared memory and each rank adds a quarter (1/size) of every pixel's
 * sums, from all ranks at once, into rank 0's: 8.5-10.3 ms after rank 0's
 * device on four H100s (batch 98). Across nodes MPI_Reduce adds them in a
 * tree, with a user op: it took 306 ms for four ranks of one node there
 * (RTCL_TEST_SUMS_BY_MESSAGES), which the measured choice of the split
 * (choose_measured) then weighs against the bands. Integer sums and joined saturation marks (cl/sample.cl,
 * sample_sums): the same whatever the order, so the same image as one
 * device's. */

/* MPI_Op over pixels' sums (4 int64 each): the channels added, the
 * saturation marks joined, as sample_sums. */
static void add_sums_op(void *in, void *inout, int *len, MPI_Datatype *type)
{
	const cl_long *a = in;
	cl_long *b = inout;

	(void)type;
	for (size_t i = 0; i < 4 * (size_t)*len; i += 4) {
		b[i] += a[i];
		b[i + 1] += a[i + 1];
		b[i + 2] += a[i + 2];
		b[i + 3] |= a[i + 3];
	}
}

/* Whether every rank runs on this one node (then node is the world's ranks
 * in the same order). */
static int one_node(struct mpi_job *j, MPI_Comm *node)
{
	int node_size = 0, node_rank = -1, mine, all = 0;

	if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, node) !=
	    MPI_SUCCESS) {
		*node = MPI_COMM_NULL;
	} else {
		MPI_Comm_size(*node, &node_size);
		MPI_Comm_rank(*node, &node_rank);
	}
	j->node_ranks = node_size > 0 ? node_size : 1;
	mine = node_size == j->size && node_rank == j->rank && !hook_sums_by_messages();
	if (MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD) != MPI_SUCCESS)
		return 0;
	return all;
}

/* Shared: once every rank has zeroed its sums, this rank's block of every
 * rank's sums (what reduce_sums reads and writes) mapped into this process
 * too, a read a page, before the clock. */
static int prefault_block(struct mpi_job *j)
{
	const struct render_settings *s = &j->settings;
	size_t pixels = (size_t)s->width * s->height;
	size_t begin = 4 * (pixels * j->rank / j->size), end = 4 * (pixels * (j->rank + 1) / j->size);
	size_t step = (size_t)sysconf(_SC_PAGESIZE) / sizeof(cl_long);
	volatile cl_long sink = 0;

	if (MPI_Barrier(MPI_COMM_WORLD) != MPI_SUCCESS)
		return -1;
	for (int r = 0; r < j->size; r++)
		for (size_t i = begin; i < end; i += step ? step : 1)
			sink += ((volatile cl_long *)j->slots[r])[i];
	(void)sink;
	return 0;
}

/* By_samples, every rank, before the clock: where this rank's sums are
 * added, and how the ranks' are. Returns 0, or -1 (out of memory). */
static int setup_reduction(struct mpi_job *j)
{
	const struct render_settings *s = &j->settings;
	size_t bytes = image_sum_bytes(s->width, s->height);
	MPI_Comm node;
	void *base = NULL;
	int made = 0, all = 0;

	/* Each rank's slot a whole number of pages, so that every slot starts
	 * on a page where the window does (RTCL_MPI_SUMS=host-ptr makes a
	 * buffer on it, which a driver pins by pages). */
	long page = sysconf(_SC_PAGESIZE);
	size_t slot = page > 0 ? (bytes + (size_t)page - 1) / (size_t)page * (size_t)page : bytes;

	if (one_node(j, &node))
		made = MPI_Win_allocate_shared((MPI_Aint)slot, 1, MPI_INFO_NULL, node, &base,
					       &j->win) == MPI_SUCCESS;
	/* A window made on some ranks only is left to MPI_Finalize. */
	if (MPI_Allreduce(&made, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD) != MPI_SUCCESS)
		all = 0;
	if (node != MPI_COMM_NULL)
		MPI_Comm_free(&node);
	if (all) {
		j->slots = calloc((size_t)j->size, sizeof(*j->slots));
		for (int r = 0; j->slots && r < j->size; r++) {
			MPI_Aint size;
			int unit;
			if (MPI_Win_shared_query(j->win, r, &size, &unit, &j->slots[r]) !=
			    MPI_SUCCESS)
				return -1;
		}
		if (!j->slots)
			return -1;
		j->shared = 1;
		j->sums = j->slots[j->rank];
	} else {
		j->sums = malloc(bytes);
		if (!j->sums ||
		    MPI_Type_contiguous(4, MPI_INT64_T, &j->pixel) != MPI_SUCCESS ||
		    MPI_Type_commit(&j->pixel) != MPI_SUCCESS ||
		    MPI_Op_create(add_sums_op, 1, &j->add_op) != MPI_SUCCESS)
			return -1;
	}
	/* Zeroed and mapped now, by this rank, before the render's clock. */
	memset(j->sums, 0, bytes);
	if (j->shared && prefault_block(j))
		return -1;
	return 0;
}

/* MPI_Barrier, in naps of MPI_NAP_MIN_NS (the ranks' devices end within
 * milliseconds of each other: wait_request's longer naps would add up to
 * one). */
static int wait_barrier(void)
{
	MPI_Request request;
	struct timespec t = {0, MPI_NAP_MIN_NS};
	int done = 0;

	if (MPI_Ibarrier(MPI_COMM_WORLD, &request) != MPI_SUCCESS)
		return -1;
	for (;;) {
		if (MPI_Test(&request, &done, MPI_STATUS_IGNORE) != MPI_SUCCESS)
			return -1;
		if (done)
			return 0;
		nanosleep(&t, NULL);
	}
}

/* By_samples, every rank, once its devices are done: every rank's sums
 * added into rank 0's j->sums, and the pieces' arrivals counted there.
 * Returns 0, or -1 when MPI failed. */
static int reduce_sums(struct mpi_job *j)
{
	const struct render_settings *s = &j->settings;
	size_t pixels = (size_t)s->width * s->height;
	int root = j->rank == ROOT, failed = 0;
	double start = timing_now();

	/* Once every rank is here (its devices done), blocking calls: nothing
	 * of this job is left for the cores they spin on. MPI_Ireduce with
	 * naps took 2.5 s for 128 MB a rank on four H100s' host (batch 98):
	 * a nonblocking collective moves only inside MPI calls. */
	if (wait_barrier())
		return -1;
	/* Every rank's sums are in the node's memory: the image's clock ends
	 * here, as one process's ends when its last device's sums are on the
	 * host (tiles_render); the add is the image's assembly, timed apart. */
	j->sums_in = timing_now();
	if (j->shared) {
		const cl_long **parts = calloc((size_t)j->size, sizeof(*parts));
		size_t begin = pixels * j->rank / j->size, end = pixels * (j->rank + 1) / j->size;
		long cores = sysconf(_SC_NPROCESSORS_ONLN);
		if (!parts)
			return -1;
		for (int r = 0; r < j->size; r++)
			parts[r] = j->slots[r] + 4 * begin;
		/* The node's cores shared among its ranks. */
		tiles_sum_parts(parts, j->size, j->slots[ROOT] + 4 * begin, end - begin,
				(int)(cores / j->size));
		free(parts);
		failed = MPI_Barrier(MPI_COMM_WORLD) != MPI_SUCCESS;
	} else {
		failed = MPI_Reduce(root ? MPI_IN_PLACE : j->sums, j->sums, (int)pixels, j->pixel,
				    j->add_op, ROOT, MPI_COMM_WORLD) != MPI_SUCCESS;
	}
	failed = failed || MPI_Reduce(root ? MPI_IN_PLACE : j->arrived, j->arrived, j->pieces,
				      MPI_INT, MPI_SUM, ROOT, MPI_COMM_WORLD) != MPI_SUCCESS;
	j->reduce_ms = (timing_now() - (j->shared ? j->sums_in : start)) * 1e3;
	return failed ? -1 : 0;
}

/* By_samples, every rank, before MPI_Finalize: the window, type and op. */
static void end_reduction(struct mpi_job *j)
{
	close_slot_buffer(j);
	if (j->shared) {
		MPI_Win_free(&j->win);
		j->shared = 0;
		j->sums = NULL; /* was the window's */
	}
	if (j->add_op != MPI_OP_NULL)
		MPI_Op_free(&j->add_op);
	if (j->pixel != MPI_DATATYPE_NULL)
		MPI_Type_free(&j->pixel);
}

/* Each of the total devices a range of the samples, in whole passes. */
static int split_rank_samples(struct mpi_job *j, int total)
{
	const struct render_settings *s = &j->settings;

	return tiles_split_samples(&j->tiles, total,
				   renderer_pass_samples(s, (long long)s->width * s->height, 1),
				   NULL);
}

/* Rank 0: the dispenser and arrivals for j->pieces pieces again (the
 * measured choice took the bands). */
static int plan_pieces_again(struct mpi_job *j)
{
	dispenser_free(&j->dispenser);
	free(j->arrived);
	j->arrived = calloc((size_t)j->pieces, sizeof(int));
	return !j->arrived ||
	       dispenser_init(&j->dispenser, piece_count(j), j->total, j->job->split);
}

/* For choose_measured, every rank, before the clock (no server yet): what
 * the pixel split's pieces cost to reach rank 0, as the server takes them
 * (serve_result): every other rank sends rank 0 a message of 1/size of the
 * image's pixels (a band of one rank's share, a fresh message filled as
 * send_result does) at once, and rank 0 receives each into fresh memory
 * and copies it into an image. The time from the ranks' barrier to the
 * last copy on rank 0 is *ms on every rank. (Four H100 ranks' bands of a
 * 2048x2048 box reached rank 0 33-40 ms after the devices' end, batch 99:
 * 30 % of the frame, where the sample split's sums go through the node's
 * shared memory.) Returns 0, or -1 when MPI or memory failed. */
static int time_move(struct mpi_job *j, double *ms)
{
	const struct render_settings *s = &j->settings;
	int rows = (s->height + j->size - 1) / j->size;
	size_t bytes = image_float_bytes(s->width, rows);
	double mine = 0;

	*ms = 0;
	if (j->size < 2 || bytes > INT_MAX)
		return 0;
	/* A failure returns at once: the caller ends every rank (MPI_Abort),
	 * which a rank waiting here for another would not see otherwise. */
	char *image = j->rank == ROOT ? malloc(bytes) : NULL;
	if (j->rank == ROOT && !image)
		return -1;
	if (image) /* rank 0's image is touched before the clock */
		pages_touch(image, bytes);
	if (wait_barrier()) {
		free(image);
		return -1;
	}
	double start = timing_now();
	if (j->rank != ROOT) {
		char *message = pages_alloc(0, bytes);
		if (!message)
			return -1;
		memset(message, 0, bytes);
		int status = MPI_Send(message, (int)bytes, MPI_BYTE, ROOT, TAG_MOVE, MPI_COMM_WORLD);
		pages_free(message, 0);
		if (status != MPI_SUCCESS)
			return -1;
	} else {
		for (int r = 1; r < j->size; r++) {
			char *message = malloc(bytes);
			if (!message || MPI_Recv(message, (int)bytes, MPI_BYTE, MPI_ANY_SOURCE,
						 TAG_MOVE, MPI_COMM_WORLD,
						 MPI_STATUS_IGNORE) != MPI_SUCCESS) {
				free(message);
				free(image);
				return -1;
			}
			memcpy(image, message, bytes);
			free(message);
		}
		mine = (timing_now() - start) * 1e3;
		free(image);
	}
	if (MPI_Allreduce(&mine, ms, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD) != MPI_SUCCESS)
		return -1;
	return 0;
}

/* j->measure, every rank, before the clock, once its devices are open and
 * probed (tiles_open): the ranks exchange their devices' probes, and each
 * times the ranks' add of the sums (reduce_sums, of the zeroed sums: they
 * stay zero) and the pixels' way to rank 0 (time_move); every rank then
 * decides the same from the same figures, as one process does
 * (tiles_prefer_samples): the samples, or bands. Returns 0, or -1 when MPI
 * or memory failed. */
static int choose_measured(struct mpi_job *j)
{
	const struct render_settings *s = &j->settings;
	/* Per rank: its device count, its pass's samples, then each device's
	 * pass, its kernels and its read-back. */
	enum { ROW = 2 + 3 * DEVICES_MAX };
	double mine[ROW] = {0}, *all = calloc((size_t)j->size * ROW, sizeof(double));
	double pass_ms[DEVICES_MAX], kernel_ms[DEVICES_MAX], sums_ms[DEVICES_MAX], add_ms = 0;
	double move_ms = 0;
	int unit = tiles_sample_unit(s, j->devs, j->count), n = 0;

	if (!all)
		return -1;
	mine[0] = j->count;
	mine[1] = unit < settings_samples(s) ? unit : 1;
	for (int k = 0; k < j->count; k++) {
		mine[2 + 3 * k] = j->tiles.dev[k].probe_ms;
		mine[3 + 3 * k] = j->tiles.dev[k].probe_kernel_ms;
		mine[4 + 3 * k] = j->tiles.dev[k].sums_ms;
	}
	/* Timed from when all are here: the ranks open their devices at
	 * different speeds. */
	if (wait_barrier())
		goto fail;
	double start = timing_now();
	if (reduce_sums(j))
		goto fail;
	double mine_ms = (timing_now() - start) * 1e3;
	if (MPI_Allreduce(&mine_ms, &add_ms, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD) !=
		    MPI_SUCCESS ||
	    MPI_Allgather(mine, ROW, MPI_DOUBLE, all, ROW, MPI_DOUBLE, MPI_COMM_WORLD) !=
		    MPI_SUCCESS ||
	    time_move(j, &move_ms))
		goto fail;
	for (int r = 0; r < j->size; r++)
		for (int k = 0; k < (int)all[r * ROW] && n < DEVICES_MAX; k++, n++) {
			pass_ms[n] = all[r * ROW + 2 + 3 * k];
			kernel_ms[n] = all[r * ROW + 3 + 3 * k];
			sums_ms[n] = all[r * ROW + 4 + 3 * k];
		}
	/* Rank 0's pass, so that every rank decides alike. */
	int samples = tiles_prefer_samples(pass_ms, kernel_ms, sums_ms, n, (int)all[1],
					   settings_samples(s), add_ms, move_ms, &j->choice);
	free(all);
	memset(j->arrived, 0, (size_t)j->pieces * sizeof(int)); /* the trial's */
	j->measure = 0;
	j->tiles.probe = 0; /* a device opened again by the render's begin is not */
	if (samples)
		return split_rank_samples(j, n);
	j->by_samples = 0;
	tiles_drop_sums(&j->tiles);
	j->pieces = j->tiles.bands;
	return j->rank == ROOT ? plan_pieces_again(j) : 0;

fail:
	free(all);
	return -1;
}

/* choose_pieces: --split samples cannot split this job (said on rank 0). */
#define CHOSEN_BADLY 2

/* Whether the image may be split by samples without --split samples, as
 * the devices' probes decide before the clock (choose_measured): when every
 * device of every rank is a GPU and the samples fit (tiles_samples_fit),
 * and only when no rank is bound to one core (note_binding), where the
 * ranks add the sums. (Before, a fixed 128 samples a device or more: four
 * H100 ranks took the lake at 256 spp in bands, 2.37 times one rank.)
 * On two H200s (batch 82, docs/results/multidevice/README.md, "MPI") two
 * ranks took 780-789 ms split by samples against 816-833 in bands, and 855-869
 * against 832-835 with each rank bound to one core. */
static int samples_by_default(const struct mpi_job *j, int total, int gpus)
{
	const struct job *job = j->job;
	const struct render_settings *s = &j->settings;

	return !job->split_given && !job->row_order_given && total >= 2 && gpus == total &&
	       j->bound_ranks == 0 && tiles_samples_fit(s, total, job->piece_rows);
}

/* The pieces, once every rank's device count is known: the frames, or the
 * image's bands over all devices (total, of which gpus are GPUs). With the
 * dynamic split and no --piece-rows, GPUs alone take one band per device,
 * a class each, as --split static gives them: smaller bands leave a GPU's
 * launches too few pixels (two H200s, batch 58: 6.57 s in 63 bands against
 * 1.16 s in 2); with a CPU among the devices, about TILES_PER_DEVICE bands
 * per device, so that the slow one cannot hold up the end. */
static int choose_pieces(struct mpi_job *j, int total, int gpus)
{
	const struct job *job = j->job;
	const struct render_settings *s = &j->settings;
	char err[MESSAGE_SIZE];

	/* Every rank reads the same environment: rank 0 says why. */
	j->slot_way = slot_way_from_env();
	if (j->slot_way < 0) {
		if (j->rank == ROOT)
			fprintf(stderr,
				"rtcl: RTCL_MPI_SUMS=%s: expected copy, read or host-ptr (how "
				"--mpi's ranks put their sample sums into the node's shared "
				"memory), or leave it unset\n",
				getenv("RTCL_MPI_SUMS"));
		return CHOSEN_BADLY;
	}
	if (!j->image) {
		j->pieces = job_frame_count(job);
		return 0;
	}
	struct rt_piece map = {0};
	/* One class per device of every rank (--row-order's S). */
	tiles_row_map(&map, s, job->row_order, job->row_classes ? job->row_classes : total);
	enum split bands = gpus == total ? SPLIT_STATIC : job->split;
	if (tiles_job_init(&j->tiles, job->scene, s, tiles_band_rows(s, job->piece_rows, total, bands),
			   0, &map, j->devs, j->count, err, sizeof(err)))
		return -1;
	j->pieces = j->tiles.bands;
	/* Every rank decides the same from the same job and counts: rank 0
	 * says why, and all stop. */
	if (job->split == SPLIT_SAMPLES && tiles_check_sample_split(s, total, err, sizeof(err))) {
		if (j->rank == ROOT)
			fprintf(stderr, "rtcl: %s\n", err);
		return CHOSEN_BADLY;
	}
	/* The sums travel in no message of their own (reduce_sums; MPI_Reduce
	 * counts pixels, at most 32768 squared, in an int): no limit of 2 GiB
	 * a message, as when each rank sent rank 0 its sums. */
	j->measure = job->split != SPLIT_SAMPLES && samples_by_default(j, total, gpus);
	j->by_samples = job->split == SPLIT_SAMPLES || j->measure;
	if (j->measure) {
		/* Each device probed as its renderer opens (tiles_open); the
		 * sample pieces made once the probes favour them. */
		j->tiles.by_samples = 1;
		j->tiles.probe = 1;
	} else if (j->by_samples && split_rank_samples(j, total)) {
		return -1;
	}
	if (j->by_samples) {
		j->pieces = total;
		/* Each device's sums are read back into pinned memory, allocated
		 * as its renderer opens (tiles_open), before the render's clock;
		 * this rank's added, and the ranks' reduced, in memory set up
		 * now. */
		if (setup_reduction(j))
			return -1;
		/* One device: its sums read in parts, each copied into the
		 * slot as it arrives (read_sums_into_slot). */
		j->tiles.sums_later = j->shared && j->count == 1;
	}
	if (j->rank != ROOT && !j->by_samples)
		return 0;
	j->arrived = calloc((size_t)j->pieces, sizeof(int));
	if (j->rank != ROOT)
		return j->arrived ? 0 : -1;
	j->record->result.rgb = calloc(1, image_float_bytes(s->width, s->height));
	if (!j->arrived || !j->record->result.rgb)
		return -1;
	/* Mapped now, before the render's clock starts, so that the bands
	 * written into it later do not pay its pages' first faults (about
	 * 25 ms for 2000x2000 here). */
	pages_touch(j->record->result.rgb, image_float_bytes(s->width, s->height));
	return 0;
}

/* This rank's GPUs (all its devices under RTCL_TEST_AS_GPUS). */
static int rank_gpus(const struct mpi_job *j)
{
	int gpus = 0;

	for (int k = 0; k < j->count; k++)
		gpus += j->devs[k].is_gpu != 0 || hook_devices_as_gpus();
	return gpus;
}

/* Every rank learns whether all started, and every rank's device and GPU
 * counts; the lowest rank that did not start says why. failed: 0, -1, or
 * OUTPUT_CLASH (a usage error). Returns 0 when all started, else the exit
 * status of the lowest rank's failure. */
static int agree_on_start(struct mpi_job *j, int failed, const char *err)
{
	int mine[2] = {failed == OUTPUT_CLASH ? -2 : failed ? -1 : j->count,
		       failed ? 0 : rank_gpus(j)};
	int lowest = -1;
	int *pairs = malloc((size_t)j->size * 2 * sizeof(int));
	int *counts = malloc((size_t)j->size * sizeof(int));

	if (!pairs || !counts ||
	    MPI_Allgather(mine, 2, MPI_INT, pairs, 2, MPI_INT, MPI_COMM_WORLD) != MPI_SUCCESS) {
		fprintf(stderr,
			"rtcl: rank %d: --mpi: the ranks could not exchange their "
			"device counts\n",
			j->rank);
		MPI_Abort(MPI_COMM_WORLD, EXIT_FAILED);
	}
	int total = 0, gpus = 0;
	for (int r = 0; r < j->size; r++) {
		counts[r] = pairs[2 * r];
		total += counts[r];
		gpus += pairs[2 * r + 1];
	}
	free(pairs);
	for (int r = j->size - 1; r >= 0; r--)
		if (counts[r] < 0)
			lowest = r;
	if (lowest == j->rank)
		fprintf(stderr, "rtcl: rank %d: %s\n", j->rank, err);
	int chosen = lowest < 0 ? choose_pieces(j, total, gpus) : 0;
	if (lowest < 0 && chosen != CHOSEN_BADLY &&
	    (chosen || (j->rank == ROOT && plan_devices(j, counts)))) {
		fprintf(stderr, "rtcl: out of host memory for the device plan\n");
		MPI_Abort(MPI_COMM_WORLD, EXIT_FAILED);
	}
	int status = chosen == CHOSEN_BADLY	 ? EXIT_USAGE
		     : lowest < 0		 ? 0
		     : counts[lowest] == -2 ? EXIT_USAGE
					    : EXIT_FAILED;
	free(counts);
	return status;
}

/* Rank 0, image: every band arrived once, then the result the outputs and
 * the summary read. Returns 0, or -1 with the failure recorded. */
static int assemble_image(struct mpi_job *j, double wall_ms)
{
	struct record *record = j->record;
	struct render_result *res = &record->result;
	char message[256];

	for (int b = 0; b < j->pieces; b++) {
		if (j->arrived[b] != 1) {
			snprintf(message, sizeof(message), "band %d of the image arrived %d times",
				 b, j->arrived[b]);
			record_failure(j, ROOT, message);
			return -1;
		}
	}
	res->kernel_ms = malloc(sizeof(double));
	res->frame_ms = malloc(sizeof(double));
	if (!res->kernel_ms || !res->frame_ms) {
		record_failure(j, ROOT, "out of host memory");
		return -1;
	}
	res->kernel_ms[0] = res->kernel_ms_median = res->kernel_ms_min = res->kernel_ms_max =
		wall_ms;
	res->frame_ms[0] = res->frame_ms_median = wall_ms;
	res->repeat = res->launches = 1;
	res->passes = 1;
	if (j->by_samples)
		tiles_mean_of_sums(&j->settings, j->sums, res->rgb);
	tiles_copy_facts(&j->tiles.dev[0].result, res);
	record_device(record, &j->devs[0]);
	snprintf(record->device.name, sizeof(record->device.name),
		 "%d devices over %d ranks, first %s", j->total, j->size, j->devs[0].name);
	record->shares.band_rows = j->tiles.rows;
	record->shares.bands = j->pieces;
	return 0;
}

/* Rank 0 after every device is done: every piece arrived once, or the
 * failure, printed. Returns the exit status. */
static int finish_root(struct mpi_job *j)
{
	char err[MESSAGE_SIZE];

	for (int k = 0; k < j->count; k++) {
		j->all_devs[k] = j->devs[k];
		j->all_work[k] = j->work[k];
	}
	j->record->shares = (struct device_shares){
		.devs = j->all_devs,
		.ranks = j->rank_of,
		.work = j->all_work,
		.count = j->total,
		.ranks_count = j->image ? j->size : 0,
		.rank_sums = !j->by_samples ? NULL : j->shared ? "shared memory" : "MPI_Reduce",
		.rank_sums_into_slot =
			j->by_samples && j->tiles.sums_later ? slot_way_names[j->slot_way] : NULL,
		.rank_sums_ms = j->reduce_ms,
		.split = j->by_samples ? SPLIT_SAMPLES : j->job->split,
		.piece = j->by_samples ? "sample range" : j->image ? "band" : "frame",
		.wall_ms = j->wall_ms,
		.row_order_given = j->image,
		.choice = j->choice,
	};
	if (j->image)
		j->record->shares.rows = j->tiles.row_map;
	if (!j->failed && j->image)
		assemble_image(j, j->wall_ms);
	else if (!j->failed && output_plan_check_held(j->plan, err, sizeof(err)))
		record_failure(j, ROOT, err);
	if (!j->failed)
		return 0;
	fprintf(stderr, "rtcl: %s\n", j->message);
	return EXIT_FAILED;
}

/* Image: every rank opens its devices (program, scene upload, the sums'
 * host copy) before the clock starts, all at once, as one process does
 * before its frames (tiles_render): the image time is the render's, and
 * each rank's own set-up (the lake's BVH build: 2.2-2.6 s on the H200s'
 * host) is reported apart. A device that fails here is opened again by the
 * render's begin, which reports it as before. Then the ranks start
 * together. */
static void open_before_clock(struct mpi_job *j)
{
	struct device_work setup[DEVICES_MAX];
	char err[MESSAGE_SIZE];
	MPI_Request request;

	memset(setup, 0, sizeof(setup));
	tiles_open_all(&j->tiles, setup, err, sizeof(err));
	for (int k = 0; k < j->count; k++)
		j->setup_ms[k] = setup[k].setup_ms;
	if (j->measure && choose_measured(j)) {
		fprintf(stderr, "rtcl: rank %d: --mpi: choosing the split from the devices' "
				"probes failed\n",
			j->rank);
		MPI_Abort(MPI_COMM_WORLD, EXIT_FAILED);
	}
	if (j->by_samples && j->tiles.sums_later && j->slot_way == SLOT_HOST_PTR) {
		double lap = timing_now();
		open_slot_buffer(j);
		j->setup_ms[0] += timing_lap_ms(&lap); /* device 0's set-up */
	}
	/* The ranks set up for seconds, at different speeds: a barrier in
	 * naps of up to 1 ms, then one in short naps, so that the ranks leave
	 * within tens of microseconds of each other. (With the first alone, a
	 * rank left up to a nap after rank 0 had started the clock: four H100
	 * ranks' devices ended 0.7-1.0 ms after rank 0's, batch 98c.) */
	if (MPI_Ibarrier(MPI_COMM_WORLD, &request) != MPI_SUCCESS || wait_request(&request) ||
	    wait_barrier())
		MPI_Abort(MPI_COMM_WORLD, EXIT_FAILED);
}

/* Every rank's devices render; rank 0 serves the others meanwhile. Every
 * rank learns whether the render succeeded. Returns the exit status. */
static int render_all(struct mpi_job *j)
{
	if (j->image)
		open_before_clock(j); /* may choose the split (choose_measured) */
	struct multidev_job job = {.piece_count = piece_count(j),
				   .split =
					   j->job->split == SPLIT_DYNAMIC && !j->by_samples
						   ? SPLIT_DYNAMIC
						   : SPLIT_STATIC,
				   .begin = j->image ? open_rank_device : NULL,
				   .render_piece = render_rank_piece,
				   .end = device_done,
				   .take_piece = take_rank_piece,
				   .failed = piece_failed,
				   .context = j};
	char err[MESSAGE_SIZE];
	pthread_t server;
	int status = 0;

	double start = timing_now();

	if (j->rank == ROOT) {
		char ranks[32];
		snprintf(ranks, sizeof(ranks), "%d rank%s", j->size, j->size == 1 ? "" : "s");
		repeats_progress_begin(&j->settings, j->image ? 1 : piece_count(j), ranks);
	}
	if (j->rank == ROOT && pthread_create(&server, NULL, serve, j) != 0) {
		fprintf(stderr, "rtcl: cannot start rank 0's server thread\n");
		MPI_Abort(MPI_COMM_WORLD, EXIT_FAILED);
	}
	multidev_run(&job, j->devs, j->count, j->work, err, sizeof(err));
	if (j->by_samples && reduce_sums(j)) {
		fprintf(stderr, "rtcl: rank %d: --mpi: adding the ranks' sample sums failed\n",
			j->rank);
		MPI_Abort(MPI_COMM_WORLD, EXIT_FAILED);
	}
	if (j->rank == ROOT) {
		pthread_join(server, NULL);
		progress_end();
		/* Split by samples in the node's shared memory: the image time
		 * ends once every rank's sums are there (reduce_sums), as one
		 * process's frame ends with its devices' sums on the host; the
		 * ranks' add follows, as one process's (multidevice.rank_sums). */
		j->wall_ms = ((j->by_samples && j->shared ? j->sums_in : timing_now()) - start) *
			     1e3;
		status = finish_root(j);
	}
	/* The other ranks wait here while rank 0's own devices finish. */
	MPI_Request request;
	if (MPI_Ibcast(&status, 1, MPI_INT, ROOT, MPI_COMM_WORLD, &request) != MPI_SUCCESS ||
	    wait_request(&request))
		MPI_Abort(MPI_COMM_WORLD, EXIT_FAILED);
	return status;
}

static void free_job(struct mpi_job *j)
{
	tiles_job_free(&j->tiles); /* the renderers, before their devices */
	devices_close(j->devs, j->count);
	free(j->arrived);
	if (!j->shared)
		free(j->sums);
	free(j->slots);
	free(j->first);
	free(j->rank_of);
	dispenser_free(&j->dispenser);
	free(j->current);
	free(j->all_devs);
	free(j->all_work);
	pthread_mutex_destroy(&j->lock);
	pthread_mutex_destroy(&j->sums_lock);
}

/* Starts MPI; only rank 0 writes the outputs. */
static int mpi_begin(struct mode_run *run, char *err, size_t err_size)
{
	struct mpi_job *j = calloc(1, sizeof(*j));
	int provided = 0;

	if (!j) {
		snprintf(err, err_size, "out of host memory");
		return EXIT_FAILED;
	}
	run->state = j;
	pthread_mutex_init(&j->lock, NULL);
	pthread_mutex_init(&j->sums_lock, NULL);
	j->job = run->job;
	j->record = run->record;
	j->plan = run->plan;
	j->image = !run->job->animation;
	j->settings = run->job->settings;
	j->settings.check_writes |= j->image && hook_count_writes();
	/* Rank 0 shows the line for every rank; render() only adds to it. */
	j->settings.progress = 0;
	if (MPI_Init_thread(NULL, NULL, MPI_THREAD_MULTIPLE, &provided) != MPI_SUCCESS) {
		snprintf(err, err_size, "--mpi: MPI_Init_thread failed (run rtcl under mpirun)");
		run->writes = 0;
		return EXIT_FAILED;
	}
	j->initialized = 1;
	j->pixel = MPI_DATATYPE_NULL;
	j->add_op = MPI_OP_NULL;
	j->threads = provided >= MPI_THREAD_MULTIPLE;
	MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
	MPI_Comm_rank(MPI_COMM_WORLD, &j->rank);
	MPI_Comm_size(MPI_COMM_WORLD, &j->size);
	run->writes = j->rank == ROOT;
	if (j->rank != ROOT)
		progress_init(0);
	interrupt_set_outcome("no output written (under --mpi, mpirun ends every rank when one "
			      "dies or is interrupted: see its report)");
	return 0;
}

/* Rank 0 notes (unless -q) when mpirun bound a rank to one core of
 * several: that rank's host threads (the scene's BVH build, the sums of the
 * sample split, a CPU device's work) then share it. On two H200s, Open MPI's
 * default binding made the lake's BVH build take 4.6-5.4 s instead of
 * 2.2-2.6 (docs/results/multidevice/README.md, "MPI"). */
static void note_binding(struct mpi_job *j)
{
	cpu_set_t set;
	long online = sysconf(_SC_NPROCESSORS_ONLN);
	int mine = sched_getaffinity(0, sizeof(set), &set) == 0 ? CPU_COUNT(&set) : 0;
	int one = mine == 1 && online > 1, count = 0, first = one ? j->rank : INT_MAX, lowest;

	if (MPI_Allreduce(&one, &count, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD) != MPI_SUCCESS ||
	    MPI_Allreduce(&first, &lowest, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD) != MPI_SUCCESS ||
	    !count)
		return;
	j->bound_ranks = count;
	if (j->rank != ROOT || j->job->quiet)
		return;
	fprintf(stderr,
		"rtcl: note: mpirun bound %d of %d rank(s) to one core each (rank %d to one of "
		"%ld): a rank's BVH build, sample sums and CPU devices then run on that core "
		"alone; start rtcl with `mpirun --bind-to none`, or give each rank cores "
		"(--map-by slot:PE=N)\n",
		count, j->size, lowest, online);
}

/* Every rank agrees on the job and on starting (rank 0's check of the
 * outputs included), then renders. Each rank prints its own failure. */
static int mpi_render(struct mode_run *run, int checked, char *err, size_t err_size)
{
	struct mpi_job *j = run->state;

	if (!j->threads) {
		snprintf(err, err_size,
			 "--mpi: this MPI library does not give threads MPI_THREAD_MULTIPLE");
		agree_on_start(j, 1, err);
		err[0] = '\0';
		return EXIT_FAILED;
	}
	if (agree_on_job(j)) {
		err[0] = '\0'; /* rank 0 printed it */
		return EXIT_FAILED;
	}
	note_binding(j);
	int status = agree_on_start(j, start_rank(j, checked, err, err_size), err);
	err[0] = '\0'; /* printed by the rank that failed */
	if (status)
		/* Said; a rank that exits first makes mpirun end this one, which
		 * must not add "interrupted" to the reason. */
		interrupt_set_outcome(NULL);
	return status ? status : render_all(j);
}

/* Rank 0 writes once every rank has finalised. A rank that dies makes Open
 * MPI's daemon send the others SIGCONT, SIGTERM after
 * odls_base_sigkill_timeout (1 s), then SIGKILL after as long again; but
 * that sleep(1) returns 0 when the SIGCHLD of a rank that exits on the
 * SIGTERM interrupts it, so SIGKILL follows in about 5 ms (strace of Open
 * MPI 4.1.4's mpirun), and a busy rank 0 is killed before its interrupt
 * thread can remove its staged files (left behind before this design, which
 * staged each frame as it arrived). Hence: until here, rank 0 has created
 * nothing in the output folder (the frames, or the image, are in memory),
 * so a rank that dies before it leaves nothing; from here no other rank is
 * left to die, and the writing (staging, then one commit) takes about
 * 10-90 ms a frame (README). */
static void mpi_end(struct mode_run *run, int status)
{
	struct mpi_job *j = run->state;

	if (!j || !j->initialized)
		return;
	end_reduction(j);
	MPI_Finalize();
	if (j->rank != ROOT && status == 0)
		interrupt_set_outcome(
			"this rank's pieces were delivered; rank 0 writes the outputs");
	if (j->rank == ROOT && status == 0)
		interrupt_watch_mpirun();
}

static void mpi_summary(const struct mode_run *run, FILE *out)
{
	if (run->job->animation)
		mode_summary_frames(run, out);
	else
		mode_summary_image(run, out);
}

static void mpi_release(struct mode_run *run)
{
	struct mpi_job *j = run->state;

	if (!j)
		return;
	free_job(j);
	free(j);
	run->state = NULL;
}

const struct mode mpi_mode = {
	.name = "mpi",
	.begin = mpi_begin,
	.render = mpi_render,
	.checks_in_render = 1,
	.end = mpi_end,
	.summary = mpi_summary,
	.release = mpi_release,
};
