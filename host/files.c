#include "files.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int files_read(const char *path, const char *noun, size_t max_bytes, char **out,
	       size_t *out_len, char *err, size_t err_size)
{
	size_t len = 0, capacity;
	struct stat st;
	char *buf = NULL;
	int fd;

	/* O_NONBLOCK: a FIFO must not hang the open; it is refused below. */
	fd = open(path, O_RDONLY | O_NONBLOCK);
	if (fd < 0) {
		snprintf(err, err_size, "%s: cannot open: %s", path, strerror(errno));
		return -1;
	}
	if (fstat(fd, &st) != 0) {
		snprintf(err, err_size, "%s: cannot stat: %s", path, strerror(errno));
		goto out_close;
	}
	if (!S_ISREG(st.st_mode)) {
		snprintf(err, err_size, "%s: not a regular file", path);
		goto out_close;
	}
	if ((unsigned long long)st.st_size > max_bytes) {
		snprintf(err, err_size, "%s: %s is %lld bytes, more than the limit of %zu bytes", path,
			 noun, (long long)st.st_size, max_bytes);
		goto out_close;
	}

	/* The size may change while we read; trust what read() returns. */
	capacity = (size_t)st.st_size + 1;
	buf = malloc(capacity);
	if (!buf) {
		snprintf(err, err_size, "%s: out of memory", path);
		goto out_close;
	}
	for (;;) {
		ssize_t n;

		if (len == capacity) {
			char *grown;

			if (capacity > max_bytes) {
				snprintf(err, err_size, "%s: %s is more than the limit of %zu bytes",
					 path, noun, max_bytes);
				goto out_free;
			}
			grown = realloc(buf, capacity * 2);
			if (!grown) {
				snprintf(err, err_size, "%s: out of memory", path);
				goto out_free;
			}
			buf = grown;
			capacity *= 2;
		}
		n = read(fd, buf + len, capacity - len);
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0) {
			snprintf(err, err_size, "%s: cannot read: %s", path, strerror(errno));
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

/* Writes dirname(path) into dir. */
static void directory_of(const char *path, char *dir, size_t dir_size)
{
	const char *slash = strrchr(path, '/');

	if (!slash)
		snprintf(dir, dir_size, ".");
	else if (slash == path)
		snprintf(dir, dir_size, "/");
	else
		snprintf(dir, dir_size, "%.*s", (int)(slash - path), path);
}

int files_check_writable(const char *path, char *err, size_t err_size)
{
	char dir[4096];
	struct stat st;

	directory_of(path, dir, sizeof(dir));
	if (path[0] == '\0' || path[strlen(path) - 1] == '/') {
		snprintf(err, err_size, "%s: not a file name", path);
		return -1;
	}
	if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
		snprintf(err, err_size, "%s: directory \"%s\" does not exist", path, dir);
		return -1;
	}
	if (access(dir, W_OK) != 0) {
		snprintf(err, err_size, "%s: cannot write in \"%s\": %s", path, dir,
			 strerror(errno));
		return -1;
	}
	if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
		snprintf(err, err_size, "%s: exists and is not a regular file", path);
		return -1;
	}
	return 0;
}

int files_write(const char *path, files_fill fill, const void *context, char *err,
		  size_t err_size)
{
	char dir[4096], tmp[4200];
	mode_t mask = umask(0);

	umask(mask);
	directory_of(path, dir, sizeof(dir));
	snprintf(tmp, sizeof(tmp), "%s/.rtcl-out-XXXXXX", dir);
	int fd = mkstemp(tmp);
	if (fd < 0) {
		snprintf(err, err_size, "%s: cannot create a temporary file in \"%s\": %s", path,
			 dir, strerror(errno));
		return -1;
	}
	FILE *file = fdopen(fd, "wb");
	if (!file) {
		close(fd);
		goto out_remove;
	}
	errno = 0;
	int failed = fill(file, context) != 0;
	failed |= fflush(file) != 0 || fsync(fileno(file)) != 0;
	failed |= fclose(file) != 0;
	if (failed || chmod(tmp, 0666 & ~mask) != 0 || rename(tmp, path) != 0)
		goto out_remove;
	return 0;

out_remove:
	snprintf(err, err_size, "%s: cannot write: %s", path,
		 errno ? strerror(errno) : "write failed");
	unlink(tmp);
	return -1;
}

void files_remove(const char *path)
{
	unlink(path);
}
