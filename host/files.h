/* Files: reading a whole input file (scenes, kernel sources), and writing
 * outputs through a temporary file in the same directory that is renamed over
 * the target once complete ("staged", then "committed"), so that a failure
 * or an interrupt leaves neither a partial nor a temporary file, and the
 * target as it was. Several staged files are committed together, so that a
 * run's outputs are replaced all or none (interrupt.h). */
#ifndef RTCL_FILES_H
#define RTCL_FILES_H

#include <limits.h>
#include <stddef.h>
#include <stdio.h>

#ifndef PATH_MAX
#define PATH_MAX 4096
#endif

/* Reads the regular file at path, of at most max_bytes, into a malloc'd
 * buffer (with a NUL after its *out_len bytes). `noun` names what the file
 * is in the message for one that is too large ("scene"). Returns 0, or -1
 * with one message in err naming path. A FIFO or device is refused without
 * blocking. */
int files_read(const char *path, const char *noun, size_t max_bytes, char **out,
	       size_t *out_len, char *err, size_t err_size);

/* An output written to a temporary file beside its target. */
struct staged_file {
	const char *target; /* kept by reference */
	char temp[PATH_MAX]; /* "" once committed or discarded */
};

/* Creates the temporary file for target (DIR/.NAME.tmp-PID-XXXXXX.EXT, the
 * extension kept) and returns its descriptor, open for writing; or -1 with
 * one message in err. An interrupt from now on removes it. */
int files_stage(struct staged_file *file, const char *target, char *err, size_t err_size);

/* Renames each staged file over its target, all inside one interrupt_hold():
 * an interrupt waits until every rename is done. Returns 0, or -1 with one
 * message in err when a rename failed (the rest are discarded). */
int files_commit(struct staged_file *files, int count, char *err, size_t err_size);

/* Removes a staged file that will not be committed. */
void files_discard(struct staged_file *file);

/* fsync (where the file system can) and close; -1 with errno on a failure. */
int files_sync_close(int fd);

/* Fills the file; returns 0, or -1 when a write failed. */
typedef int (*files_fill)(FILE *file, const void *context);

/* Stages target and fills it with fill(file, context), synced and closed.
 * Returns 0, or -1 with one message in err (nothing left behind). */
int files_stage_with(struct staged_file *file, const char *target, files_fill fill,
		     const void *context, char *err, size_t err_size);

/* files_stage_with, then files_commit. */
int files_write(const char *path, files_fill fill, const void *context, char *err,
		size_t err_size);

/* The part of path after the last slash. */
const char *files_base_name(const char *path);

/* The extension of path's base name with its dot, or "" when it has none (a
 * leading dot starts a hidden file's name, not an extension). */
const char *files_extension(const char *path);

/* Checks before any work what writing path will need: its directory exists
 * and a file can be created there, its name is not too long, and an existing
 * path is a regular file that the user could overwrite and may replace (not
 * another user's in a sticky directory). Returns 0, or -1 with one message in
 * err. */
int files_check_writable(const char *path, char *err, size_t err_size);

#endif
