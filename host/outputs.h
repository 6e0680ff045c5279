/* The files a run writes: the image, and with the options that ask for them
 * the work map, the --flops counts and their sidecar, and the --stats
 * document. All of them are checked before any work and written all or
 * none. */
#ifndef RTCL_OUTPUTS_H
#define RTCL_OUTPUTS_H

#include <stddef.h>

#include "stats.h"

/* Checks that every output can be written, before any work starts. Returns
 * 0, or -1 with one message in err. */
int outputs_check(const struct options *opt, char *err, size_t err_size);

/* Writes every output of the run, or none of them: a failure removes what
 * this run already wrote. Returns 0, or -1 with one message in err. */
int outputs_write(const struct run *run, char *err, size_t err_size);

/* Removes every output of this run (after an interrupt while writing). */
void outputs_remove(const struct options *opt);

#endif
