/* The files a run writes: the image (or an animation's frames), and with the
 * options that ask for them the work map, the --flops counts and their
 * sidecar, the --stats document, and RTCL_DUMP_BINARY's program. They are
 * checked before any work, staged and then renamed over their targets
 * together (files.h), so that a failure or an interrupt leaves the previous
 * files untouched or every new one in place. */
#ifndef RTCL_OUTPUTS_H
#define RTCL_OUTPUTS_H

#include <stddef.h>

#include "report/stats.h"

/* outputs_check's result when two outputs name the same file, or an output
 * names a file the scene was read from (a usage error). */
#define OUTPUTS_CLASH (-2)

/* Checks, before any work and in every mode (one image, --frames, --mpi),
 * that the outputs name distinct files, that none is a file the scene was
 * read from (scene->inputs, compared by identity), and that each can be
 * written. Returns 0, OUTPUTS_CLASH, or -1 with one message in err. */
int outputs_check(const struct options *opt, const struct scene *scene, char *err, size_t err_size);

/* Whether two paths name one file (through links and "./"). */
int outputs_same_file(const char *a, const char *b);

/* Writes every output of the run, or none of them. Returns 0, or -1 with one
 * message in err. */
int outputs_write(const struct run *run, char *err, size_t err_size);

#endif
