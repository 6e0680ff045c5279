/* The modes: one image, an animation (--frames) and --mpi, each an entry of
 * one table with the same hooks, so that main runs every mode through one
 * pipeline: options -> scene -> job -> output plan -> mode -> write ->
 * report (cmd/main.c). */
#ifndef RTCL_MODE_H
#define RTCL_MODE_H

#include <stddef.h>
#include <stdio.h>

#include "job/job.h"
#include "job/record.h"
#include "output/plan.h"

/* One run of a mode. */
struct mode_run {
	const struct job *job;
	struct output_plan *plan;
	struct record *record;
	int writes;  /* this process writes the outputs (under --mpi, rank 0) */
	void *state; /* the mode's own */
};

/* Each hook that can fail returns 0 or the exit status, with the message in
 * err (or, under --mpi, printed by the rank that failed and err empty). */
struct mode {
	const char *name;
	/* Optional: before the outputs are checked (--mpi starts MPI and
	 * learns whether this process is rank 0, the one that writes). */
	int (*begin)(struct mode_run *run, char *err, size_t err_size);
	/* Renders the job into run->record (an animation's frames into
	 * run->plan). checked: output_plan_check's result where this process
	 * writes. Only a mode with checks_in_render is called with a failed
	 * check (--mpi: every rank must learn it); it reports it. */
	int (*render)(struct mode_run *run, int checked, char *err, size_t err_size);
	int checks_in_render;
	/* Optional: after render, before the outputs are committed, whatever
	 * render returned (--mpi: MPI_Finalize). */
	void (*end)(struct mode_run *run, int status);
	/* The summary on stdout (after the commit, unless -q). */
	void (*summary)(const struct mode_run *run, FILE *out);
	/* Optional: releases what render kept (the devices). */
	void (*release)(struct mode_run *run);
};

extern const struct mode image_mode;  /* run/image.c */
extern const struct mode frames_mode; /* run/frames.c */
extern const struct mode mpi_mode;    /* run/mpi_render.c, or mpi_stub.c */

/* The mode that renders job. */
const struct mode *mode_for(const struct job *job);

/* The summaries a mode prints, shared by --mpi: one image's (with -v's time
 * breakdown on stderr), an animation's. */
void mode_summary_image(const struct mode_run *run, FILE *out);
void mode_summary_frames(const struct mode_run *run, FILE *out);

#endif
