#include "output/npy.h"

#include <stdio.h>
#include <string.h>

#include "base/files.h"

struct npy_array {
	const uint64_t *counts;
	size_t rows, cols;
};

/* NPY format 1.0: magic, version, header length, a Python dict literal padded
 * with spaces to a multiple of 64 bytes and ended by a newline, then the data
 * (little-endian, as on every platform rtcl runs on). */
static int fill_npy(FILE *file, const void *context)
{
	const struct npy_array *a = context;
	char header[256];
	int length = snprintf(header, sizeof(header),
			      "{'descr': '<u8', 'fortran_order': False, 'shape': (%zu, %zu), }",
			      a->rows, a->cols);
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
	size_t n = a->rows * a->cols;
	return fwrite(a->counts, sizeof(uint64_t), n, file) == n ? 0 : -1;
}

int npy_stage(struct staged_file *staged, const char *path, const uint64_t *counts, size_t rows,
	      size_t cols, char *err, size_t err_size)
{
	struct npy_array array = {counts, rows, cols};

	return files_stage_with(staged, path, fill_npy, &array, err, err_size);
}
