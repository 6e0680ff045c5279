#include "base/progress.h"

#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "base/timing.h"

/* Wide enough for the longest line. */
#define LINE_SIZE 160

static struct {
	int enabled;
	pthread_mutex_t lock;
	char what[64], step[64];
	double total, done, step_total, step_start;
	const void *slot_key[PROGRESS_SLOTS];
	double slot_done[PROGRESS_SLOTS];
	double start, last_draw;
	int shown; /* characters on the line now */
} line = {.lock = PTHREAD_MUTEX_INITIALIZER};

void progress_init(int enabled)
{
	line.enabled = enabled;
}

int progress_enabled(void)
{
	return line.enabled;
}

void progress_begin(const char *what, double total)
{
	if (!line.enabled)
		return;
	pthread_mutex_lock(&line.lock);
	snprintf(line.what, sizeof(line.what), "%s", what);
	line.step[0] = '\0';
	line.total = total > 0 ? total : 1;
	line.done = line.step_total = line.step_start = 0;
	memset(line.slot_key, 0, sizeof(line.slot_key));
	memset(line.slot_done, 0, sizeof(line.slot_done));
	line.start = timing_now();
	line.last_draw = 0;
	pthread_mutex_unlock(&line.lock);
}

/* The work done, the launches under way included. Under the lock. */
static double done_so_far(void)
{
	double done = line.done;

	for (int k = 0; k < PROGRESS_SLOTS; k++)
		done += line.slot_done[k];
	return done < line.total ? done : line.total;
}

void progress_step(const char *step, double step_total)
{
	if (!line.enabled)
		return;
	pthread_mutex_lock(&line.lock);
	snprintf(line.step, sizeof(line.step), "%s", step ? step : "");
	line.step_total = step_total;
	line.step_start = done_so_far();
	line.last_draw = 0; /* a new step shows at the next draw */
	pthread_mutex_unlock(&line.lock);
}

/* The slot of key, taken if new; NULL when all are taken (its launch then
 * shows only once finished). Under the lock. */
static double *slot_of(const void *key)
{
	for (int k = 0; k < PROGRESS_SLOTS; k++)
		if (line.slot_key[k] == key)
			return &line.slot_done[k];
	for (int k = 0; k < PROGRESS_SLOTS; k++) {
		if (!line.slot_key[k]) {
			line.slot_key[k] = key;
			return &line.slot_done[k];
		}
	}
	return NULL;
}

void progress_add(const void *slot, double done)
{
	if (!line.enabled)
		return;
	pthread_mutex_lock(&line.lock);
	double *partial = slot ? slot_of(slot) : NULL;
	if (partial)
		*partial = 0;
	line.done += done;
	pthread_mutex_unlock(&line.lock);
}

void progress_partial(const void *slot, double done)
{
	if (!line.enabled)
		return;
	pthread_mutex_lock(&line.lock);
	double *partial = slot ? slot_of(slot) : NULL;
	if (partial)
		*partial = done;
	pthread_mutex_unlock(&line.lock);
}

/* "about 12 s left", "about 3 min left", or "" before there is a pace. */
static void format_left(char *out, size_t size, double share, double elapsed)
{
	double left = share > 0 ? elapsed * (1 - share) / share : -1;

	if (share <= 0 || elapsed < 0.5)
		snprintf(out, size, "%s", "");
	else if (left < 100)
		snprintf(out, size, ", about %.0f s left", left < 1 ? 1 : left);
	else if (left < 6000)
		snprintf(out, size, ", about %.0f min left", left / 60);
	else
		snprintf(out, size, ", about %.1f h left", left / 3600);
}

void progress_draw(void)
{
	char text[LINE_SIZE], step[96] = "", left[48];
	double now = timing_now();

	if (!line.enabled)
		return;
	pthread_mutex_lock(&line.lock);
	if (now - line.last_draw < PROGRESS_TICK_MS * 1e-3 * 0.9) {
		pthread_mutex_unlock(&line.lock);
		return;
	}
	line.last_draw = now;
	double done = done_so_far(), share = done / line.total;
	if (line.step[0] && line.step_total > 0) {
		double step_share = (done - line.step_start) / line.step_total;
		step_share = step_share < 0 ? 0 : step_share > 1 ? 1 : step_share;
		snprintf(step, sizeof(step), ", %s: %d%%", line.step, (int)(100 * step_share));
	} else if (line.step[0]) {
		snprintf(step, sizeof(step), ", %s", line.step);
	}
	format_left(left, sizeof(left), share, now - line.start);
	/* "rendering (dynamic)" becomes "rendering (dynamic, STEP)". */
	size_t what_len = strlen(line.what);
	int close = what_len > 0 && line.what[what_len - 1] == ')' && step[0];
	int n = snprintf(text, sizeof(text), "\r%.*s%s%s: %d%% done%s", (int)what_len - close,
			 line.what, step, close ? ")" : "", (int)(100 * share), left);
	int width = n - 1;
	/* Spaces over what a longer line before left. */
	fprintf(stderr, "%s%*s", text, line.shown > width ? line.shown - width : 0, "");
	if (line.shown > width)
		fprintf(stderr, "\r%s", text + 1);
	fflush(stderr);
	line.shown = width;
	pthread_mutex_unlock(&line.lock);
}

void progress_end(void)
{
	if (!line.enabled)
		return;
	pthread_mutex_lock(&line.lock);
	if (line.shown > 0)
		fprintf(stderr, "\r%*s\r", line.shown, "");
	line.shown = 0;
	line.total = 0;
	pthread_mutex_unlock(&line.lock);
}
