#include "device/device.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/interrupt.h"

#define MAX_PLATFORMS 16
#define MAX_DEVICES 64

#define POCL_PLATFORM_NAME "Portable Computing Language"

/* The directory PoCL 3.1 keeps its kernel cache in, as it chooses it:
 * POCL_CACHE_DIR, else $XDG_CACHE_HOME/pocl, else $HOME/.cache/pocl, else
 * /tmp/pocl. *source says where the choice came from, for a message. */
static void pocl_cache_dir(char *dir, size_t size, char *source, size_t source_size)
{
	const char *value;

	if ((value = getenv("POCL_CACHE_DIR"))) {
		snprintf(dir, size, "%s", value);
		snprintf(source, source_size, "from POCL_CACHE_DIR");
	} else if ((value = getenv("XDG_CACHE_HOME"))) {
		snprintf(dir, size, "%s/pocl", value);
		snprintf(source, source_size, "from XDG_CACHE_HOME=%s", value);
	} else if ((value = getenv("HOME"))) {
		snprintf(dir, size, "%s/.cache/pocl", value);
		snprintf(source, source_size, "from HOME=%s", value);
	} else {
		snprintf(dir, size, "/tmp/pocl");
		snprintf(source, source_size, "PoCL's choice when HOME is not set");
	}
}

/* Whether this process could create and write directory `dir`, as
 * `mkdir -p` would: its nearest existing ancestor, or itself, must be a
 * directory it may write. If not, says why in `why`. */
static int can_create_dir(const char *dir, char *why, size_t why_size)
{
	char path[1024], missing[1024] = "";
	struct stat st;

	snprintf(path, sizeof(path), "%s", dir);
	while (stat(path, &st) != 0) {
		char *slash = strrchr(path, '/');
		if (errno != ENOENT || strcmp(path, ".") == 0) {
			snprintf(why, why_size, "%s cannot be read: %s", path, strerror(errno));
			return 0;
		}
		snprintf(missing, sizeof(missing), "%s", path);
		if (!slash)
			snprintf(path, sizeof(path), ".");
		else
			slash[slash == path] = '\0'; /* keep the root's slash */
	}
	if (S_ISDIR(st.st_mode) && access(path, W_OK | X_OK) == 0)
		return 1;
	if (!S_ISDIR(st.st_mode))
		snprintf(why, why_size, "%s is not a directory", path);
	else if (missing[0])
		snprintf(why, why_size, "%s does not exist and %s is not writable", missing, path);
	else
		snprintf(why, why_size, "%s is not writable", path);
	return 0;
}

/* Appends to err why PoCL may have found no device: it reports none when it
 * cannot create its cache directory (without a writable HOME, say). Only
 * when `platform` is PoCL and that directory is out of reach. */
static void explain_pocl_without_devices(cl_platform_id platform, char *err, size_t err_size)
{
	char name[256] = "", dir[1024], source[1024], why[1200];
	size_t used = strlen(err);

	clGetPlatformInfo(platform, CL_PLATFORM_NAME, sizeof(name), name, NULL);
	if (!strstr(name, POCL_PLATFORM_NAME) || used >= err_size)
		return;
	pocl_cache_dir(dir, sizeof(dir), source, sizeof(source));
	if (can_create_dir(dir, why, sizeof(why)))
		return;
	snprintf(err + used, err_size - used,
		 "; PoCL needs a writable cache directory and cannot create %s (%s): %s; set "
		 "POCL_CACHE_DIR to a writable directory, e.g. POCL_CACHE_DIR=$(mktemp -d)",
		 dir, source, why);
}

static int get_platforms(cl_platform_id *platforms, cl_uint *count, char *err, size_t err_size)
{
	cl_int status = clGetPlatformIDs(MAX_PLATFORMS, platforms, count);

	if (status == CL_PLATFORM_NOT_FOUND_KHR || (status == CL_SUCCESS && *count == 0)) {
		unsigned long long mib = interrupt_memory_limit_mib();
		if (mib)
			snprintf(err, err_size,
				 "no OpenCL platform found: rtcl runs with an address-space limit "
				 "of %llu MiB (`ulimit -v`), which may be too little for the OpenCL "
				 "runtime to start: raise or lift it (else install an OpenCL "
				 "driver, e.g. `apt-get install pocl-opencl-icd`, and check "
				 "/etc/OpenCL/vendors)",
				 mib);
		else
			snprintf(err, err_size,
				 "no OpenCL platform found: install an OpenCL driver (e.g. "
				 "`apt-get install pocl-opencl-icd`) and check /etc/OpenCL/vendors");
		return -1;
	}
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clGetPlatformIDs failed: %s", cl_error_name(status));
		return -1;
	}
	if (*count > MAX_PLATFORMS)
		*count = MAX_PLATFORMS;
	return 0;
}

