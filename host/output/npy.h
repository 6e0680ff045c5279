/* Arrays of uint64 counts as .npy files (NPY format 1.0, little-endian),
 * which numpy.load reads directly: the --flops counts and --work-map
 * FILE.npy. */
#ifndef RTCL_NPY_H
#define RTCL_NPY_H

#include <stddef.h>
#include <stdint.h>

struct staged_file;

/* Stages counts[rows * cols], row-major, shape (rows, cols), for the
 * caller's commit (base/files.h). Returns 0, or -1 with one message in err. */
int npy_stage(struct staged_file *staged, const char *path, const uint64_t *counts, size_t rows,
	      size_t cols, char *err, size_t err_size);

#endif
