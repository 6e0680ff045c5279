#include "base/files.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "base/interrupt.h"
#include "base/quote.h"

/* Longest part of the target's name kept in the temporary file's name, so
 * that the latter stays under NAME_MAX (255) with its additions. */
#define TEMP_NAME_KEEP 100
#define TEMP_CREATE_TRIES 100
#define NAME_MAX_PORTABLE 255
/* In a staging folder: the new files, and the old ones during a commit. */
#define TEMP_PREFIX "new-"
#define BACKUP_PREFIX "old-"
#define STAGE_PREFIX ".rtcl-stage-"
/* Output folders a run writes into at once (the outputs of one run: seven at
 * most), and those it clears of stale staging folders. */
#define STAGE_DIRS_MAX 16
#define SWEPT_DIRS_MAX 64
/* Room for a host name in a staging folder's name. */
#define HOST_NAME_KEEP 65

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

int files_read(const char *path, const char *noun, size_t max_bytes, char **out, size_t *out_len,
	       char *err, size_t err_size)
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
						 "%s: %s is more than the limit of %zu bytes",
						 quote_text(path), noun, max_bytes);
				else
					snprintf(err, err_size, "%s: out of memory",
						 quote_text(path));
				goto out_free;
			}
			buf = grown;
			capacity *= 2;
		}
		ssize_t n = read(fd, buf + len, capacity - len);
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0) {
			snprintf(err, err_size, "%s: cannot read: %s", quote_text(path),
				 strerror(errno));
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

/* Six random characters and a NUL into suffix. */
static void random_suffix(char suffix[7])
{
	static const char digits[] = "0123456789abcdefghijklmnopqrstuvwxyz";
	static uint64_t state;
	struct timespec now;

	clock_gettime(CLOCK_REALTIME, &now);
	state ^= (uint64_t)now.tv_nsec ^ ((uint64_t)now.tv_sec << 30) ^ ((uint64_t)getpid() << 42);
	uint64_t bits = splitmix64(&state);
	for (int i = 0; i < 6; i++, bits /= 36)
		suffix[i] = digits[bits % 36];
	suffix[6] = '\0';
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

/* ---- staging folders -------------------------------------------------- */

/* One staging folder of this run, in an output folder. */
struct stage_dir {
	dev_t dev; /* the output folder */
	ino_t ino;
	char path[PATH_MAX]; /* DIR/.rtcl-stage-HOST-PID; "" when the slot is free */
	int files;	     /* staged files in it */
};

/* Every staging folder in use (under interrupt_hold()), and the output
 * folders already cleared of stale ones in this run. */
static struct stage_dir stage_dirs[STAGE_DIRS_MAX];
static struct {
	dev_t dev;
	ino_t ino;
} swept[SWEPT_DIRS_MAX];
static int swept_count;
static int rename_failure_at;

void files_inject_rename_failure(int nth)
{
	rename_failure_at = nth;
}

/* This host's name, as it appears in staging folders' names. */
static void host_name(char *host, size_t size)
{
	if (gethostname(host, size) != 0)
		snprintf(host, size, "localhost");
	host[size - 1] = '\0';
	for (char *c = host; *c; c++)
		if (*c == '/' || *c == '-')
			*c = '_'; /* the last '-' of the folder's name comes before the pid */
}

/* Whether the entry `name` of an output folder is a staging folder that a
 * killed run of this host left: its process is gone, or it is this process's
 * own from an earlier process with the same pid (this run has not created
 * its own in that folder yet). */
static int is_stale_stage(const char *name, const char *host)
{
	size_t prefix = strlen(STAGE_PREFIX), host_length = strlen(host);
	const char *rest = name + prefix;
	char *end;
	long pid;

	if (strncmp(name, STAGE_PREFIX, prefix) || strncmp(rest, host, host_length) ||
	    rest[host_length] != '-')
		return 0;
	errno = 0;
	pid = strtol(rest + host_length + 1, &end, 10);
	if (end == rest + host_length + 1 || *end || pid <= 0 || errno)
		return 0;
	return pid == (long)getpid() || (kill((pid_t)pid, 0) != 0 && errno == ESRCH);
}

/* Removes the stale staging folder `name` of the folder dir_fd: its new
 * files, and its old files (BACKUP_PREFIX) put back where their target is
 * missing (a run killed in the middle of a commit). */
static void clear_stale_stage(int dir_fd, const char *name)
{
	size_t prefix = strlen(BACKUP_PREFIX);
	int fd = openat(dir_fd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
	DIR *stage = fd >= 0 ? fdopendir(fd) : NULL;
	struct dirent *entry;
	struct stat st;

	/* Only one's own: another user's is none of this run's business. */
	if (!stage || fstat(fd, &st) != 0 || st.st_uid != geteuid()) {
		if (stage)
			closedir(stage);
		else if (fd >= 0)
			close(fd);
		return;
	}
	while ((entry = readdir(stage))) {
		const char *e = entry->d_name;

		if (!strcmp(e, ".") || !strcmp(e, ".."))
			continue;
		if (!strncmp(e, BACKUP_PREFIX, prefix) && e[prefix] &&
		    fstatat(dir_fd, e + prefix, &st, AT_SYMLINK_NOFOLLOW) != 0 && errno == ENOENT)
			renameat(fd, e, dir_fd, e + prefix);
		else
			unlinkat(fd, e, 0);
	}
	closedir(stage);
	unlinkat(dir_fd, name, AT_REMOVEDIR);
}

/* Clears dir of the staging folders that killed runs of this host left, once
 * a run. */
static void sweep_once(const char *dir, const struct stat *st)
{
	char host[HOST_NAME_KEEP];
	struct dirent *entry;
	DIR *d;

	for (int i = 0; i < swept_count; i++)
		if (swept[i].dev == st->st_dev && swept[i].ino == st->st_ino)
			return;
	if (swept_count < SWEPT_DIRS_MAX) {
		swept[swept_count].dev = st->st_dev;
		swept[swept_count++].ino = st->st_ino;
	}
	d = opendir(dir);
	if (!d)
		return;
	host_name(host, sizeof(host));
	while ((entry = readdir(d)))
		if (is_stale_stage(entry->d_name, host))
			clear_stale_stage(dirfd(d), entry->d_name);
	closedir(d);
}

/* The staging folder for a file in dir (target names it in messages),
 * created on its first use; returns its index, or -1 with one message in
 * err. Under interrupt_hold(). */
static int acquire_stage(const char *target, const char *dir, char *err, size_t err_size)
{
	char host[HOST_NAME_KEEP];
	struct stage_dir *s = NULL;
	struct stat st;
	int slot = -1;

	if (stat(dir, &st) != 0) {
		snprintf(err, err_size, "%s: directory \"%s\": %s", quote_text(target),
			 quote_text(dir), strerror(errno));
		return -1;
	}
	for (int i = 0; i < STAGE_DIRS_MAX; i++) {
		if (stage_dirs[i].path[0] && stage_dirs[i].dev == st.st_dev &&
		    stage_dirs[i].ino == st.st_ino) {
			stage_dirs[i].files++;
			return i;
		}
		if (!stage_dirs[i].path[0] && slot < 0)
			slot = i;
	}
	if (slot < 0) {
		snprintf(err, err_size, "%s: more than %d output folders at once",
			 quote_text(target), STAGE_DIRS_MAX);
		return -1;
	}
	sweep_once(dir, &st);
	s = &stage_dirs[slot];
	host_name(host, sizeof(host));
	int n = snprintf(s->path, sizeof(s->path), "%s/%s%s-%ld", dir, STAGE_PREFIX, host,
			 (long)getpid());
	if (n < 0 || (size_t)n >= sizeof(s->path)) {
		snprintf(err, err_size, "%s: %s", quote_text(target), strerror(ENAMETOOLONG));
	} else if (mkdir(s->path, 0700) != 0) {
		snprintf(err, err_size, "%s: cannot create a file in its directory: %s",
			 quote_text(target), strerror(errno));
	} else if (interrupt_track(s->path)) {
		snprintf(err, err_size, "%s: too many files open for writing at once",
			 quote_text(target));
		rmdir(s->path);
	} else {
		s->dev = st.st_dev;
		s->ino = st.st_ino;
		s->files = 1;
		return slot;
	}
	s->path[0] = '\0';
	return -1;
}

/* One file fewer in staging folder i, which goes once empty. Under
 * interrupt_hold(). */
static void release_stage(int i)
{
	struct stage_dir *s = &stage_dirs[i];

	if (--s->files > 0)
		return;
	rmdir(s->path);
	interrupt_untrack(s->path);
	s->path[0] = '\0';
}

/* ---- staging and committing --------------------------------------------- */

/* The file that writing target replaces, into path[PATH_MAX]: target
 * itself, or where it leads when it is a symbolic link (written through, as
 * cp does; a link that leads nowhere is refused, as cp refuses it). Returns 0,
 * or -1 with one message in err. */
static int resolve_target(const char *target, char *path, char *err, size_t err_size)
{
	struct stat st;

	if (lstat(target, &st) != 0 || !S_ISLNK(st.st_mode)) {
		if (strlen(target) >= PATH_MAX) {
			snprintf(err, err_size, "%s: %s", quote_text(target),
				 strerror(ENAMETOOLONG));
			return -1;
		}
		strcpy(path, target);
		return 0;
	}
	if (realpath(target, path))
		return 0;
	if (errno == ENOENT)
		snprintf(
			err, err_size,
			"%s: is a symbolic link to a file that does not exist; rtcl writes through "
			"a link only to an existing file, as cp does: create the file or remove "
			"the link",
			quote_text(target));
	else
		snprintf(err, err_size, "%s: cannot follow the symbolic link: %s",
			 quote_text(target), strerror(errno));
	return -1;
}

/* Creates STAGE/new-NAME-XXXXXX.EXT for f, exclusively, with mode 0666 less
 * the umask like any new file. The extension of the name the user gave is
 * kept so that OpenImageIO picks the format from the temporary name as well.
 * Returns the descriptor, open for writing, with the name in f->temp; or -1. */
static int create_temp(struct staged_file *f, char *err, size_t err_size)
{
	const char *base = files_base_name(f->path);
	const char *ext = files_extension(f->target);
	char suffix[7];

	for (int tries = 0; tries < TEMP_CREATE_TRIES; tries++) {
		random_suffix(suffix);
		int n = snprintf(f->temp, sizeof(f->temp), "%s/%s%.*s-%s%s",
				 stage_dirs[f->stage].path, TEMP_PREFIX, TEMP_NAME_KEEP, base,
				 suffix, ext);
		if (n < 0 || (size_t)n >= sizeof(f->temp)) {
			snprintf(err, err_size, "%s: %s", quote_text(f->target),
				 strerror(ENAMETOOLONG));
			return -1;
		}
		int fd = open(f->temp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
		if (fd >= 0)
			return fd;
		if (errno != EEXIST)
			break;
	}
	snprintf(err, err_size, "%s: cannot create a file in its directory: %s",
		 quote_text(f->target), strerror(errno));
	return -1;
}

int files_stage(struct staged_file *f, const char *target, char *err, size_t err_size)
{
	char dir[PATH_MAX];
	int fd = -1;

	f->target = target;
	f->temp[0] = '\0';
	f->stage = -1;
	if (resolve_target(target, f->path, err, err_size) ||
	    directory_of(f->path, dir, err, err_size))
		return -1;
	interrupt_hold();
	f->stage = acquire_stage(target, dir, err, err_size);
	if (f->stage >= 0)
		fd = create_temp(f, err, err_size);
	if (fd >= 0 && interrupt_track(f->temp)) {
		snprintf(err, err_size, "%s: too many files open for writing at once",
			 quote_text(target));
		close(fd);
		unlink(f->temp);
		fd = -1;
	}
	if (fd < 0) {
		f->temp[0] = '\0';
		if (f->stage >= 0)
			release_stage(f->stage);
	}
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
		release_stage(f->stage);
	}
	interrupt_release();
}

/* A target's previous file while a commit runs. */
struct old_file {
	char backup[PATH_MAX]; /* its second name in the staging folder; "" for none */
	int moved;	       /* the backup is its only name (no hard link was possible) */
};

/* Where f's old file is kept during the commit: STAGE/old-NAME, from which
 * a later run puts it back if this one is killed in between; a name too long
 * for that gets a shortened one with a random part. */
static void backup_name(const struct staged_file *f, char *backup)
{
	const char *base = files_base_name(f->path);
	const char *stage = stage_dirs[f->stage].path;
	char suffix[7];

	if (strlen(BACKUP_PREFIX) + strlen(base) <= NAME_MAX_PORTABLE) {
		snprintf(backup, PATH_MAX, "%s/%s%s", stage, BACKUP_PREFIX, base);
		return;
	}
	random_suffix(suffix);
	snprintf(backup, PATH_MAX, "%s/old~%.*s-%s", stage, TEMP_NAME_KEEP, base, suffix);
}

/* Gives f's target, if it exists, a second name in old->backup: a hard
 * link, or where the file system allows none, the file moved there. Refuses
 * a target that is no longer a regular file. Returns 0, or -1 with one
 * message in err. */
static int keep_old(const struct staged_file *f, struct old_file *old, char *err, size_t err_size)
{
	struct stat st;

	if (lstat(f->path, &st) != 0) {
		if (errno == ENOENT)
			return 0;
		snprintf(err, err_size, "%s: cannot replace: %s", quote_text(f->target),
			 strerror(errno));
		return -1;
	}
	if (!S_ISREG(st.st_mode)) {
		const char *now = S_ISDIR(st.st_mode) ? "now a directory" : "replaced meanwhile";
		snprintf(err, err_size,
			 "%s: is no longer a regular file (%s), so it cannot be replaced",
			 quote_text(f->target), now);
		return -1;
	}
	backup_name(f, old->backup);
	if (link(f->path, old->backup) == 0)
		return 0;
	if (rename(f->path, old->backup) == 0) {
		old->moved = 1;
		return 0;
	}
	snprintf(err, err_size, "%s: cannot replace: %s", quote_text(f->target), strerror(errno));
	old->backup[0] = '\0';
	return -1;
}

/* After a failure once `renamed` new files were renamed in: every target
 * gets its old file back (or, having none, loses the new one). Returns the
 * index of the first target it could not put back, or -1. */
static int put_back(const struct staged_file *files, struct old_file *old, int count, int renamed)
{
	int lost = -1;

	for (int i = 0; i < count; i++) {
		int ok = 1;

		if (!old[i].backup[0])
			ok = i >= renamed || unlink(files[i].path) == 0;
		else if (i < renamed || old[i].moved)
			ok = rename(old[i].backup, files[i].path) == 0;
		else
			unlink(old[i].backup);
		if (ok)
			old[i].backup[0] = '\0';
		else if (lost < 0)
			lost = i;
	}
	return lost;
}

/* files_commit's steps, under interrupt_hold(). */
static int commit(struct staged_file *files, struct old_file *old, int count, char *err,
		  size_t err_size)
{
	int done = 0, lost;

	for (int i = 0; i < count; i++)
		if (keep_old(&files[i], &old[i], err, err_size))
			goto out_put_back;
	for (; done < count; done++) {
		struct staged_file *f = &files[done];
		int failed = rename_failure_at == done + 1 ? (errno = EIO, 1)
							   : rename(f->temp, f->path) != 0;
		if (failed) {
			snprintf(err, err_size, "%s: cannot replace: %s", quote_text(f->target),
				 strerror(errno));
			goto out_put_back;
		}
	}
	for (int i = 0; i < count; i++)
		if (old[i].backup[0])
			unlink(old[i].backup);
	return 0;

out_put_back:
	lost = put_back(files, old, count, done);
	size_t length = strlen(err);
	if (lost < 0)
		snprintf(err + length, err_size - length, "; no output was replaced");
	else
		snprintf(err + length, err_size - length,
			 "; and %s could not be put back: its previous version is %s",
			 quote_text(files[lost].target),
			 old[lost].backup[0] ? quote_text(old[lost].backup) : "lost");
	return -1;
}

int files_commit(struct staged_file *files, int count, char *err, size_t err_size)
{
	struct old_file *old = calloc(count > 0 ? (size_t)count : 1, sizeof(*old));
	int ret;

	/* The staged ones: an entry with no temporary file (an animation's
	 * frame an interrupt left unrendered) has nothing to commit. */
	struct staged_file *live = malloc((count > 0 ? (size_t)count : 1) * sizeof(*live));
	int live_count = 0;

	for (int i = 0; live && i < count; i++)
		if (files[i].temp[0])
			live[live_count++] = files[i];
	interrupt_hold();
	if (!old || !live) {
		snprintf(err, err_size, "out of host memory to replace %d files", count);
		ret = -1;
	} else {
		ret = commit(live, old, live_count, err, err_size);
	}
	for (int i = 0; i < count; i++) {
		struct staged_file *f = &files[i];

		if (!f->temp[0])
			continue;
		if (ret != 0)
			unlink(f->temp);
		interrupt_untrack(f->temp);
		f->temp[0] = '\0';
		release_stage(f->stage);
	}
	interrupt_release();
	free(live);
	free(old);
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

int files_write(const char *path, files_fill fill, const void *context, char *err, size_t err_size)
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

/* The directory exists, is one, and takes a name this long (name: the
 * path as the user gave it, for messages). */
static int check_directory(const char *name, const char *path, const char *dir, char *err,
			   size_t err_size)
{
	struct stat st;
	long name_max;

	if (stat(dir, &st) != 0) {
		if (errno == ENOENT)
			snprintf(err, err_size, "%s: directory \"%s\" does not exist",
				 quote_text(name), quote_text(dir));
		else
			snprintf(err, err_size, "%s: directory \"%s\": %s", quote_text(name),
				 quote_text(dir), strerror(errno));
		return -1;
	}
	if (!S_ISDIR(st.st_mode)) {
		snprintf(err, err_size, "%s: \"%s\" is not a directory", quote_text(name),
			 quote_text(dir));
		return -1;
	}
	name_max = pathconf(dir, _PC_NAME_MAX);
	if (name_max > 0 && strlen(files_base_name(path)) > (size_t)name_max) {
		snprintf(err, err_size,
			 "%s: the file name is %zu characters long, more than the %ld this file "
			 "system allows",
			 quote_text(name), strlen(files_base_name(path)), name_max);
		return -1;
	}
	return 0;
}

/* An existing target is replaced only if the user could overwrite it, as cp
 * would, and if the rename will be allowed (a sticky directory lets only the
 * file's or the directory's owner replace it). */
static int check_replaceable(const char *name, const char *path, const char *dir, char *err,
			     size_t err_size)
{
	struct stat st, dir_st;
	uid_t me = geteuid();

	if (lstat(path, &st) != 0)
		return 0; /* nothing to replace */
	if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
		snprintf(err, err_size,
			 "%s: exists and is not a regular file; refusing to replace it",
			 quote_text(name));
		return -1;
	}
	if (access(path, W_OK) != 0 && errno != ENOENT) {
		snprintf(err, err_size,
			 "%s: exists and you cannot write it (%s); rtcl replaces only a file you "
			 "could overwrite: remove it or choose another name",
			 quote_text(name), strerror(errno));
		return -1;
	}
	if (lstat(path, &st) == 0 && stat(dir, &dir_st) == 0 && (dir_st.st_mode & S_ISVTX) &&
	    me != 0 && st.st_uid != me && dir_st.st_uid != me) {
		snprintf(err, err_size,
			 "%s: belongs to another user in the sticky directory \"%s\", so it "
			 "cannot be replaced: choose another name",
			 quote_text(name), quote_text(dir));
		return -1;
	}
	return 0;
}

int files_check_writable(const char *path, char *err, size_t err_size)
{
	char dir[PATH_MAX], resolved[PATH_MAX];
	struct staged_file trial;
	int fd;

	if (path[0] == '\0' || path[strlen(path) - 1] == '/') {
		snprintf(err, err_size, "%s: not a file name", quote_text(path));
		return -1;
	}
	/* A symbolic link is checked where it leads: that file is replaced. */
	if (resolve_target(path, resolved, err, err_size) ||
	    directory_of(resolved, dir, err, err_size) ||
	    check_directory(path, resolved, dir, err, err_size) ||
	    check_replaceable(path, resolved, dir, err, err_size))
		return -1;
	/* What the write will do: create a file beside the target. */
	fd = files_stage(&trial, path, err, err_size);
	if (fd < 0)
		return -1;
	close(fd);
	files_discard(&trial);
	return 0;
}
