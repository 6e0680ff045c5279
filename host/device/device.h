/* OpenCL device selection: platforms, devices, their limits, and the context
 * and profiling queue rtcl renders with. */
#ifndef RTCL_DEVICE_H
#define RTCL_DEVICE_H

#include <stddef.h>
#include <stdio.h>
#include "device/clerror.h"

struct device {
	cl_platform_id platform;
	cl_device_id id;
	cl_context context;
	cl_command_queue queue; /* in order, with profiling */
	int platform_index, device_index;

	char name[256];
	char platform_name[256];
	char version[256]; /* CL_DEVICE_VERSION */
	char driver[256];  /* CL_DRIVER_VERSION */
	int is_gpu;
	cl_uint compute_units;
	cl_uint max_clock_mhz; /* CL_DEVICE_MAX_CLOCK_FREQUENCY */
	size_t max_work_group_size;
	size_t max_work_item_sizes[3];
	cl_ulong local_mem_size;
	cl_ulong global_mem_size;
	cl_ulong max_alloc_size;
	cl_uint mem_base_addr_align; /* bytes */
	int nv_compiler_options;     /* cl_nv_compiler_options: -cl-nv-* build options */
	int simd_measurable;	     /* NVIDIA, compute capability 7.0 or more: inline PTX
					with activemask (RTCL_SIMD_MEASURE) */
	int host_unified;	     /* CL_DEVICE_HOST_UNIFIED_MEMORY: a CPU device */
	int int64_atomics;	     /* cl_khr_int64_base_atomics (--fetch group) */
};

/* Opens a device. platform_index < 0 and device_index < 0 mean "the first
 * GPU of any platform, else the first device"; a platform alone means its
 * first GPU, else its first device. Returns 0, or -1 with a message in err. */
int device_open(struct device *dev, int platform_index, int device_index, char *err,
		size_t err_size);

/* -t/--type: the kind of device asked for (all: any). */
enum device_kind { DEVICE_KIND_ANY, DEVICE_KIND_GPU, DEVICE_KIND_CPU };

/* device_open for a kind: without -p/-d the first device of that kind (of
 * the platform, when given); with them, the device they name, which must be
 * of that kind. Returns 0, or -1 with one message in err ("no GPU found;
 * --list-devices shows what there is"). */
int device_open_kind(struct device *dev, int platform_index, int device_index,
		     enum device_kind kind, char *err, size_t err_size);

void device_close(struct device *dev);

/* Checks that a buffer of `bytes` fits the device (one allocation of at most
 * CL_DEVICE_MAX_MEM_ALLOC_SIZE) before asking for it; `what` names it in the
 * message. Returns 0, or -1 with one message in err. */
int device_check_fits(const struct device *dev, const char *what, double bytes, char *err,
		      size_t err_size);

/* clCreateBuffer with one message naming `what` on failure; NULL then. On a
 * device that shares the host's memory the buffer is allocated at once
 * (CL_MEM_ALLOC_HOST_PTR), so that too little host memory is this message
 * ("out of host memory for the image ..."), not a failure at the first launch
 * (PoCL 3.1 allocates a plain buffer there, and asserts when it cannot). */
cl_mem device_create_buffer(struct device *dev, cl_mem_flags flags, size_t bytes, void *host,
			    const char *what, char *err, size_t err_size);

/* Host memory the device reads back into at the speed of its link: a buffer
 * of `bytes` made with CL_MEM_ALLOC_HOST_PTR and mapped for good, which
 * NVIDIA's OpenCL pins (page-locked), so that a read into it is one DMA
 * transfer, not a copy through the driver's own staging memory. Returns the
 * mapped memory and sets *mem, or returns NULL (the caller then uses
 * ordinary memory). */
void *device_pinned_alloc(struct device *dev, size_t bytes, cl_mem *mem);

/* Unmaps and releases what device_pinned_alloc gave (nothing for NULL). */
void device_pinned_free(struct device *dev, cl_mem mem, void *p);

/* device_pinned_alloc mapped on a queue of its own (*queue, made here), so
 * that a thread may pin memory while dev->queue renders: the map waits for
 * nothing queued there. NULL (and *queue NULL) where it cannot. Free with
 * device_pinned_free_aside. */
void *device_pinned_alloc_aside(struct device *dev, size_t bytes, cl_mem *mem,
				cl_command_queue *queue);

/* Unmaps on `queue` (dev->queue when NULL) and releases what
 * device_pinned_alloc_aside gave, then the queue. */
void device_pinned_free_aside(struct device *dev, cl_command_queue queue, cl_mem mem, void *p);

/* Finds every GPU and CPU device of every platform, platform by platform
 * in index order, and writes up to max of their indices to platforms[] and
 * devices[]. Returns how many, or -1 with a message in err. */
int device_find_all(int *platforms, int *devices, int max, char *err, size_t err_size);

/* Prints every platform and device in the style of `clinfo -l`, with the
 * indices -p and -d take. Returns 0, or -1 with a message in err. */
int device_list(FILE *out, char *err, size_t err_size);

#endif
