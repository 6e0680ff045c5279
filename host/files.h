/* Files: reading a whole input file (scenes, kernel sources), and writing
 * outputs other than images (--stats, --flops) through a temporary file in
 * the same directory that is renamed over the target once complete, so a
 * failure leaves neither a partial nor a temporary file. */
#ifndef RTCL_FILES_H
#define RTCL_FILES_H

#include <stddef.h>
#include <stdio.h>

/* Reads the regular file at path, of at most max_bytes, into a malloc'd
 * buffer (with a NUL after its *out_len bytes). `noun` names what the file
 * is in the message for one that is too large ("scene"). Returns 0, or -1
 * with one message in err naming path. A FIFO or device is refused without
 * blocking. */
int files_read(const char *path, const char *noun, size_t max_bytes, char **out,
	       size_t *out_len, char *err, size_t err_size);

/* Fills the file; returns 0, or -1 when a write failed. */
typedef int (*files_fill)(FILE *file, const void *context);

/* Checks before any work that path's directory exists and is writable and
 * that path is not something other than a regular file. Returns 0, or -1 with
 * one message in err. */
int files_check_writable(const char *path, char *err, size_t err_size);

/* Writes path with fill(file, context). Returns 0, or -1 with one message in
 * err naming path and the reason. */
int files_write(const char *path, files_fill fill, const void *context, char *err,
		size_t err_size);

/* Removes a file written earlier in this run, when a later output fails. */
void files_remove(const char *path);

#endif
