#include "files.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "interrupt.h"
#include "quote.h"

/* Longest part of the target's name kept in the temporary file's name, so
 * that the latter stays under NAME_MAX (255) with its additions. */
#define TEMP_NAME_KEEP 100
#define TEMP_CREATE_TRIES 100

/* Opens path for reading if it is a regular file of at most max_bytes;
 * returns the descriptor and its size in *size, or -1 with a message. */
static int open_regular(const char *path, const char *noun, size_t max_bytes, size_t *size,
			char *err, size_t err_size)
{
	struct stat st;
	/* O_NONBLOCK: a FIFO must not hang the open; it is refused below. */
	int fd = open(path, O_RDONLY | O_NONBLOCK);

	if (fd < 0) {
		snprintf(err, err_size, "%s: cannot open: %s", quote_text(path), strerror(errno));
		return -1;
	}
	if (fstat(fd, &st) != 0)
		snprintf(err, err_size, "%s: cannot stat: %s", quote_text(path), strerror(errno));
	else if (!S_ISREG(st.st_mode))
		snprintf(err, err_size, "%s: not a regular file", quote_text(path));
	else if ((unsigned long long)st.st_size > max_bytes)
		snprintf(err, err_size, "%s: %s is %lld bytes, more than the limit of %zu bytes",
			 quote_text(path), noun, (long long)st.st_size, max_bytes);
	else {
		*size = (size_t)st.st_size;
		return fd;
	}
	close(fd);
	return -1;
}

int files_read(const char *path, const char *noun, size_t max_bytes, char **out,
	       size_t *out_len, char *err, size_t err_size)
{
	size_t len = 0, capacity;
	char *buf;
	int fd = open_regular(path, noun, max_bytes, &capacity, err, err_size);

	if (fd < 0)
		return -1;
	/* The size may change while we read; trust what read() returns. */
	capacity++;
	buf = malloc(capacity);
	if (!buf) {
		snprintf(err, err_size, "%s: out of memory", quote_text(path));
		goto out_close;
	}
	for (;;) {
		if (len == capacity) {
			char *grown = capacity > max_bytes ? NULL : realloc(buf, capacity * 2);
			if (!grown) {
				if (capacity > max_bytes)
					snprintf(err, err_size,
						 "%s: %s is more than the limit of %zu bytes", quote_text(path),
						 noun, max_bytes);
				else
					snprintf(err, err_size, "%s: out of memory", quote_text(path));
				goto out_free;
			}
			buf = grown;
			capacity *= 2;
		}
		ssize_t n = read(fd, buf + len, capacity - len);
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0) {
			snprintf(err, err_size, "%s: cannot read: %s", quote_text(path), strerror(errno));
			goto out_free;
		}
		if (n == 0)
			break;
		len += (size_t)n;
	}
	close(fd);
	buf[len] = '\0'; /* the loop leaves room for it */
	*out = buf;
	*out_len = len;
	return 0;

out_free:
	free(buf);
out_close:
	close(fd);
	return -1;
}

static uint64_t splitmix64(uint64_t *state)
{
	uint64_t z = (*state += 0x9e3779b97f4a7c15u);

	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
	return z ^ (z >> 31);
}

/* Creates DIR/.NAME.tmp-PID-XXXXXX.EXT next to target, exclusively, with
 * mode 0666 less the umask like any new file. The extension is kept so that
 * OpenImageIO picks the format from the temporary name as well. Returns the
 * descriptor, open for writing, with the name in f->temp; or -1. */
