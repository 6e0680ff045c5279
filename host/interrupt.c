#include "interrupt.h"

#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

/* Recursive, so that a caller may hold it around calls that hold it too
 * (outputs.c commits the files and records the outcome as one step). */
static pthread_mutex_t lock;
static pthread_once_t lock_once = PTHREAD_ONCE_INIT;
static const char *tracked[INTERRUPT_MAX_TRACKED]; /* NULL: a free slot */
static const char *outcome = "no output written";
static int progress_on_stderr;
static sigset_t signals;

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
	dprintf(STDERR_FILENO, "%srtcl: interrupted; %s\n", progress_on_stderr ? "\n" : "",
		outcome);
	_exit(128 + signal_number);
}

static void *take_signals(void *unused)
{
	(void)unused;
	for (;;) {
		int signal_number;

		if (sigwait(&signals, &signal_number) != 0)
			continue;
		lock_held();
		leave(signal_number);
	}
	return NULL;
}

int interrupt_setup(int progress_line, char *err, size_t err_size)
{
	pthread_attr_t attributes;
	pthread_t thread;
	int failed;

	progress_on_stderr = progress_line;
	sigemptyset(&signals);
	sigaddset(&signals, SIGINT);
	sigaddset(&signals, SIGTERM);
	sigaddset(&signals, SIGHUP);
	failed = pthread_sigmask(SIG_BLOCK, &signals, NULL);
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

void interrupt_set_outcome(const char *text)
{
	lock_held();
	outcome = text;
	pthread_mutex_unlock(&lock);
}
