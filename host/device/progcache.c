/* The program binary cache (see progcache.h). A cache file is a header, the
 * key and an FNV-1a hash of the binary (so a torn or altered file is caught
 * before the driver sees it), then the binary. It is written to a temporary
 * file in the cache folder and renamed into place, so that a reader never
 * sees half a file and two rtcls writing at once leave one whole file.
 *
 * Only a regular file is read (a FIFO or device in its place, opened without
 * blocking, is a miss: issue 24 finding 7, a FIFO hung every render). The
 * temporary file is named <key>.bin.tmp-<pid>-XXXXXX; an interrupt removes it
 * (interrupt.h), and each save removes those of writers no longer running
 * (killed with SIGKILL, or from before this naming). */
#include "device/progcache.h"

#include "base/version.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "base/test_hooks.h" /* hook_cache_write_delay */
#include "base/interrupt.h"
#include "base/quote.h"

/* The file's first bytes; a new layout gets a new one. */
static const char magic[8] = {'r', 't', 'c', 'l', 'b', 'i', 'n', '1'};

/* Environment variables of OpenCL drivers that change the binary a build
 * makes: part of the key. */
static const char *const driver_settings[] = {"POCL_EXTRA_BUILD_FLAGS",
					      "POCL_WORK_GROUP_SPECIALIZATION"};

/* No program binary is larger (PoCL's are about 1 MB, PTX a few hundred kB). */
#define MAX_BINARY_BYTES ((size_t)256 << 20)

struct header {
	char magic[8];
	uint64_t key;
	uint64_t binary_hash;
	uint64_t binary_size;
};

static uint64_t fnv1a(uint64_t hash, const void *data, size_t size)
{
	const unsigned char *p = data;

	for (size_t i = 0; i < size; i++)
		hash = (hash ^ p[i]) * 0x100000001b3ULL;
	return hash;
}

/* Hashes a string with its terminating NUL, so that "ab","c" and "a","bc"
 * differ. */
static uint64_t hash_text(uint64_t hash, const char *text)
{
	return fnv1a(hash, text, strlen(text) + 1);
}

static int cache_dir(char *dir, size_t size)
{
	const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");

	/* The XDG spec: a relative XDG_CACHE_HOME is invalid and ignored. */
	if (xdg && xdg[0] == '/')
		return snprintf(dir, size, "%s/rtcl", xdg) < (int)size ? 0 : -1;
	if (home && home[0] == '/')
		return snprintf(dir, size, "%s/.cache/rtcl", home) < (int)size ? 0 : -1;
	return -1;
}

void progcache_init(struct progcache *cache, const struct device *dev, const char *const *texts,
		    int count, const char *options, int verbose)
{
	const char *setting = getenv("RTCL_CACHE");
	char dir[4000];
	uint64_t key = 0xcbf29ce484222325ULL;

	memset(cache, 0, sizeof(*cache));
	cache->verbose = verbose;
	cache->options = options;
	cache->enabled = !(setting && strcmp(setting, "0") == 0);
	key = hash_text(key, "rtcl " RTCL_VERSION);
	key = hash_text(key, dev->platform_name);
	key = hash_text(key, dev->name);
	key = hash_text(key, dev->version);
	key = hash_text(key, dev->driver);
	key = hash_text(key, options);
	/* PoCL's build settings from the environment change its binary
	 * (make test builds without LLVM's optimiser, make test-long with it). */
	for (size_t i = 0; i < sizeof(driver_settings) / sizeof(driver_settings[0]); i++) {
		const char *value = getenv(driver_settings[i]);
		key = hash_text(key, value ? value : "");
	}
	for (int i = 0; i < count; i++)
		key = hash_text(key, texts[i]);
	cache->key = key;
	if (cache->enabled && cache_dir(dir, sizeof(dir)) == 0)
		snprintf(cache->path, sizeof(cache->path), "%s/%016llx.bin", dir,
			 (unsigned long long)key);
}

