/* Interrupts (SIGINT, SIGTERM, SIGHUP, and SIGQUIT, SIGABRT or SIGSEGV sent
 * by another process) in a multi-threaded process.
 *
 * The signals are blocked in every thread from the start of main, before the
 * OpenCL runtime starts threads of its own (which inherit the mask), and are
 * taken by one thread with sigwait(). That thread removes the temporary files
 * of this run that are still open for writing (tracked below), says so on
 * stderr and ends the process with 128 + the signal number. Renaming the
 * finished files over their targets happens inside interrupt_hold() /
 * interrupt_release(), so a signal then waits until every rename is done:
 * after an interrupt the user finds either the previous outputs untouched or
 * the complete new ones, never a mixture and never a temporary file, and
 * nothing rtcl did not create in this run is ever removed. */
#ifndef RTCL_INTERRUPT_H
#define RTCL_INTERRUPT_H

#include <stddef.h>

/* Blocks the signals and starts the thread that takes them. progress_line:
 * a progress line may be open on stderr (the message then starts on a line of
 * its own). under_mpirun: --mpi (interrupt_watch_mpirun()). Returns 0, or -1
 * with one message in err. */
int interrupt_setup(int progress_line, int under_mpirun, char *err, size_t err_size);

/* A critical section: while it is held, a signal waits. It may be nested. */
void interrupt_hold(void);
void interrupt_release(void);

/* Under interrupt_hold(): removes path (a file, or a folder emptied of the
 * tracked files) if a signal comes before interrupt_untrack(path). At most
 * INTERRUPT_MAX_TRACKED paths, each kept by reference (the caller keeps the
 * string alive). Returns 0, or -1 when full. */
#define INTERRUPT_MAX_TRACKED 1024 /* room for every frame of an animation */
int interrupt_track(const char *path);
void interrupt_untrack(const char *path);

/* What the message says was left after an interrupt from now on (default "no
 * output written"); a string literal. NULL: no message (the run has failed
 * and said why; under --mpi, mpirun may still end the rank). */
void interrupt_set_outcome(const char *outcome);

/* Stopping a render early, keeping what it has done: while allowed
 * (interrupt_allow_stop(1), between a render's first and last pass), the
 * first SIGINT or SIGTERM does not end the process: it is taken as a
 * request to stop after the pass under way, said on stderr, and
 * interrupt_stop_signal() returns it from then on; the render then writes
 * the samples it has. A second signal, or any while stopping is not
 * allowed, ends the process as above. */
void interrupt_allow_stop(int allowed);

/* The signal that asked the render to stop (SIGINT or SIGTERM), or 0. */
int interrupt_stop_signal(void);

/* At the end of a successful run, before the process exits: a signal that
 * came while the run ended (its handling waiting, say, for a commit) ends
 * the process as it would have, with its message and status, rather than
 * being lost to a normal exit (under mpirun, Ctrl-C during rank 0's commit
 * then said nothing at all). A signal after this call finds the run over
 * and the process exits normally. */
void interrupt_settle(void);

/* A step that may crash in a library (the OpenCL compiler): between
 * interrupt_guard_crashes(doing) and interrupt_unguard_crashes(), a fault
 * (SIGSEGV, SIGBUS, SIGILL, SIGFPE) or abort() in the calling thread removes
 * the tracked files, prints "rtcl: crashed (SIGNAL) while DOING; no output
 * written" (and, under an address-space limit, `ulimit -v`, that limit and
 * what to do) and ends the process by the signal. Without it such a crash
 * ended rtcl with nothing on stderr (PoCL's compiler under a small limit).
 * doing is copied; guards may nest and come from several threads. */
void interrupt_guard_crashes(const char *doing);
void interrupt_unguard_crashes(void);

/* The address-space limit (RLIMIT_AS) in MiB, or 0 when there is none. */
unsigned long long interrupt_memory_limit_mib(void);

/* Under mpirun, rank 0 from the end of the ranks' work to the end of its
 * writing: mpirun's SIGCONT from now on announces its SIGTERM, which
 * interrupt_settle() then waits for. */
void interrupt_watch_mpirun(void);

#endif