/* Returns the number of devices of the platform (0 when it has none). */
static cl_uint get_devices(cl_platform_id platform, cl_device_type type, cl_device_id *devices)
{
	cl_uint count = 0;

	if (clGetDeviceIDs(platform, type, MAX_DEVICES, devices, &count) != CL_SUCCESS)
		return 0;
	return count > MAX_DEVICES ? MAX_DEVICES : count;
}

/* Returns the index of `device` among all devices of its platform. */
static int index_in_platform(cl_platform_id platform, cl_device_id device)
{
	cl_device_id all[MAX_DEVICES];
	cl_uint count = get_devices(platform, CL_DEVICE_TYPE_ALL, all);

	for (cl_uint i = 0; i < count; i++)
		if (all[i] == device)
			return (int)i;
	return 0;
}

/* "GPU" or "CPU": what -t/--type names. */
static const char *kind_name(enum device_kind kind)
{
	return kind == DEVICE_KIND_GPU ? "GPU" : "CPU";
}

/* Checks that the device -p/-d chose is of the kind -t asks for. */
static int check_kind(const struct device *dev, enum device_kind kind, char *err, size_t err_size)
{
	cl_device_type type = 0;
	char name[256] = "";

	if (kind == DEVICE_KIND_ANY)
		return 0;
	clGetDeviceInfo(dev->id, CL_DEVICE_TYPE, sizeof(type), &type, NULL);
	if ((type & (kind == DEVICE_KIND_GPU ? CL_DEVICE_TYPE_GPU : CL_DEVICE_TYPE_CPU)) != 0)
		return 0;
	clGetDeviceInfo(dev->id, CL_DEVICE_NAME, sizeof(name), name, NULL);
	snprintf(err, err_size,
		 "-t/--type %s: device %d:%d (%s) is not a %s; --list-devices shows what there is",
		 kind == DEVICE_KIND_GPU ? "gpu" : "cpu", dev->platform_index, dev->device_index,
		 name, kind_name(kind));
	return -1;
}

/* Picks the platform and device per device_open_kind's rules. */
static int choose_device(struct device *dev, int platform_index, int device_index,
			 enum device_kind kind, char *err, size_t err_size)
{
	cl_platform_id platforms[MAX_PLATFORMS];
	cl_device_id devices[MAX_DEVICES];
	cl_uint platform_count = 0;

	if (get_platforms(platforms, &platform_count, err, err_size))
		return -1;
	if (platform_index >= (int)platform_count) {
		snprintf(err, err_size,
			 "platform %d does not exist: there %s %u (see --list-devices)",
			 platform_index, platform_count == 1 ? "is" : "are", platform_count);
		return -1;
	}
	if (device_index >= 0) {
		int p = platform_index < 0 ? 0 : platform_index;
		cl_uint count = get_devices(platforms[p], CL_DEVICE_TYPE_ALL, devices);
		if (device_index >= (int)count) {
			snprintf(err, err_size,
				 "device %d does not exist on platform %d: it has %u "
				 "(see --list-devices)",
				 device_index, p, count);
			if (count == 0)
				explain_pocl_without_devices(platforms[p], err, err_size);
			return -1;
		}
		dev->platform = platforms[p];
		dev->id = devices[device_index];
		dev->platform_index = p;
		dev->device_index = device_index;
		return check_kind(dev, kind, err, err_size);
	}