static int create_temp(struct staged_file *f, char *err, size_t err_size)
{
	static const char digits[] = "0123456789abcdefghijklmnopqrstuvwxyz";
	static unsigned counter;
	const char *base = files_base_name(f->target);
	const char *ext = files_extension(f->target);
	struct timespec now;
	uint64_t state;
	char suffix[7];

	clock_gettime(CLOCK_REALTIME, &now);
	state = (uint64_t)now.tv_nsec ^ ((uint64_t)now.tv_sec << 30) ^ ((uint64_t)getpid() << 42) ^
		counter++;
	for (int tries = 0; tries < TEMP_CREATE_TRIES; tries++) {
		uint64_t bits = splitmix64(&state);

		for (int i = 0; i < 6; i++, bits /= 36)
			suffix[i] = digits[bits % 36];
		suffix[6] = '\0';
		int n = snprintf(f->temp, sizeof(f->temp), "%.*s.%.*s.tmp-%ld-%s%s",
				 (int)(base - f->target), f->target, TEMP_NAME_KEEP, base,
				 (long)getpid(), suffix, ext);
		if (n < 0 || (size_t)n >= sizeof(f->temp)) {
			snprintf(err, err_size, "%s: %s", quote_text(f->target), strerror(ENAMETOOLONG));
			return -1;
		}
		int fd = open(f->temp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
		if (fd >= 0)
			return fd;
		if (errno != EEXIST)
			break;
	}
	snprintf(err, err_size, "%s: cannot create a file in its directory: %s", quote_text(f->target),
		 strerror(errno));
	return -1;
}

int files_stage(struct staged_file *f, const char *target, char *err, size_t err_size)
{
	int fd;

	f->target = target;
	f->temp[0] = '\0';
	interrupt_hold();
	fd = create_temp(f, err, err_size);
	if (fd >= 0 && interrupt_track(f->temp)) {
		snprintf(err, err_size, "%s: too many files open for writing at once", quote_text(target));
		close(fd);
		unlink(f->temp);
		fd = -1;
	}
	if (fd < 0)
		f->temp[0] = '\0';
	interrupt_release();
	return fd;
}

void files_discard(struct staged_file *f)
{
	interrupt_hold();
	if (f->temp[0]) {
		unlink(f->temp);
		interrupt_untrack(f->temp);
		f->temp[0] = '\0';
	}
	interrupt_release();
}

int files_commit(struct staged_file *files, int count, char *err, size_t err_size)
{
	int ret = 0;

	interrupt_hold();
	for (int i = 0; i < count; i++) {
		struct staged_file *f = &files[i];
		if (ret == 0 && rename(f->temp, f->target) != 0) {
			snprintf(err, err_size, "%s: cannot replace: %s", quote_text(f->target),
				 strerror(errno));
			ret = -1;
		}
		if (ret != 0)
			unlink(f->temp); /* the ones renamed before stay renamed */
		interrupt_untrack(f->temp);
		f->temp[0] = '\0';
	}
	interrupt_release();
	return ret;
}

int files_sync_close(int fd)
{
	int failed = fsync(fd) != 0 && errno != EINVAL; /* as in files_stage_with */
	int saved = errno;

	if (close(fd) != 0)
		return -1;
	errno = saved;
	return failed ? -1 : 0;
}

int files_stage_with(struct staged_file *f, const char *target, files_fill fill,
		     const void *context, char *err, size_t err_size)
{
	int fd = files_stage(f, target, err, err_size);
	FILE *file;

	if (fd < 0)
		return -1;
	file = fdopen(fd, "wb");
	if (!file) {
		close(fd);
		goto out_discard;
	}
	errno = 0;
	/* fsync fails with EINVAL where the file system cannot sync: nothing to
	 * report then. A deferred write error (ENOSPC, EIO) shows up here. */
	int failed = fill(file, context) != 0 || fflush(file) != 0 ||
		     (fsync(fileno(file)) != 0 && errno != EINVAL);
	failed |= fclose(file) != 0;
	if (failed)
		goto out_discard;
	return 0;

out_discard:
	snprintf(err, err_size, "%s: cannot write: %s", quote_text(target),
		 errno ? strerror(errno) : "write failed");
	files_discard(f);
	return -1;
}

int files_write(const char *path, files_fill fill, const void *context, char *err,
		size_t err_size)
{
	struct staged_file f;

	if (files_stage_with(&f, path, fill, context, err, err_size))
		return -1;
	return files_commit(&f, 1, err, err_size);
}

const char *files_base_name(const char *path)
{
	const char *slash = strrchr(path, '/');

	return slash ? slash + 1 : path;
}

const char *files_extension(const char *path)
{
	const char *base = files_base_name(path);
	const char *dot = strrchr(base, '.');

	/* ".png" is a hidden file's name, not an extension */
	return dot && dot != base ? dot : "";
}

/* Copies the directory part of path ("." for none) into dir[PATH_MAX]. */
static int directory_of(const char *path, char *dir, char *err, size_t err_size)
{
	size_t length = (size_t)(files_base_name(path) - path);

	if (length == 0) {
		snprintf(dir, PATH_MAX, ".");
		return 0;
	}
	if (length > 1)
		length--; /* drop the slash, except for "/" itself */
	if (length >= PATH_MAX) {
		snprintf(err, err_size, "%s: %s", quote_text(path), strerror(ENAMETOOLONG));
		return -1;
	}
	memcpy(dir, path, length);
	dir[length] = '\0';
	return 0;
}

/* The directory exists, is one, and takes a name this long. */
static int check_directory(const char *path, const char *dir, char *err, size_t err_size)
{
	struct stat st;
	long name_max;

	if (stat(dir, &st) != 0) {
		if (errno == ENOENT)
			snprintf(err, err_size, "%s: directory \"%s\" does not exist", quote_text(path), quote_text(dir));
		else
			snprintf(err, err_size, "%s: directory \"%s\": %s", quote_text(path), quote_text(dir),
				 strerror(errno));
		return -1;
	}
	if (!S_ISDIR(st.st_mode)) {
		snprintf(err, err_size, "%s: \"%s\" is not a directory", quote_text(path), quote_text(dir));
		return -1;
	}
	name_max = pathconf(dir, _PC_NAME_MAX);
	if (name_max > 0 && strlen(files_base_name(path)) > (size_t)name_max) {
		snprintf(err, err_size,
			 "%s: the file name is %zu characters long, more than the %ld this file "
			 "system allows",
			 quote_text(path), strlen(files_base_name(path)), name_max);
		return -1;
	}
	return 0;
}

/* An existing target is replaced only if the user could overwrite it, as cp
 * would, and if the rename will be allowed (a sticky directory lets only the
 * file's or the directory's owner replace it). */
static int check_replaceable(const char *path, const char *dir, char *err, size_t err_size)
{
	struct stat st, dir_st;
	uid_t me = geteuid();

	if (lstat(path, &st) != 0)
		return 0; /* nothing to replace */
	if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
		snprintf(err, err_size,
			 "%s: exists and is not a regular file; refusing to replace it", quote_text(path));
		return -1;
	}
	if (access(path, W_OK) != 0 && errno != ENOENT) {
		snprintf(err, err_size,
			 "%s: exists and you cannot write it (%s); rtcl replaces only a file you "
			 "could overwrite: remove it or choose another name",
			 quote_text(path), strerror(errno));
		return -1;
	}
	if (lstat(path, &st) == 0 && stat(dir, &dir_st) == 0 && (dir_st.st_mode & S_ISVTX) &&
	    me != 0 && st.st_uid != me && dir_st.st_uid != me) {
		snprintf(err, err_size,
			 "%s: belongs to another user in the sticky directory \"%s\", so it "
			 "cannot be replaced: choose another name",
			 quote_text(path), quote_text(dir));
		return -1;
	}
	return 0;
}

int files_check_writable(const char *path, char *err, size_t err_size)
{
	char dir[PATH_MAX];
	struct staged_file trial;
	int fd;

	if (path[0] == '\0' || path[strlen(path) - 1] == '/') {
		snprintf(err, err_size, "%s: not a file name", quote_text(path));
		return -1;
	}
	if (directory_of(path, dir, err, err_size) || check_directory(path, dir, err, err_size) ||
	    check_replaceable(path, dir, err, err_size))
		return -1;
	/* What the write will do: create a file beside the target. */
	fd = files_stage(&trial, path, err, err_size);
	if (fd < 0)
		return -1;
	close(fd);
	files_discard(&trial);
	return 0;
}
