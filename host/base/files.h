/* Files: reading a whole input file (scenes, kernel sources), and writing
 * outputs through a temporary file that is renamed over the target once
 * complete ("staged", then "committed"), so that a failure or an interrupt
 * leaves neither a partial nor a temporary file, and the target as it was.
 * Several staged files are committed together, all or none (interrupt.h).
 *
 * The temporary files live in one staging folder per output folder and run,
 * DIR/.rtcl-stage-HOST-PID, removed when the run ends. A run killed outright
 * (SIGKILL) cannot remove it; the next run that writes into DIR on the same
 * host removes it once process PID is gone.
 *
 * A target that is a symbolic link is written through, as cp does: the file
 * the link leads to is replaced and the link kept. A link that leads nowhere
 * is refused (cp refuses to write through a dangling link too). */
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
int files_read(const char *path, const char *noun, size_t max_bytes, char **out, size_t *out_len,
	       char *err, size_t err_size);

/* An output written to a temporary file in its folder's staging folder. */
struct staged_file {
	const char *target;  /* as named by the user, kept by reference */
	char path[PATH_MAX]; /* the file replaced: target, or where its link leads */
	char temp[PATH_MAX]; /* "" once committed or discarded */
	int stage;	     /* its staging folder (files.c) */
};

/* Creates the temporary file for target (DIR/.rtcl-stage-HOST-PID/
 * new-NAME-XXXXXX.EXT, the extension kept) and returns its descriptor, open
 * for writing; or -1 with one message in err. An interrupt from now on
 * removes it. */
int files_stage(struct staged_file *file, const char *target, char *err, size_t err_size);

/* Replaces every target by its staged file, or none: inside one
 * interrupt_hold() (an interrupt waits until it is done), it checks that each
 * target is still a regular file, keeps each old target under a second name
 * in the staging folder, renames the new files in, and removes the old ones;
 * a rename that fails puts every old file back. An entry with nothing
 * staged (temp "") is passed over. Returns 0, or -1 with one message in err
 * (the staged files are discarded either way). */
int files_commit(struct staged_file *files, int count, char *err, size_t err_size);

/* For tests (base/test_hooks.h, RTCL_TEST_FAIL_RENAME): the nth rename of a new file
 * over its target in a commit (from 1) fails with EIO; 0: none does. */
void files_inject_rename_failure(int nth);

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
int files_write(const char *path, files_fill fill, const void *context, char *err, size_t err_size);

/* The part of path after the last slash. */
const char *files_base_name(const char *path);

/* The extension of path's base name with its dot, or "" when it has none (a
 * leading dot starts a hidden file's name, not an extension). */
const char *files_extension(const char *path);

/* Checks before any work what writing path will need: its directory exists
 * and a file can be created there, its name is not too long, and an existing
 * path is a regular file that the user could overwrite and may replace (not
 * another user's in a sticky directory); a symbolic link is checked where it
 * leads, and one that leads nowhere is refused. Returns 0, or -1 with one
 * message in err. */
int files_check_writable(const char *path, char *err, size_t err_size);

#endif
