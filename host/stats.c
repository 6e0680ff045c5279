#include "stats.h"

#include <stdio.h>
#include <string.h>

#include "outfile.h"

void flop_summary_compute(struct flop_summary *s, const uint64_t *item_flops, size_t items,
			  uint64_t rays)
{
	uint64_t max = 0, min = items ? UINT64_MAX : 0, total = 0;

	for (size_t i = 0; i < items; i++) {
		total += item_flops[i];
		max = item_flops[i] > max ? item_flops[i] : max;
		min = item_flops[i] < min ? item_flops[i] : min;
	}
	s->total = total;
	s->mean = items ? (double)total / items : 0;
	s->max = (double)max;
	s->min = (double)min;
	s->parallel_efficiency = max ? s->mean / s->max : 1.0;
	s->rays = rays;
}

static int fill_json(FILE *file, const void *document)
{
	if (json_dumpf(document, file, JSON_INDENT(2) | JSON_REAL_PRECISION(9)) != 0)
		return -1;
	return fputc('\n', file) == EOF ? -1 : 0;
}

int stats_write_json(const char *path, const json_t *document, char *err, size_t err_size)
{
	return outfile_write(path, fill_json, document, err, err_size);
}

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

int stats_write_npy(const char *path, const uint64_t *counts, size_t rows, size_t cols, char *err,
		    size_t err_size)
{
	struct npy_array array = {counts, rows, cols};
	return outfile_write(path, fill_npy, &array, err, err_size);
}