	/* First GPU, else first device, of the given platform or of any; with
	 * a kind, its first device only. */
	cl_device_type types[2] = {CL_DEVICE_TYPE_GPU, CL_DEVICE_TYPE_ALL};
	int type_count = 2;
	if (kind != DEVICE_KIND_ANY) {
		types[0] = kind == DEVICE_KIND_GPU ? CL_DEVICE_TYPE_GPU : CL_DEVICE_TYPE_CPU;
		type_count = 1;
	}
	for (int t = 0; t < type_count; t++) {
		for (cl_uint p = 0; p < platform_count; p++) {
			if (platform_index >= 0 && (int)p != platform_index)
				continue;
			if (get_devices(platforms[p], types[t], devices) > 0) {
				dev->platform = platforms[p];
				dev->id = devices[0];
				dev->platform_index = (int)p;
				dev->device_index = index_in_platform(platforms[p], devices[0]);
				return 0;
			}
		}
	}
	if (kind != DEVICE_KIND_ANY && platform_index >= 0)
		snprintf(err, err_size,
			 "no %s found on platform %d; --list-devices shows what there is",
			 kind_name(kind), platform_index);
	else if (kind != DEVICE_KIND_ANY)
		snprintf(err, err_size, "no %s found; --list-devices shows what there is",
			 kind_name(kind));
	else if (platform_index >= 0)
		snprintf(err, err_size, "platform %d has no devices", platform_index);
	else
		snprintf(err, err_size, "no OpenCL device found on any platform");
	for (cl_uint p = 0; p < platform_count; p++)
		if (platform_index < 0 || (int)p == platform_index)
			explain_pocl_without_devices(platforms[p], err, err_size);
	return -1;
}

static void query_info(struct device *dev)
{
	cl_device_type type = 0;
	cl_uint align_bits = 0;

	clGetPlatformInfo(dev->platform, CL_PLATFORM_NAME, sizeof(dev->platform_name),
			  dev->platform_name, NULL);
	clGetDeviceInfo(dev->id, CL_DEVICE_NAME, sizeof(dev->name), dev->name, NULL);
	clGetDeviceInfo(dev->id, CL_DEVICE_VERSION, sizeof(dev->version), dev->version, NULL);
	clGetDeviceInfo(dev->id, CL_DRIVER_VERSION, sizeof(dev->driver), dev->driver, NULL);
	clGetDeviceInfo(dev->id, CL_DEVICE_TYPE, sizeof(type), &type, NULL);
	dev->is_gpu = (type & CL_DEVICE_TYPE_GPU) != 0;
	clGetDeviceInfo(dev->id, CL_DEVICE_MAX_COMPUTE_UNITS, sizeof(dev->compute_units),
			&dev->compute_units, NULL);
	clGetDeviceInfo(dev->id, CL_DEVICE_MAX_CLOCK_FREQUENCY, sizeof(dev->max_clock_mhz),
			&dev->max_clock_mhz, NULL);
	clGetDeviceInfo(dev->id, CL_DEVICE_MAX_WORK_GROUP_SIZE, sizeof(dev->max_work_group_size),
			&dev->max_work_group_size, NULL);
	clGetDeviceInfo(dev->id, CL_DEVICE_MAX_WORK_ITEM_SIZES, sizeof(dev->max_work_item_sizes),
			dev->max_work_item_sizes, NULL);
	clGetDeviceInfo(dev->id, CL_DEVICE_LOCAL_MEM_SIZE, sizeof(dev->local_mem_size),
			&dev->local_mem_size, NULL);
	clGetDeviceInfo(dev->id, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof(dev->global_mem_size),
			&dev->global_mem_size, NULL);
	clGetDeviceInfo(dev->id, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof(dev->max_alloc_size),
			&dev->max_alloc_size, NULL);
	clGetDeviceInfo(dev->id, CL_DEVICE_MEM_BASE_ADDR_ALIGN, sizeof(align_bits), &align_bits,
			NULL);
	dev->mem_base_addr_align = align_bits / 8 ? align_bits / 8 : 128;
	cl_bool unified = CL_FALSE;
	if (clGetDeviceInfo(dev->id, CL_DEVICE_HOST_UNIFIED_MEMORY, sizeof(unified), &unified,
			    NULL) == CL_SUCCESS)
		dev->host_unified = unified == CL_TRUE;

	size_t size = 0;
	clGetDeviceInfo(dev->id, CL_DEVICE_EXTENSIONS, 0, NULL, &size);
	char *extensions = size ? malloc(size + 1) : NULL;
	if (extensions &&
	    clGetDeviceInfo(dev->id, CL_DEVICE_EXTENSIONS, size, extensions, NULL) == CL_SUCCESS) {
		extensions[size] = '\0';
		dev->nv_compiler_options = strstr(extensions, "cl_nv_compiler_options") != NULL;
		dev->int64_atomics = strstr(extensions, "cl_khr_int64_base_atomics") != NULL;
		/* CL_DEVICE_COMPUTE_CAPABILITY_MAJOR_NV (cl_nv_device_attribute_query). */
		cl_uint major = 0;
		if (strstr(extensions, "cl_nv_device_attribute_query") &&
		    clGetDeviceInfo(dev->id, 0x4000, sizeof(major), &major, NULL) == CL_SUCCESS)
			dev->simd_measurable = major >= 7;
	}
	free(extensions);
}

