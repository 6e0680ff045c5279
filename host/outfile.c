#include "outfile.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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

int outfile_check_writable(const char *path, char *err, size_t err_size)
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

int outfile_write(const char *path, outfile_fill fill, const void *context, char *err,
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

void outfile_remove(const char *path)
{
	unlink(path);
}
