/* mesh_import (mesh.h): the Open Asset Import Library in a child process.
 * Assimp 5.2 calls abort() on some malformed files (found by the mesh fuzzer,
 * test/fuzz_mesh_regressions/); in a child, that ends the child, and the parent
 * refuses the file with a message like any other bad input. The child sends
 * the mesh back through a pipe: a header, then the arrays as they are.
 * rtcl loads its scene before it starts OpenCL, threads or MPI, so the fork
 * happens in a process of one thread. */
#include "mesh.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif
#include <unistd.h>

/* What the child sends first: the import's outcome and the arrays' sizes,
 * then (ok) the arrays or (!ok) reason_length bytes of reason. */
struct reply {
	int ok, has_normals;
	size_t vertex_count, triangle_count, reason_length;
};

static int write_all(int fd, const void *data, size_t size)
{
	const char *p = data;

	while (size > 0) {
		ssize_t n = write(fd, p, size);
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0)
			return -1;
		p += n;
		size -= (size_t)n;
	}
	return 0;
}

static int read_all(int fd, void *data, size_t size)
{
	char *p = data;

	while (size > 0) {
		ssize_t n = read(fd, p, size);
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0)
			return -1;
		p += n;
		size -= (size_t)n;
	}
	return 0;
}

/* The child dies of what kills it, plainly: no handler the parent installed
 * (rtcl's Ctrl-C bookkeeping, a fuzzer's or sanitizer's crash reports) runs
 * in it. */
static void default_signals(void)
{
	const int signals[] = {SIGABRT, SIGSEGV, SIGBUS,  SIGFPE, SIGILL,
			       SIGALRM, SIGINT,	 SIGTERM, SIGPIPE};

	for (size_t i = 0; i < sizeof(signals) / sizeof(signals[0]); i++)
		signal(signals[i], SIG_DFL);
}

/* Assimp prints its assertion failures (and the like) on stderr before it
 * aborts; the parent's one message says what matters. */
static void silence_stderr(void)
{
	int null = open("/dev/null", O_WRONLY);

	if (null >= 0) {
		dup2(null, STDERR_FILENO);
		close(null);
	}
}

/* The child: imports and sends; its exit status says whether all was sent. */
static void child_import(const char *path, int fd)
{
	struct mesh_data mesh;
	char reason[512] = "";
	struct reply r = {0};

	r.ok = mesh_import_here(path, &mesh, reason, sizeof(reason)) == 0;
	if (!r.ok) {
		r.reason_length = strlen(reason);
		_exit(write_all(fd, &r, sizeof(r)) || write_all(fd, reason, r.reason_length));
	}
	r.has_normals = mesh.normals != NULL;
	r.vertex_count = mesh.vertex_count;
	r.triangle_count = mesh.triangle_count;
	int failed = write_all(fd, &r, sizeof(r)) ||
		     write_all(fd, mesh.positions, 3 * r.vertex_count * sizeof(double)) ||
		     (r.has_normals &&
		      write_all(fd, mesh.normals, 3 * r.vertex_count * sizeof(double))) ||
		     write_all(fd, mesh.indices, 3 * r.triangle_count * sizeof(size_t));
	_exit(failed);
}

/* The parent's side of the pipe: the mesh into *out, or the child's reason.
 * Returns 0, -1 with reason set, or -2 when the pipe broke off (the child
 * died: its status says why). */
static int receive(int fd, struct mesh_data *out, char *reason, size_t reason_size)
{
	struct reply r;

	if (read_all(fd, &r, sizeof(r)))
		return -2;
	if (!r.ok) {
		char text[512];
		size_t n = r.reason_length < sizeof(text) - 1 ? r.reason_length : sizeof(text) - 1;
		if (read_all(fd, text, n))
			return -2;
		text[n] = '\0';
		snprintf(reason, reason_size, "%s", text);
		return -1;
	}
	out->positions = malloc((r.vertex_count ? r.vertex_count : 1) * 3 * sizeof(double));
	out->normals = r.has_normals
			       ? malloc((r.vertex_count ? r.vertex_count : 1) * 3 * sizeof(double))
			       : NULL;
	out->indices = malloc((r.triangle_count ? r.triangle_count : 1) * 3 * sizeof(size_t));
	out->vertex_count = r.vertex_count;
	out->triangle_count = r.triangle_count;
	if (!out->positions || (r.has_normals && !out->normals) || !out->indices) {
		snprintf(reason, reason_size, "out of memory for %zu triangles", r.triangle_count);
		return -1;
	}
	if (read_all(fd, out->positions, 3 * r.vertex_count * sizeof(double)) ||
	    (r.has_normals && read_all(fd, out->normals, 3 * r.vertex_count * sizeof(double))) ||
	    read_all(fd, out->indices, 3 * r.triangle_count * sizeof(size_t)))
		return -2;
	return 0;
}

/* Waits for the child; a death by signal, or a pipe that broke off, becomes
 * the reason. */
static int reap(pid_t child, int received, char *reason, size_t reason_size)
{
	int status;

	while (waitpid(child, &status, 0) < 0)
		if (errno != EINTR) {
			snprintf(reason, reason_size, "waiting for the importer: %s",
				 strerror(errno));
			return -1;
		}
	if (WIFSIGNALED(status)) {
		snprintf(reason, reason_size,
			 "the importer (Assimp) crashed reading it (signal %d, %s): the file is "
			 "malformed",
			 WTERMSIG(status), strsignal(WTERMSIG(status)));
		return -1;
	}
	if (received == -2) {
		snprintf(reason, reason_size,
			 "the importer ended without an answer (exit status %d)",
			 WIFEXITED(status) ? WEXITSTATUS(status) : -1);
		return -1;
	}
	return received;
}

int mesh_import(const char *path, struct mesh_data *out, char *reason, size_t reason_size)
{
	int fds[2], received;
	pid_t child;

	memset(out, 0, sizeof(*out));
	if (pipe(fds)) {
		snprintf(reason, reason_size, "cannot start the importer: %s", strerror(errno));
		return -1;
	}
	fflush(NULL); /* nothing buffered is written twice */
	child = fork();
	if (child < 0) {
		snprintf(reason, reason_size, "cannot start the importer: %s", strerror(errno));
		close(fds[0]);
		close(fds[1]);
		return -1;
	}
	if (child == 0) {
		close(fds[0]);
#ifdef __linux__
		/* Killed with its parent (a timeout, kill -9): never left spinning
		 * in a loop of Assimp's. */
		prctl(PR_SET_PDEATHSIG, SIGKILL);
#endif
		default_signals();
		silence_stderr();
		child_import(path, fds[1]);
	}
	close(fds[1]);
	received = receive(fds[0], out, reason, reason_size);
	close(fds[0]);
	if (reap(child, received, reason, reason_size)) {
		mesh_data_free(out);
		return -1;
	}
	return 0;
}
