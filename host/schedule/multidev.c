#include "schedule/multidev.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/test_hooks.h"
#include "base/timing.h"

#define WORKER_ERR_SIZE 4096

/* What the threads share: the pieces and the first failure, under lock. */
struct pool {
	pthread_mutex_t lock;
	const struct multidev_job *job;
	struct dispenser pieces; /* unless the job has its own take_piece */
	int failed;		 /* a piece failed: hand out no more */
	double start;		 /* timing_now() when the job started */
};

struct worker {
	struct pool *pool;
	struct device *dev;
	int index;
	struct device_work *work;
	int failed;
	char err[WORKER_ERR_SIZE];
};

/* The next piece for device k, or -1 when there is none left for it. */
static int pool_take(struct pool *p, int k)
{
	int piece = -1;

	if (p->job->take_piece) {
		pthread_mutex_lock(&p->lock);
		int failed = p->failed;
		pthread_mutex_unlock(&p->lock);
		return failed ? -1 : p->job->take_piece(p->job->context, k);
	}
	pthread_mutex_lock(&p->lock);
	if (!p->failed)
		piece = dispenser_take(&p->pieces, k);
	pthread_mutex_unlock(&p->lock);
	return piece;
}

static void mark_failed(struct pool *p)
{
	pthread_mutex_lock(&p->lock);
	p->failed = 1;
	pthread_mutex_unlock(&p->lock);
}

/* "DEVICE P:D (NAME): what failed" */
static void describe_failure(const struct worker *w, char *out, size_t size)
{
	snprintf(out, size, "device %d:%d (%s): %s", w->dev->platform_index, w->dev->device_index,
		 w->dev->name, w->err);
}

/* Stops the job after w's failure, telling the job's failed callback. */
static void fail(struct worker *w)
{
	const struct multidev_job *job = w->pool->job;
	char message[WORKER_ERR_SIZE + 600];

	w->failed = 1;
	mark_failed(w->pool);
	if (job->failed) {
		describe_failure(w, message, sizeof(message));
		job->failed(job->context, w->index, message);
	}
}

/* One piece, with the test-only delay and fault (base/test_hooks.h) around it. */
static int render_one(struct worker *w, int piece, struct piece_work *done)
{
	const struct multidev_job *job = w->pool->job;
	double start = timing_now();
	int ret = job->render_piece(job->context, w->index, piece, done, w->err, sizeof(w->err));

	hook_piece_delay(w->index, (timing_now() - start) * 1e3);
	if (ret == 0 && hook_piece_fault(w->index, w->work->pieces + 1)) {
		snprintf(w->err, sizeof(w->err),
			 "the device failed on its piece %d (RTCL_TEST_FAIL_DEVICE)",
			 w->work->pieces + 1);
		ret = -1;
	}
	return ret;
}

static void *work_loop(void *arg)
{
	struct worker *w = arg;
	const struct multidev_job *job = w->pool->job;
	double lap = timing_now(), piece_ms;
	int piece;

	if (job->begin && job->begin(job->context, w->index, w->err, sizeof(w->err))) {
		fail(w);
		return NULL;
	}
	w->work->setup_ms = timing_lap_ms(&lap);
	while ((piece = pool_take(w->pool, w->index)) >= 0) {
		struct piece_work done = {0};
		if (render_one(w, piece, &done)) {
			fail(w);
			break;
		}
		w->work->pieces++;
		w->work->pixels += done.pixels;
		w->work->kernel_ms += done.kernel_ms;
		w->work->launches += done.launches;
		piece_ms = timing_lap_ms(&lap);
		w->work->busy_ms += piece_ms;
		if (w->work->pieces == 1)
			w->work->first_piece_ms = piece_ms;
		w->work->last_piece_ms = piece_ms;
		w->work->finish_ms = (lap - w->pool->start) * 1e3;
	}
	if (job->end)
		job->end(job->context, w->index);
	return NULL;
}

static int init_pool(struct pool *p, const struct multidev_job *job, int count)
{
	memset(p, 0, sizeof(*p));
	p->job = job;
	p->start = timing_now();
	if (dispenser_init(&p->pieces, job->piece_count, count, job->split))
		return -1;
	pthread_mutex_init(&p->lock, NULL);
	return 0;
}

/* The first failed device's message (by device order), with its name. */
static void report_failure(const struct worker *workers, int count, char *err, size_t err_size)
{
	for (int k = 0; k < count; k++) {
		const struct worker *w = &workers[k];
		if (w->failed) {
			describe_failure(w, err, err_size);
			return;
		}
	}
}

int multidev_run(const struct multidev_job *job, struct device *devs, int count,
		 struct device_work *work, char *err, size_t err_size)
{
	/* Each call its own workers: several jobs may run at once on disjoint
	 * devices (--frames' last frames, run/frames.c). */
	struct worker *workers = calloc((size_t)(count > 0 ? count : 1), sizeof(*workers));
	pthread_t threads[DEVICES_MAX];
	struct pool pool;
	int started = 0, failed = 0;

	memset(work, 0, (size_t)count * sizeof(*work));
	if (!workers || init_pool(&pool, job, count)) {
		free(workers);
		snprintf(err, err_size, "out of host memory for the pieces of %d devices", count);
		return -1;
	}
	for (int k = 0; k < count; k++) {
		workers[k] = (struct worker){&pool, &devs[k], k, &work[k], 0, ""};
		if (pthread_create(&threads[k], NULL, work_loop, &workers[k]) != 0) {
			snprintf(err, err_size, "cannot start a host thread for device %d", k);
			mark_failed(&pool);
			failed = 1;
			break;
		}
		started++;
	}
	for (int k = 0; k < started; k++)
		pthread_join(threads[k], NULL);
	pthread_mutex_destroy(&pool.lock);
	dispenser_free(&pool.pieces);
	for (int k = 0; k < started; k++)
		failed |= workers[k].failed;
	if (failed && started == count)
		report_failure(workers, count, err, err_size);
	free(workers);
	return failed ? -1 : 0;
}

double multidev_efficiency(const struct device_work *work, int count)
{
	double sum = 0, max = 0;

	for (int k = 0; k < count; k++) {
		sum += work[k].busy_ms;
		max = work[k].busy_ms > max ? work[k].busy_ms : max;
	}
	return max > 0 ? sum / count / max : 1.0;
}
