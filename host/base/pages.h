#ifndef RTCL_BASE_PAGES_H
#define RTCL_BASE_PAGES_H

#include <stdlib.h>

/* Host memory whose data begin on a page boundary after a header of
 * `header` bytes (at most PAGE_BYTES), for buffers a device reads back into
 * and that also travel with the header in one message: NVIDIA's OpenCL
 * reads back into page-aligned memory at full speed, and slowly into memory
 * 8 bytes past a 16-byte boundary (docs/results/multidevice/README.md,
 * "MPI"). Free with pages_free and the same header. */
#define PAGE_BYTES 4096

static inline char *pages_alloc(size_t header, size_t bytes)
{
	void *base = NULL;

	if (header > PAGE_BYTES || bytes > (size_t)-1 - PAGE_BYTES ||
	    posix_memalign(&base, PAGE_BYTES, PAGE_BYTES + bytes))
		return NULL;
	return (char *)base + PAGE_BYTES - header;
}

static inline void pages_free(char *p, size_t header)
{
	if (p)
		free(p - (PAGE_BYTES - header));
}

/* Maps every page of [p, p + bytes) now by writing a zero into each, so that
 * a timed write into it later pays no first faults. A memset(p, 0, n) right
 * after malloc does not do this: the compiler may merge the two into calloc,
 * which maps nothing (on the 2-core VM, 128 MB of sums then took 166 ms to
 * add into instead of 31). For memory that is zero already, as calloc's. */
static inline void pages_touch(void *p, size_t bytes)
{
	volatile char *v = p;

	for (size_t i = 0; i < bytes; i += PAGE_BYTES)
		v[i] = 0;
	if (bytes)
		v[bytes - 1] = 0;
}

#endif
