#include "base/interrupt.h"

#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* Recursive, so that a caller may hold it around calls that hold it too
 * (output/plan.c commits the files and records the outcome as one step). */
static pthread_mutex_t lock;
static pthread_once_t lock_once = PTHREAD_ONCE_INIT;
static const char *tracked[INTERRUPT_MAX_TRACKED]; /* NULL: a free slot */
static const char *outcome = "no output written";
static int progress_on_stderr;
static sigset_t signals;
static volatile sig_atomic_t received; /* a signal taken, its handling under way */
static int blocks_sigcont;	       /* under mpirun (interrupt_setup) */
static int watches_mpirun;	       /* interrupt_watch_mpirun() was called */
static int stop_allowed;	       /* interrupt_allow_stop() */
static volatile sig_atomic_t stop_signal; /* the signal that asked to stop */

static void init_lock(void)
{
	pthread_mutexattr_t attributes;

	pthread_mutexattr_init(&attributes);
	pthread_mutexattr_settype(&attributes, PTHREAD_MUTEX_RECURSIVE);
	pthread_mutex_init(&lock, &attributes);
	pthread_mutexattr_destroy(&attributes);
}

static void lock_held(void)
{
	pthread_once(&lock_once, init_lock);
	pthread_mutex_lock(&lock);
}

/* How the message names the signal: not at all for the interrupts, whose
 * names say nothing more than "interrupted". */
static const char *signal_name(int signal_number)
{
	switch (signal_number) {
	case SIGQUIT:
		return " (SIGQUIT)";
	case SIGABRT:
		return " (SIGABRT sent to rtcl)";
	case SIGSEGV:
		return " (SIGSEGV sent to rtcl)";
	}
	return "";
}

/* Runs with the lock held, so no rename or new temporary file can start. */
static void leave(int signal_number)
{
	for (int i = 0; i < INTERRUPT_MAX_TRACKED; i++)
		if (tracked[i])
			unlink(tracked[i]);
	/* Then the staging folders they were in (files.h), empty now. */
	for (int i = 0; i < INTERRUPT_MAX_TRACKED; i++)
		if (tracked[i])
			rmdir(tracked[i]);
	/* dprintf, not stdio: the main thread may hold stderr's lock. */
	if (outcome)
		dprintf(STDERR_FILENO, "%srtcl: interrupted%s; %s\n", progress_on_stderr ? "\n" : "",
		signal_name(signal_number), outcome);
	_exit(128 + signal_number);
}

static void *take_signals(void *unused)
{
	(void)unused;
	for (;;) {
		int signal_number;

		if (sigwait(&signals, &signal_number) != 0)
			continue;
		received = signal_number; /* before the lock: interrupt_settle() */
		lock_held();
		if (stop_allowed && !stop_signal &&
		    (signal_number == SIGINT || signal_number == SIGTERM)) {
			/* A request to stop (interrupt_allow_stop), not an end. */
			stop_signal = signal_number;
			received = 0;
			dprintf(STDERR_FILENO,
				"%srtcl: interrupted; stopping after the pass under way to write "
				"what is done (interrupt again to stop at once, writing "
				"nothing)\n",
				progress_on_stderr ? "\n" : "");
			pthread_mutex_unlock(&lock);
			continue;
		}
		leave(signal_number);
	}
	return NULL;
}

