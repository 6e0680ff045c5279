/* The progress line on stderr: what is running, the share of the run's
 * work done and the time left, redrawn while the devices work.
 *
 * Work is counted in pixel samples (a pixel's samples of one launch). A run
 * (progress_begin) has a total; pieces add what they finished
 * (progress_add), and a launch under way says how far it is
 * (progress_partial), read from its device while it runs (render/watch.h). The
 * line is one per process and every function is thread-safe, so several
 * devices' threads add to one line. With progress_init(0) (stderr not a
 * terminal, or -q) every function does nothing. */
#ifndef RTCL_PROGRESS_H
#define RTCL_PROGRESS_H

/* Devices whose launches are followed at once (DEVICES_MAX). */
#define PROGRESS_SLOTS 16

/* Shows the line from now on, or never. */
void progress_init(int enabled);

/* Whether the line is shown. */
int progress_enabled(void);

/* Starts a run of `total` pixel samples: `what` (e.g. "rendering
 * (dynamic)") is shown first; the clock and the counts start again. */
void progress_begin(const char *what, double total);

/* Names the step under way, shown after `what` (e.g. "timed launch 2 of
 * 3"), and its size in pixel samples: with step_total > 0 the line also
 * shows the step's own share. NULL: no step. */
void progress_step(const char *step, double step_total);

/* Finished work: pixel samples, and the slot's partial work ends (slot
 * NULL: work of no slot, e.g. another MPI rank's). */
void progress_add(const void *slot, double done);

/* Work under way on slot (a device), so far, in pixel samples. */
void progress_partial(const void *slot, double done);

/* Redraws the line, at most every PROGRESS_TICK_MS. */
void progress_draw(void);

/* Clears the line (before a message or the summary). */
void progress_end(void);

/* How often a waiting launch reads its device and redraws. */
#define PROGRESS_TICK_MS 100

#endif