/* The cache file open for reading, or NULL: none (silently), or not a
 * regular file (said with -v). Opened without blocking: a FIFO in its place
 * must not wait for a writer. */
static FILE *open_entry(const struct progcache *cache)
{
	int fd = open(cache->path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	struct stat st;
	FILE *file;

	if (fd < 0)
		return NULL;
	if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
		if (cache->verbose)
			fprintf(stderr,
				"rtcl: program cache: %s is not a regular file; building from "
				"source\n",
				cache->path);
		close(fd);
		return NULL;
	}
	file = fdopen(fd, "rb");
	if (!file)
		close(fd);
	return file;
}

/* Reads the cached binary for the key; NULL when there is none whole. */
static unsigned char *read_binary(const struct progcache *cache, size_t *size)
{
	FILE *file = open_entry(cache);
	struct header h;
	unsigned char *binary = NULL;

	if (!file)
		return NULL;
	if (fread(&h, sizeof(h), 1, file) != 1 || memcmp(h.magic, magic, sizeof(magic)) ||
	    h.key != cache->key || h.binary_size == 0 || h.binary_size > MAX_BINARY_BYTES)
		goto out_close;
	binary = malloc(h.binary_size);
	if (binary &&
	    (fread(binary, 1, h.binary_size, file) != h.binary_size || fgetc(file) != EOF ||
	     fnv1a(0xcbf29ce484222325ULL, binary, h.binary_size) != h.binary_hash)) {
		free(binary);
		binary = NULL;
	}
	*size = h.binary_size;
out_close:
	fclose(file);
	if (!binary && cache->verbose)
		fprintf(stderr, "rtcl: program cache: %s is damaged; building from source\n",
			quote_text(cache->path));
	return binary;
}

cl_program progcache_load(const struct progcache *cache, const struct device *dev)
{
	unsigned char *binary;
	const unsigned char *binaries[1];
	size_t size = 0;
	cl_int status, binary_status = CL_SUCCESS;
	cl_program program;

	if (!cache->enabled || !cache->path[0])
		return NULL;
	binary = read_binary(cache, &size);
	if (!binary)
		return NULL;
	binaries[0] = binary;
	program = clCreateProgramWithBinary(dev->context, 1, &dev->id, &size, binaries,
					    &binary_status, &status);
	free(binary);
	if (status == CL_SUCCESS && binary_status == CL_SUCCESS &&
	    clBuildProgram(program, 1, &dev->id, cache->options, NULL, NULL) == CL_SUCCESS)
		return program;
	if (status == CL_SUCCESS)
		clReleaseProgram(program);
	if (cache->verbose)
		fprintf(stderr,
			"rtcl: program cache: the device refused %s; building from source\n",
			quote_text(cache->path));
	return NULL;
}

/* Creates the cache folder and its parents, as `mkdir -p` (0700: a user's
 * cache is private). */
static int make_dirs(char *path)
{
	for (char *slash = strchr(path + 1, '/'); slash; slash = strchr(slash + 1, '/')) {
		*slash = '\0';
		int failed = mkdir(path, 0700) != 0 && errno != EEXIST;
		*slash = '/';
		if (failed)
			return -1;
	}
	return 0;
}

/* A temporary file older than this whose writer cannot be told (a name
 * without a pid) is left over: a write takes well under a second. */
#define STALE_SECONDS 3600

/* Whether the temporary file `name` in dir (a "<key>.bin.tmp-" name) was left
 * by a writer that is gone: its pid is not running, or, without one, it is
 * older than STALE_SECONDS. */
static int left_over(int dir_fd, const char *name)
{
	const char *tail = strstr(name, ".bin.tmp-") + strlen(".bin.tmp-");
	char *end;
	long pid = strtol(tail, &end, 10);
	struct stat st;

	if (end != tail && *end == '-' && pid > 0)
		return pid != (long)getpid() && kill((pid_t)pid, 0) != 0 && errno == ESRCH;
	return fstatat(dir_fd, name, &st, AT_SYMLINK_NOFOLLOW) == 0 && S_ISREG(st.st_mode) &&
	       st.st_mtime + STALE_SECONDS < time(NULL);
}