int device_open(struct device *dev, int platform_index, int device_index, char *err,
		size_t err_size)
{
	return device_open_kind(dev, platform_index, device_index, DEVICE_KIND_ANY, err, err_size);
}

int device_open_kind(struct device *dev, int platform_index, int device_index,
		     enum device_kind kind, char *err, size_t err_size)
{
	cl_int status;

	memset(dev, 0, sizeof(*dev));
	if (choose_device(dev, platform_index, device_index, kind, err, err_size))
		return -1;
	query_info(dev);

	dev->context = clCreateContext(NULL, 1, &dev->id, NULL, NULL, &status);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clCreateContext failed on %s: %s", dev->name,
			 cl_error_name(status));
		return -1;
	}
	dev->queue =
		clCreateCommandQueue(dev->context, dev->id, CL_QUEUE_PROFILING_ENABLE, &status);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clCreateCommandQueue failed on %s: %s", dev->name,
			 cl_error_name(status));
		goto out_release_context;
	}
	return 0;

out_release_context:
	clReleaseContext(dev->context);
	dev->context = NULL;
	return -1;
}

void device_close(struct device *dev)
{
	if (dev->queue)
		clReleaseCommandQueue(dev->queue);
	if (dev->context)
		clReleaseContext(dev->context);
	dev->queue = NULL;
	dev->context = NULL;
}

int device_check_fits(const struct device *dev, const char *what, double bytes, char *err,
		      size_t err_size)
{
	if (bytes > (double)dev->max_alloc_size) {
		snprintf(err, err_size,
			 "%s needs %.0f bytes of device memory, but %s allows at most %llu bytes "
			 "in one buffer (CL_DEVICE_MAX_MEM_ALLOC_SIZE): choose a smaller --size",
			 what, bytes, dev->name, (unsigned long long)dev->max_alloc_size);
		return -1;
	}
	return 0;
}

cl_mem device_create_buffer(struct device *dev, cl_mem_flags flags, size_t bytes, void *host,
			    const char *what, char *err, size_t err_size)
{
	cl_int status;
	cl_mem buffer;

	if (dev->host_unified && !(flags & CL_MEM_USE_HOST_PTR))
		flags |= CL_MEM_ALLOC_HOST_PTR;
	buffer = clCreateBuffer(dev->context, flags, bytes, host, &status);
	if (status == CL_OUT_OF_HOST_MEMORY ||
	    (dev->host_unified && status == CL_MEM_OBJECT_ALLOCATION_FAILURE)) {
		snprintf(err, err_size, "out of host memory for the %s (%zu bytes) on %s", what,
			 bytes, dev->name);
		return NULL;
	}
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clCreateBuffer for the %s (%zu bytes) failed: %s", what,
			 bytes, cl_error_name(status));
		return NULL;
	}
	return buffer;
}

void *device_pinned_alloc(struct device *dev, size_t bytes, cl_mem *mem)
{
	cl_int status;
	void *p;

	*mem = clCreateBuffer(dev->context, CL_MEM_READ_WRITE | CL_MEM_ALLOC_HOST_PTR, bytes, NULL,
			      &status);
	if (status != CL_SUCCESS) {
		*mem = NULL;
		return NULL;
	}
	p = clEnqueueMapBuffer(dev->queue, *mem, CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0, bytes, 0,
			       NULL, NULL, &status);
	if (status != CL_SUCCESS) {
		clReleaseMemObject(*mem);
		*mem = NULL;
		return NULL;
	}
	return p;
}

void device_pinned_free(struct device *dev, cl_mem mem, void *p)
{
	if (!mem)
		return;
	if (p && clEnqueueUnmapMemObject(dev->queue, mem, p, 0, NULL, NULL) == CL_SUCCESS)
		clFinish(dev->queue);
	clReleaseMemObject(mem);
}

