#include "stats.h"

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

int stats_check_writable(const char *path, char *err, size_t err_size)
{
	char dir[4096];
	struct stat st;

	directory_of(path, dir, sizeof(dir));
	if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
		snprintf(err, err_size, "%s: directory %s does not exist", path, dir);
		return -1;
	}
	if (access(dir, W_OK) != 0) {
		snprintf(err, err_size, "%s: cannot write in %s: %s", path, dir, strerror(errno));
		return -1;
	}
	if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
		snprintf(err, err_size, "%s: exists and is not a regular file", path);
		return -1;
	}
	return 0;
}

int stats_write(const char *path, const json_t *document, char *err, size_t err_size)
{
	char dir[4096], tmp[4200];
	int fd;

	directory_of(path, dir, sizeof(dir));
	snprintf(tmp, sizeof(tmp), "%s/.rtcl-stats-XXXXXX", dir);
	fd = mkstemp(tmp);
	if (fd < 0) {
		snprintf(err, err_size, "%s: cannot create a temporary file in %s: %s", path, dir,
			 strerror(errno));
		return -1;
	}
	FILE *f = fdopen(fd, "w");
	if (!f) {
		close(fd);
		goto out_remove;
	}
	int failed = json_dumpf(document, f, JSON_INDENT(2) | JSON_REAL_PRECISION(9)) != 0;
	failed |= fputc('\n', f) == EOF;
	failed |= fflush(f) != 0 || fsync(fileno(f)) != 0;
	failed |= fclose(f) != 0;
	if (failed)
		goto out_remove;
	if (chmod(tmp, 0644) != 0 || rename(tmp, path) != 0)
		goto out_remove;
	return 0;

out_remove:
	snprintf(err, err_size, "%s: cannot write: %s", path, strerror(errno));
	unlink(tmp);
	return -1;
}
