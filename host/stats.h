/* The --stats JSON document: every figure rtcl prints, for scripts. */
#ifndef RTCL_STATS_H
#define RTCL_STATS_H

#include <jansson.h>
#include <stddef.h>

/* Writes the JSON document to path through a temporary file in the same
 * directory that is renamed over it, so a failure leaves no partial file.
 * Returns 0, or -1 with one message in err. */
int stats_write(const char *path, const json_t *document, char *err, size_t err_size);

/* Checks before rendering that path's directory exists and is writable.
 * Returns 0, or -1 with one message in err. */
int stats_check_writable(const char *path, char *err, size_t err_size);

#endif
