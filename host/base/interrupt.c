#include "base/interrupt.h"

#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>
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

/* The tracked temporary files, then the staging folders they were in
 * (files.h), empty now. */
static void remove_tracked(void)
{
	for (int i = 0; i < INTERRUPT_MAX_TRACKED; i++)
		if (tracked[i])
			unlink(tracked[i]);
	for (int i = 0; i < INTERRUPT_MAX_TRACKED; i++)
		if (tracked[i])
			rmdir(tracked[i]);
}

/* Runs with the lock held, so no rename or new temporary file can start. */
static void leave(int signal_number)
{
	remove_tracked();
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

/* The crash guard (interrupt_guard_crashes). The message is made before the
 * crash: the handler only writes it. */
static const int crash_signals[] = {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT};
#define CRASH_SIGNALS (int)(sizeof(crash_signals) / sizeof(crash_signals[0]))
static pthread_mutex_t guard_lock = PTHREAD_MUTEX_INITIALIZER;
static int guards; /* guards in force, in every thread */
static struct sigaction crash_before[CRASH_SIGNALS];
static char crash_note[1024];
static __thread int thread_guards;    /* this thread's guards in force */
static __thread sigset_t thread_mask; /* its signal mask before them */

unsigned long long interrupt_memory_limit_mib(void)
{
	struct rlimit limit;

	if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY)
		return 0;
	return (unsigned long long)limit.rlim_cur >> 20;
}

/* The fault's name (the crash signals only: SIGABRT last). */
static const char *crash_name(int signal_number)
{
	return signal_number == SIGSEGV ? "SIGSEGV"
	       : signal_number == SIGBUS ? "SIGBUS"
	       : signal_number == SIGILL ? "SIGILL"
	       : signal_number == SIGFPE ? "SIGFPE"
					 : "SIGABRT";
}

static volatile sig_atomic_t sent_in_guard; /* a signal sent while guarded */

static void on_crash(int signal_number, siginfo_t *info, void *context)
{
	(void)context;
	if (info && info->si_code <= 0 && info->si_pid != getpid()) {
		/* Sent by another process (kill), not a fault: an interrupt,
		 * passed on to the signal thread once the guard ends. */
		sent_in_guard = signal_number;
		return;
	}
	/* Without the lock, which this very thread may hold. */
	remove_tracked();
	dprintf(STDERR_FILENO, "%srtcl: crashed (%s) while %s\n", progress_on_stderr ? "\n" : "",
		crash_name(signal_number), crash_note);
	signal(signal_number, SIG_DFL);
	raise(signal_number);
}

void interrupt_guard_crashes(const char *doing)
{
	unsigned long long mib = interrupt_memory_limit_mib();
	sigset_t faults;

	pthread_mutex_lock(&guard_lock);
	if (mib)
		snprintf(crash_note, sizeof(crash_note),
			 "%s; no output written. rtcl runs with an address-space limit of %llu "
			 "MiB (`ulimit -v`), which the OpenCL runtime may have run out of: raise "
			 "or lift it",
			 doing, mib);
	else
		snprintf(crash_note, sizeof(crash_note), "%s; no output written", doing);
	if (guards++ == 0) {
		struct sigaction action = {.sa_sigaction = on_crash,
					   .sa_flags = SA_ONSTACK | SA_SIGINFO};

		sigemptyset(&action.sa_mask);
		for (int i = 0; i < CRASH_SIGNALS; i++)
			sigaction(crash_signals[i], &action, &crash_before[i]);
	}
	pthread_mutex_unlock(&guard_lock);
	/* A fault in a thread that blocks its signal kills the process without
	 * a handler (interrupt_setup blocks SIGSEGV and SIGABRT): unblocked here
	 * for the step. */
	if (thread_guards++ == 0) {
		sigemptyset(&faults);
		for (int i = 0; i < CRASH_SIGNALS; i++)
			sigaddset(&faults, crash_signals[i]);
		pthread_sigmask(SIG_UNBLOCK, &faults, &thread_mask);
	}
}

void interrupt_unguard_crashes(void)
{
	/* The mask as it was (interrupt_setup blocks SIGSEGV and SIGABRT, so
	 * that one sent by another process goes to the signal thread). */
	if (thread_guards > 0 && --thread_guards == 0)
		pthread_sigmask(SIG_SETMASK, &thread_mask, NULL);
	pthread_mutex_lock(&guard_lock);
	if (guards > 0 && --guards == 0)
		for (int i = 0; i < CRASH_SIGNALS; i++)
			sigaction(crash_signals[i], &crash_before[i], NULL);
	pthread_mutex_unlock(&guard_lock);
	/* A SIGABRT or SIGSEGV a user sent meanwhile, to the signal thread now
	 * (blocked here again: the process's, not this thread's). */
	if (!guards && sent_in_guard) {
		int signal_number = sent_in_guard;
		sent_in_guard = 0;
		kill(getpid(), signal_number);
	}
}