int interrupt_setup(int progress_line, int under_mpirun, char *err, size_t err_size)
{
	pthread_attr_t attributes;
	pthread_t thread;
	sigset_t blocked;
	int failed;

	progress_on_stderr = progress_line;
	blocks_sigcont = under_mpirun;
	sigemptyset(&signals);
	sigaddset(&signals, SIGINT);
	sigaddset(&signals, SIGTERM);
	sigaddset(&signals, SIGHUP);
	/* A quit, and the crash signals that a user sends with kill: the OpenCL
	 * runtime's LLVM installs handlers for these that print nothing and
	 * return, which swallowed them (the render went on). Blocked, they come
	 * here instead. A real fault is unaffected: the kernel delivers a
	 * SIGSEGV that the faulting thread blocks with the default action (the
	 * process dies), and abort() unblocks SIGABRT in its own thread. */
	sigaddset(&signals, SIGQUIT);
	sigaddset(&signals, SIGABRT);
	sigaddset(&signals, SIGSEGV);
	/* Under mpirun, SIGCONT too, left pending for interrupt_settle(). */
	blocked = signals;
	if (under_mpirun)
		sigaddset(&blocked, SIGCONT);
	failed = pthread_sigmask(SIG_BLOCK, &blocked, NULL);
	if (!failed)
		failed = pthread_attr_init(&attributes);
	if (!failed) {
		pthread_attr_setdetachstate(&attributes, PTHREAD_CREATE_DETACHED);
		failed = pthread_create(&thread, &attributes, take_signals, NULL);
		pthread_attr_destroy(&attributes);
	}
	if (failed) {
		snprintf(err, err_size, "cannot start the thread that handles interrupts: %s",
			 strerror(failed));
		return -1;
	}
	return 0;
}

void interrupt_hold(void)
{
	lock_held();
}

void interrupt_release(void)
{
	pthread_mutex_unlock(&lock);
}

int interrupt_track(const char *path)
{
	for (int i = 0; i < INTERRUPT_MAX_TRACKED; i++) {
		if (!tracked[i]) {
			tracked[i] = path;
			return 0;
		}
	}
	return -1;
}

void interrupt_untrack(const char *path)
{
	for (int i = 0; i < INTERRUPT_MAX_TRACKED; i++)
		if (tracked[i] == path)
			tracked[i] = NULL;
}

void interrupt_allow_stop(int allowed)
{
	lock_held();
	stop_allowed = allowed;
	pthread_mutex_unlock(&lock);
}

int interrupt_stop_signal(void)
{
	return stop_signal;
}

void interrupt_set_outcome(const char *text)
{
	lock_held();
	outcome = text;
	pthread_mutex_unlock(&lock);
}

/* Takes a pending SIGCONT; returns 1 if there was one. */
static int take_sigcont(void)
{
	struct timespec now = {0, 0};
	sigset_t cont;

	sigemptyset(&cont);
	sigaddset(&cont, SIGCONT);
	return sigtimedwait(&cont, NULL, &now) == SIGCONT;
}

void interrupt_watch_mpirun(void)
{
	if (!blocks_sigcont)
		return;
	take_sigcont(); /* one from before (a job resumed) does not count */
	watches_mpirun = 1;
}

/* How long rank 0 waits for mpirun's SIGTERM after its SIGCONT. */
#define MPIRUN_SIGTERM_WAIT_S 1

void interrupt_settle(void)
{
	struct timespec now = {0, 0};
	int signal_number;

	lock_held();
	/* One taken by the thread, which waits for the lock we hold now, or
	 * one not taken yet. */
	if (received)
		leave(received);
	signal_number = sigtimedwait(&signals, NULL, &now);
	if (signal_number > 0)
		leave(signal_number);
	if (watches_mpirun && take_sigcont()) {
		/* mpirun ends a job it was told to end (Ctrl-C) with SIGCONT, then
		 * SIGTERM some 30 ms later (Open MPI 4.1.4's odls): a rank 0 that
		 * finished its commit in between exited 0 unaware, and mpirun's
		 * status 1 came with no message at all. A SIGCONT during the end of
		 * the run is waited on: the SIGTERM that follows ends rank 0 with
		 * the message; none (a job resumed after Ctrl-Z) costs a second. */
		struct timespec wait = {MPIRUN_SIGTERM_WAIT_S, 0};
		signal_number = sigtimedwait(&signals, NULL, &wait);
		if (signal_number > 0)
			leave(signal_number);
	}
	/* Held until the process exits: a later signal finds the run over. */
}
