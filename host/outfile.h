/* Output files other than images (--stats, --flops): written through a
 * temporary file in the same directory that is renamed over the target once
 * complete, so a failure leaves neither a partial nor a temporary file. */
#ifndef RTCL_OUTFILE_H
#define RTCL_OUTFILE_H

#include <stddef.h>
#include <stdio.h>

/* Fills the file; returns 0, or -1 when a write failed. */
typedef int (*outfile_fill)(FILE *file, const void *context);

/* Checks before any work that path's directory exists and is writable and
 * that path is not something other than a regular file. Returns 0, or -1 with
 * one message in err. */
int outfile_check_writable(const char *path, char *err, size_t err_size);

/* Writes path with fill(file, context). Returns 0, or -1 with one message in
 * err naming path and the reason. */
int outfile_write(const char *path, outfile_fill fill, const void *context, char *err,
		  size_t err_size);

/* Removes a file written earlier in this run, when a later output fails. */
void outfile_remove(const char *path);

#endif