void *device_pinned_alloc_aside(struct device *dev, size_t bytes, cl_mem *mem,
				cl_command_queue *queue)
{
	struct device side = *dev;
	cl_int status;

	*mem = NULL;
	*queue = clCreateCommandQueue(dev->context, dev->id, 0, &status);
	if (status != CL_SUCCESS) {
		*queue = NULL;
		return NULL;
	}
	side.queue = *queue;
	void *p = device_pinned_alloc(&side, bytes, mem);
	if (!p) {
		clReleaseCommandQueue(*queue);
		*queue = NULL;
	}
	return p;
}

void device_pinned_free_aside(struct device *dev, cl_command_queue queue, cl_mem mem, void *p)
{
	struct device side = *dev;

	if (queue)
		side.queue = queue;
	device_pinned_free(&side, mem, p);
	if (queue)
		clReleaseCommandQueue(queue);
}

int device_find_all(int *platform_indices, int *device_indices, int max, char *err, size_t err_size)
{
	cl_platform_id platforms[MAX_PLATFORMS];
	cl_uint platform_count = 0;
	int n = 0;

	if (get_platforms(platforms, &platform_count, err, err_size))
		return -1;
	for (cl_uint p = 0; p < platform_count; p++) {
		cl_device_id devices[MAX_DEVICES];
		cl_uint count = get_devices(platforms[p], CL_DEVICE_TYPE_ALL, devices);

		for (cl_uint d = 0; d < count && n < max; d++) {
			cl_device_type type = 0;
			clGetDeviceInfo(devices[d], CL_DEVICE_TYPE, sizeof(type), &type, NULL);
			if (!(type & (CL_DEVICE_TYPE_GPU | CL_DEVICE_TYPE_CPU)))
				continue;
			platform_indices[n] = (int)p;
			device_indices[n++] = (int)d;
		}
	}
	return n;
}

static const char *type_name(cl_device_type type)
{
	if (type & CL_DEVICE_TYPE_GPU)
		return "GPU";
	if (type & CL_DEVICE_TYPE_CPU)
		return "CPU";
	if (type & CL_DEVICE_TYPE_ACCELERATOR)
		return "accelerator";
	return "other";
}

int device_list(FILE *out, char *err, size_t err_size)
{
	cl_platform_id platforms[MAX_PLATFORMS];
	cl_uint platform_count = 0;

	if (get_platforms(platforms, &platform_count, err, err_size))
		return -1;
	for (cl_uint p = 0; p < platform_count; p++) {
		cl_device_id devices[MAX_DEVICES];
		char name[256] = "";
		cl_uint count = get_devices(platforms[p], CL_DEVICE_TYPE_ALL, devices);

		clGetPlatformInfo(platforms[p], CL_PLATFORM_NAME, sizeof(name), name, NULL);
		fprintf(out, "Platform #%u: %s\n", p, name);
		if (count == 0) {
			char none[2048] = "no devices";
			explain_pocl_without_devices(platforms[p], none, sizeof(none));
			fprintf(out, " `-- %s\n", none);
		}
		for (cl_uint d = 0; d < count; d++) {
			cl_device_type type = 0;
			cl_uint units = 0;
			cl_ulong local = 0, global = 0;

			clGetDeviceInfo(devices[d], CL_DEVICE_NAME, sizeof(name), name, NULL);
			clGetDeviceInfo(devices[d], CL_DEVICE_TYPE, sizeof(type), &type, NULL);
			clGetDeviceInfo(devices[d], CL_DEVICE_MAX_COMPUTE_UNITS, sizeof(units),
					&units, NULL);
			clGetDeviceInfo(devices[d], CL_DEVICE_LOCAL_MEM_SIZE, sizeof(local), &local,
					NULL);
			clGetDeviceInfo(devices[d], CL_DEVICE_GLOBAL_MEM_SIZE, sizeof(global),
					&global, NULL);
			fprintf(out,
				" %s-- Device #%u: %s (%s, %u compute units, %llu KiB local, "
				"%llu MiB global)\n",
				d + 1 == count ? "`" : "|", d, name, type_name(type), units,
				(unsigned long long)(local / 1024),
				(unsigned long long)(global / (1024 * 1024)));
		}
	}
	return 0;
}
