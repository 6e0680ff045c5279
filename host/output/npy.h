/* Arrays as .npy files (NPY format 1.0, little-endian), which numpy.load
 * reads directly: the --flops counts, --work-map FILE.npy and
 * --schedule-map FILE.npy. */
#ifndef RTCL_NPY_H
#define RTCL_NPY_H

#include <stddef.h>
#include <stdint.h>

struct staged_file;

/* Stages counts[rows * cols] (uint64), row-major, shape (rows, cols), for the
 * caller's commit (base/files.h). Returns 0, or -1 with one message in err. */
int npy_stage(struct staged_file *staged, const char *path, const uint64_t *counts, size_t rows,
	      size_t cols, char *err, size_t err_size);

/* Stages words[rows * cols * depth] (uint32), row-major, shape (rows, cols,
 * depth). Returns 0, or -1 with one message in err. */
int npy_stage_u32(struct staged_file *staged, const char *path, const uint32_t *words,
		  size_t rows, size_t cols, size_t depth, char *err, size_t err_size);

#endif
