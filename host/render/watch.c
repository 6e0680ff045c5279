#include "render/watch.h"

#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "base/progress.h"

int watch_create_counter(struct device *dev, cl_command_queue queue, int watched,
			 size_t extra_bytes, struct work_counter *c, char *err,
			 size_t err_size)
{
	size_t bytes = RT_COUNTER_WORDS * sizeof(cl_uint);
	int in_place = watched && dev->host_unified;
	cl_int status = CL_SUCCESS;

	memset(c, 0, sizeof(*c));
	c->queue = queue;
	c->watched = watched;
	c->buffer = device_create_buffer(dev,
					 CL_MEM_READ_WRITE | (in_place ? CL_MEM_ALLOC_HOST_PTR : 0),
					 bytes + extra_bytes, NULL, "work counter", err, err_size);
	if (!c->buffer)
		return -1;
	if (in_place)
		c->mapped = clEnqueueMapBuffer(queue, c->buffer, CL_TRUE, CL_MAP_READ, 0,
					       bytes, 0, NULL, NULL, &status);
	else if (watched)
		c->side_queue = clCreateCommandQueue(dev->context, dev->id, 0, &status);
	if (status == CL_SUCCESS)
		return 0;
	snprintf(err, err_size, "%s failed for the work counter on %s: %s",
		 in_place ? "clEnqueueMapBuffer" : "clCreateCommandQueue", dev->name,
		 cl_error_name(status));
	return -1;
}

/* Waits for the read in flight, if any. */
static void finish_reading(struct work_counter *c)
{
	if (!c->reading)
		return;
	clWaitForEvents(1, &c->reading);
	clReleaseEvent(c->reading);
	c->reading = NULL;
}

cl_int watch_reset_counter(struct work_counter *c)
{
	cl_uint zero = 0;

	finish_reading(c);
	if (c->reset)
		clReleaseEvent(c->reset);
	c->reset = NULL;
	memset(c->copy, 0, sizeof(c->copy));
	return clEnqueueFillBuffer(c->queue, c->buffer, &zero, sizeof(zero), 0, sizeof(c->copy), 0,
				   NULL, c->watched ? &c->reset : NULL);
}

void watch_release_counter(struct work_counter *c)
{
	finish_reading(c);
	if (c->reset)
		clReleaseEvent(c->reset);
	if (c->mapped) {
		clEnqueueUnmapMemObject(c->queue, c->buffer, c->mapped, 0, NULL, NULL);
		clFinish(c->queue);
	}
	if (c->side_queue)
		clReleaseCommandQueue(c->side_queue);
	if (c->buffer)
		clReleaseMemObject(c->buffer);
	memset(c, 0, sizeof(*c));
}

/* The counter's word as last seen: in place, or from the last finished
 * read, starting the next. */
static cl_uint read_counter(struct work_counter *c, int word)
{
	cl_int state = CL_QUEUED;

	if (c->mapped) {
		/* Before the zeroing has run the words are the last launch's. */
		if (clGetEventInfo(c->reset, CL_EVENT_COMMAND_EXECUTION_STATUS, sizeof(state),
				   &state, NULL) != CL_SUCCESS ||
		    state != CL_COMPLETE)
			return 0;
		return __atomic_load_n(&c->mapped[word], __ATOMIC_RELAXED);
	}
	if (c->reading &&
	    clGetEventInfo(c->reading, CL_EVENT_COMMAND_EXECUTION_STATUS, sizeof(state), &state,
			   NULL) == CL_SUCCESS &&
	    state <= CL_COMPLETE) {
		clReleaseEvent(c->reading); /* done, or failed: a later read tries again */
		c->reading = NULL;
	}
	if (!c->reading &&
	    clEnqueueReadBuffer(c->side_queue, c->buffer, CL_FALSE, 0, sizeof(c->copy), c->copy,
				c->reset ? 1 : 0, c->reset ? &c->reset : NULL,
				&c->reading) == CL_SUCCESS)
		clFlush(c->side_queue);
	return c->copy[word];
}

/* Shows how far the launch is: its share of the work from the counter. */
static void show_share(const struct launch_watch *w)
{
	if (!w || !w->counter || !w->counter->watched)
		return;
	double count = read_counter(w->counter, w->word) * w->pixels_per_count;
	double share = count < w->pixels ? count / w->pixels : 1;
	progress_partial(w->slot, share * w->work);
}

/* The launches being waited for while the progress line is shown, one per
 * device at most, and the ticker thread that reads their counters and
 * redraws the line every PROGRESS_TICK_MS. The thread that waits for a
 * launch blocks in clWaitForEvents and so returns the moment the launch
 * ends: waiting in ticks, or for an event callback, added 17 ms to every
 * pass on the H100 (docs/results/h100-batch6, run 24). The ticker draws
 * only while some launch is waited for, and touches a watch's counter only
 * while it is in the list, under watch_lock. */
static pthread_mutex_t watch_lock = PTHREAD_MUTEX_INITIALIZER;
static const struct launch_watch *watched_launches[PROGRESS_SLOTS];
static int launches_waited_for;

static void *ticker(void *unused)
{
	struct timespec tick = {0, PROGRESS_TICK_MS * 1000000L};

	(void)unused;
	for (;;) {
		nanosleep(&tick, NULL);
		pthread_mutex_lock(&watch_lock);
		for (int i = 0; i < PROGRESS_SLOTS; i++)
			show_share(watched_launches[i]);
		if (launches_waited_for > 0)
			progress_draw();
		pthread_mutex_unlock(&watch_lock);
	}
	return NULL;
}

static void start_ticker(void)
{
	pthread_t thread;

	/* Without the thread the line still moves from launch to launch. */
	if (pthread_create(&thread, NULL, ticker, NULL) == 0)
		pthread_detach(thread);
}

cl_int watch_wait(cl_event event, const struct launch_watch *watch)
{
	static pthread_once_t ticker_once = PTHREAD_ONCE_INIT;
	int index = -1;

	if (!progress_enabled())
		return clWaitForEvents(1, &event);
	pthread_once(&ticker_once, start_ticker);
	pthread_mutex_lock(&watch_lock);
	launches_waited_for++;
	for (int i = 0; watch && watch->counter && i < PROGRESS_SLOTS && index < 0; i++)
		if (!watched_launches[i]) {
			watched_launches[i] = watch;
			index = i;
		}
	pthread_mutex_unlock(&watch_lock);

	cl_int status = clWaitForEvents(1, &event);

	pthread_mutex_lock(&watch_lock);
	launches_waited_for--;
	if (index >= 0) {
		watched_launches[index] = NULL;
		finish_reading(watch->counter);
	}
	pthread_mutex_unlock(&watch_lock);
	return status;
}