/* Removes the temporary files of the cache folder (of path) that writers
 * killed before their rename left behind. */
static void remove_left_over(const char *path)
{
	char dir_path[4096];
	char *slash;
	struct dirent *entry;
	DIR *dir;

	snprintf(dir_path, sizeof(dir_path), "%s", path);
	slash = strrchr(dir_path, '/');
	if (!slash)
		return;
	*slash = '\0';
	dir = opendir(dir_path);
	if (!dir)
		return;
	while ((entry = readdir(dir)))
		if (strstr(entry->d_name, ".bin.tmp-") && left_over(dirfd(dir), entry->d_name))
			unlinkat(dirfd(dir), entry->d_name, 0);
	closedir(dir);
}

/* Writes header and binary to a temporary file beside path and renames it
 * over path; an interrupt meanwhile removes the temporary file. Returns 0,
 * or -1 with errno set. */
static int write_atomically(const char *path, const struct header *h, const unsigned char *binary)
{
	char temp[4200];
	int fd, saved, tracked;
	FILE *file;

	snprintf(temp, sizeof(temp), "%s.tmp-%ld-XXXXXX", path, (long)getpid());
	interrupt_hold();
	fd = mkstemp(temp);
	tracked = fd >= 0 && interrupt_track(temp) == 0;
	saved = fd < 0 ? errno : EMFILE;
	interrupt_release();
	if (fd < 0) {
		errno = saved;
		return -1;
	}
	if (!tracked) {
		close(fd);
		goto out_unlink;
	}
	file = fdopen(fd, "wb");
	if (!file) {
		saved = errno;
		close(fd);
		goto out_unlink;
	}
	if (fwrite(h, sizeof(*h), 1, file) != 1 ||
	    fwrite(binary, 1, h->binary_size, file) != h->binary_size) {
		saved = errno;
		fclose(file);
		goto out_unlink;
	}
	hook_cache_write_delay();
	if (fclose(file) != 0) {
		saved = errno;
		goto out_unlink;
	}
	interrupt_hold();
	if (rename(temp, path) == 0) {
		interrupt_untrack(temp);
		interrupt_release();
		return 0;
	}
	saved = errno;
	interrupt_release();
out_unlink:
	interrupt_hold();
	unlink(temp);
	if (tracked)
		interrupt_untrack(temp);
	interrupt_release();
	errno = saved;
	return -1;
}

void progcache_save(const struct progcache *cache, cl_program program)
{
	struct header h = {{0}, cache->key, 0, 0};
	unsigned char *binary;
	char dir[4096];
	size_t size = 0;

	if (!cache->enabled || !cache->path[0])
		return;
	if (clGetProgramInfo(program, CL_PROGRAM_BINARY_SIZES, sizeof(size), &size, NULL) !=
		    CL_SUCCESS ||
	    size == 0 || size > MAX_BINARY_BYTES || !(binary = malloc(size)))
		return; /* a device without binaries: nothing to cache */
	if (clGetProgramInfo(program, CL_PROGRAM_BINARIES, sizeof(binary), &binary, NULL) ==
	    CL_SUCCESS) {
		memcpy(h.magic, magic, sizeof(magic));
		h.binary_hash = fnv1a(0xcbf29ce484222325ULL, binary, size);
		h.binary_size = size;
		snprintf(dir, sizeof(dir), "%s", cache->path);
		int failed = make_dirs(dir);
		if (!failed) {
			remove_left_over(cache->path);
			failed = write_atomically(cache->path, &h, binary);
		}
		if (failed && cache->verbose)
			fprintf(stderr, "rtcl: program cache: cannot write %s (%s)\n",
				quote_text(cache->path), strerror(errno));
	}
	free(binary);
}
