#include "output/npy.h"

#include <stdio.h>
#include <string.h>

#include "base/files.h"

struct npy_array {
	const void *data;
	const char *descr; /* '<u8' or '<u4' */
	size_t item_size;
	size_t rows, cols, depth; /* depth 0: a 2-D array */
};

/* NPY format 1.0: magic, version, header length, a Python dict literal padded
 * with spaces to a multiple of 64 bytes and ended by a newline, then the data
 * (little-endian, as on every platform rtcl runs on). */
static int fill_npy(FILE *file, const void *context)
{
	const struct npy_array *a = context;
	char header[256], shape[96];
	if (a->depth)
		snprintf(shape, sizeof(shape), "(%zu, %zu, %zu)", a->rows, a->cols, a->depth);
	else
		snprintf(shape, sizeof(shape), "(%zu, %zu)", a->rows, a->cols);
	int length = snprintf(header, sizeof(header),
			      "{'descr': '%s', 'fortran_order': False, 'shape': %s, }", a->descr,
			      shape);
	int padded = (10 + length + 1 + 63) / 64 * 64 - 10;

	memset(header + length, ' ', (size_t)(padded - length - 1));
	header[padded - 1] = '\n';
	unsigned char preamble[10] = {0x93,
				      'N',
				      'U',
				      'M',
				      'P',
				      'Y',
				      1,
				      0,
				      (unsigned char)(padded & 0xff),
				      (unsigned char)(padded >> 8)};
	if (fwrite(preamble, 1, sizeof(preamble), file) != sizeof(preamble) ||
	    fwrite(header, 1, (size_t)padded, file) != (size_t)padded)
		return -1;
	size_t n = a->rows * a->cols * (a->depth ? a->depth : 1);
	return fwrite(a->data, a->item_size, n, file) == n ? 0 : -1;
}

int npy_stage(struct staged_file *staged, const char *path, const uint64_t *counts, size_t rows,
	      size_t cols, char *err, size_t err_size)
{
	struct npy_array array = {counts, "<u8", sizeof(uint64_t), rows, cols, 0};

	return files_stage_with(staged, path, fill_npy, &array, err, err_size);
}

int npy_stage_u32(struct staged_file *staged, const char *path, const uint32_t *words,
		  size_t rows, size_t cols, size_t depth, char *err, size_t err_size)
{
	struct npy_array array = {words, "<u4", sizeof(uint32_t), rows, cols, depth};

	return files_stage_with(staged, path, fill_npy, &array, err, err_size);
}
