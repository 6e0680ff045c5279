/* rtcl-meshread [--memory-limit MIB] FILE: the mesh import helper (mesh.h).
 * Reads FILE with the Open Asset Import Library and sends the triangles, or
 * the importer's reason for refusing the file, to standard output in the form
 * mesh_import reads. rtcl starts it for each mesh file of a scene; it is not
 * meant to be run by hand (its output is binary). Exit status 0 when the
 * answer went out.
 *
 * --memory-limit: the helper's address space (RLIMIT_AS) in MiB, set before
 * the import, so that a file that makes Assimp allocate without bound ends
 * in one message, not in the machine's memory (issue 24 finding 5). Not set
 * under AddressSanitizer, whose shadow memory needs terabytes of addresses. */
#ifndef _DEFAULT_SOURCE
#define _DEFAULT_SOURCE /* sigaltstack */
#endif
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include "scene/mesh.h"

#if defined(__SANITIZE_ADDRESS__)
#define ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ADDRESS_SANITIZER 1
#endif
#endif

/* The address space limit in bytes; 0: none. */
static unsigned long long limit_bytes;

/* Whether the process's address space is near its limit (a crash then is an
 * allocation that failed in code that does not check it). Async-signal-safe. */
static int near_limit(void)
{
	char text[64];
	unsigned long long pages = 0;
	int fd = open("/proc/self/statm", O_RDONLY);
	ssize_t n = fd >= 0 ? read(fd, text, sizeof(text) - 1) : -1;

	if (fd >= 0)
		close(fd);
	for (ssize_t i = 0; i < n && text[i] >= '0' && text[i] <= '9'; i++)
		pages = pages * 10 + (unsigned long long)(text[i] - '0');
	return limit_bytes &&
	       pages * (unsigned long long)sysconf(_SC_PAGESIZE) >= limit_bytes / 10 * 9;
}

/* A crash (Assimp dereferencing a failed allocation) near the limit says so
 * on stderr, where rtcl finds it (host/scene/mesh_spawn.c), then ends as it would. */
static void on_crash(int sig)
{
	static const char note[] = MESH_MEMORY_NOTE "\n";

	if (near_limit())
		(void)!write(STDERR_FILENO, note, sizeof(note) - 1);
	signal(sig, SIG_DFL);
	raise(sig);
}

/* Limits the address space to mib MiB (0: no limit). */
static void limit_memory(unsigned long mib)
{
#ifndef ADDRESS_SANITIZER
	static char crash_stack[1 << 16];
	stack_t stack = {.ss_sp = crash_stack, .ss_size = sizeof(crash_stack)};
	struct sigaction action = {.sa_handler = on_crash, .sa_flags = SA_ONSTACK};
	struct rlimit limit;

	if (mib == 0 || mib > (unsigned long)(RLIM_INFINITY >> 20))
		return;
	limit_bytes = (unsigned long long)mib << 20;
	limit.rlim_cur = limit.rlim_max = (rlim_t)limit_bytes;
	if (setrlimit(RLIMIT_AS, &limit) != 0)
		return;
	sigaltstack(&stack, NULL);
	sigemptyset(&action.sa_mask);
	sigaction(SIGSEGV, &action, NULL);
	sigaction(SIGBUS, &action, NULL);
	sigaction(SIGABRT, &action, NULL);
#else
	(void)mib;
#endif
}

int main(int argc, char **argv)
{
	struct mesh_data mesh;
	char reason[1024] = "";
	unsigned long memory_mib = 0;
	const char *path = argc == 2 ? argv[1] : NULL;
	int sent;

#ifdef __linux__
	/* Ends with rtcl (killed, timed out): never left behind in a loop of
	 * the importer's. */
	prctl(PR_SET_PDEATHSIG, SIGKILL);
#endif
	if (argc == 4 && strcmp(argv[1], "--memory-limit") == 0) {
		char *end;
		memory_mib = strtoul(argv[2], &end, 10);
		path = *end || !argv[2][0] ? NULL : argv[3];
	}
	if (!path || isatty(STDOUT_FILENO)) {
		fprintf(stderr,
			"usage: %s [--memory-limit MIB] FILE > PIPE (rtcl's mesh import helper; "
			"rtcl runs it)\n",
			argv[0]);
		return 2;
	}
	limit_memory(memory_mib);
	if (mesh_import_here(path, &mesh, reason, sizeof(reason))) {
		/* Assimp's words when an allocation failed under the limit. */
		if (memory_mib && (strstr(reason, "bad_alloc") || strstr(reason, "out of memory")))
			snprintf(reason, sizeof(reason), MESH_MEMORY_MESSAGE, memory_mib);
		sent = mesh_send(STDOUT_FILENO, NULL,
				 reason[0] ? reason : "the importer refused it");
	} else {
		sent = mesh_send(STDOUT_FILENO, &mesh, NULL);
		mesh_data_free(&mesh);
	}
	/* _exit, not exit: Assimp 5.2 leaks on some error paths for malformed
	 * PLY files (found by the mesh fuzzer), and LeakSanitizer's check at exit
	 * in a sanitizer build would fail the import for memory that is not
	 * rtcl's; the process ends here, which frees it all. */
	fflush(stderr);
	_exit(sent ? 1 : 0);
}
