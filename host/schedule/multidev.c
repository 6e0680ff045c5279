#include "schedule/multidev.h"

#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "base/test_hooks.h"
#include "base/timing.h"

#define WORKER_ERR_SIZE 4096

/* What the threads share: the dispenser and the first failure. */
struct dispenser {
	pthread_mutex_t lock;
	const struct multidev_job *job;
	int count; /* devices */
	int next;  /* dynamic: the next piece to hand out */
	int next_static[DEVICES_MAX], end_static[DEVICES_MAX];
	int failed;   /* a piece failed: hand out no more */
	double start; /* timing_now() when the job started */
};

struct worker {
	struct dispenser *dispenser;
	struct device *dev;
	int index;
	struct device_work *work;
	int failed;
	char err[WORKER_ERR_SIZE];
};

int multidev_static_first(int k, int n, int count)
{
	return (int)((long long)k * count / n);
}

/* The next piece for device k, or -1 when there is none left for it. */
static int dispenser_take(struct dispenser *d, int k)
{
	int piece = -1;

	if (d->job->take_piece) {
		pthread_mutex_lock(&d->lock);
		int failed = d->failed;
		pthread_mutex_unlock(&d->lock);
		return failed ? -1 : d->job->take_piece(d->job->context, k);
	}
	pthread_mutex_lock(&d->lock);
	if (d->failed)
		piece = -1;
	else if (d->job->split == SPLIT_STATIC)
		piece = d->next_static[k] < d->end_static[k] ? d->next_static[k]++ : -1;
	else if (d->next < d->job->piece_count)
		piece = d->next++;
	pthread_mutex_unlock(&d->lock);
	return piece;
}

static void mark_failed(struct dispenser *d)
{
	pthread_mutex_lock(&d->lock);
	d->failed = 1;
	pthread_mutex_unlock(&d->lock);
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
	const struct multidev_job *job = w->dispenser->job;
	char message[WORKER_ERR_SIZE + 600];

	w->failed = 1;
	mark_failed(w->dispenser);
	if (job->failed) {
		describe_failure(w, message, sizeof(message));
		job->failed(job->context, w->index, message);
	}
}

/* One piece, with the test-only delay and fault (base/test_hooks.h) around it. */
static int render_one(struct worker *w, int piece, struct piece_work *done)
{
	const struct multidev_job *job = w->dispenser->job;
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
	const struct multidev_job *job = w->dispenser->job;
	double lap = timing_now(), piece_ms;
	int piece;

	if (job->begin && job->begin(job->context, w->index, w->err, sizeof(w->err))) {
		fail(w);
		return NULL;
	}
	w->work->setup_ms = timing_lap_ms(&lap);
	while ((piece = dispenser_take(w->dispenser, w->index)) >= 0) {
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
		w->work->last_piece_ms = piece_ms;
		w->work->finish_ms = (lap - w->dispenser->start) * 1e3;
	}
	if (job->end)
		job->end(job->context, w->index);
	return NULL;
}

static void init_dispenser(struct dispenser *d, const struct multidev_job *job, int count)
{
	memset(d, 0, sizeof(*d));
	pthread_mutex_init(&d->lock, NULL);
	d->job = job;
	d->count = count;
	d->start = timing_now();
	for (int k = 0; k < count; k++) {
		d->next_static[k] = multidev_static_first(k, count, job->piece_count);
		d->end_static[k] = multidev_static_first(k + 1, count, job->piece_count);
	}
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
	static struct worker workers[DEVICES_MAX];
	pthread_t threads[DEVICES_MAX];
	struct dispenser dispenser;
	int started = 0, failed = 0;

	init_dispenser(&dispenser, job, count);
	memset(work, 0, (size_t)count * sizeof(*work));
	for (int k = 0; k < count; k++) {
		workers[k] = (struct worker){&dispenser, &devs[k], k, &work[k], 0, ""};
		if (pthread_create(&threads[k], NULL, work_loop, &workers[k]) != 0) {
			snprintf(err, err_size, "cannot start a host thread for device %d", k);
			mark_failed(&dispenser);
			failed = 1;
			break;
		}
		started++;
	}
	for (int k = 0; k < started; k++)
		pthread_join(threads[k], NULL);
	pthread_mutex_destroy(&dispenser.lock);
	for (int k = 0; k < started; k++)
		failed |= workers[k].failed;
	if (failed && started == count)
		report_failure(workers, count, err, err_size);
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
