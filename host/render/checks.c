#include "render/checks.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render/launch.h"

int checks_create_image(struct device *dev, const struct render_settings *s,
			struct guarded_image *g, char *err, size_t err_size)
{
	size_t image_bytes = image_float_bytes(s->width, s->height);
	cl_int status;

	g->guard_bytes = 0;
	if (s->check_writes)
		g->guard_bytes = dev->mem_base_addr_align > 4096 ? dev->mem_base_addr_align : 4096;
	g->parent = device_create_buffer(dev, CL_MEM_READ_WRITE, image_bytes + 2 * g->guard_bytes,
					 NULL, "image", err, err_size);
	if (!g->parent)
		return -1;
	cl_buffer_region region = {g->guard_bytes, image_bytes};
	g->image = clCreateSubBuffer(g->parent, CL_MEM_READ_WRITE, CL_BUFFER_CREATE_TYPE_REGION,
				     &region, &status);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clCreateSubBuffer for the image failed: %s",
			 cl_error_name(status));
		return -1;
	}
	return 0;
}

void checks_release_image(struct guarded_image *g)
{
	if (g->image)
		clReleaseMemObject(g->image);
	if (g->parent)
		clReleaseMemObject(g->parent);
	g->image = g->parent = NULL;
}

cl_mem checks_create_write_counts(struct device *dev, const struct render_settings *s, char *err,
				  size_t err_size)
{
	size_t bytes = s->check_writes ? (size_t)s->width * s->height * sizeof(cl_uint)
				       : UNUSED_BUFFER_BYTES;

	return device_create_buffer(dev, CL_MEM_READ_WRITE, bytes, NULL, "write counts", err,
				    err_size);
}

cl_int checks_poison(struct device *dev, const struct render_settings *s,
		     const struct guarded_image *g, cl_mem write_counts)
{
	size_t pixels = (size_t)s->width * s->height;
	cl_uint zero = 0, poison = POISON_WORD;
	cl_int status;

	if (!s->check_writes)
		return CL_SUCCESS;
	status = clEnqueueFillBuffer(dev->queue, write_counts, &zero, sizeof(zero), 0,
				     pixels * sizeof(cl_uint), 0, NULL, NULL);
	if (status == CL_SUCCESS)
		status = clEnqueueFillBuffer(
			dev->queue, g->parent, &poison, sizeof(poison), 0,
			image_float_bytes(s->width, s->height) + 2 * g->guard_bytes, 0, NULL, NULL);
	return status;
}

cl_int checks_read(struct device *dev, const struct render_settings *s,
		   const struct guarded_image *g, cl_mem write_counts, struct render_result *res)
{
	size_t pixels = (size_t)s->width * s->height;
	cl_uint *guard;
	cl_int status;

	if (!s->check_writes)
		return CL_SUCCESS;
	guard = malloc(g->guard_bytes);
	res->write_counts = malloc(pixels * sizeof(uint32_t));
	if (!guard || !res->write_counts) {
		free(guard);
		return CL_OUT_OF_HOST_MEMORY;
	}
	status = clEnqueueReadBuffer(dev->queue, write_counts, CL_TRUE, 0, pixels * sizeof(cl_uint),
				     res->write_counts, 0, NULL, NULL);
	res->guards_intact = 1;
	for (int side = 0; status == CL_SUCCESS && side < 2; side++) {
		size_t offset = side ? g->guard_bytes + image_float_bytes(s->width, s->height) : 0;
		status = clEnqueueReadBuffer(dev->queue, g->parent, CL_TRUE, offset, g->guard_bytes,
					     guard, 0, NULL, NULL);
		for (size_t i = 0; status == CL_SUCCESS && i < g->guard_bytes / sizeof(cl_uint);
		     i++)
			res->guards_intact &= guard[i] == POISON_WORD;
	}
	free(guard);
	return status;
}

int checks_device_fault_injected(void)
{
	const char *fault = getenv("RTCL_TEST_DEVICE_FAULT");

	return fault && strcmp(fault, "1") == 0;
}

void checks_cache_write_delay(void)
{
	const char *value = getenv("RTCL_TEST_SLOW_CACHE_WRITE");
	long ms = value ? strtol(value, NULL, 10) : 0;

	if (ms > 0)
		nanosleep(&(struct timespec){ms / 1000, ms % 1000 * 1000000L}, NULL);
}

/* Parses "K:N" from the environment variable name; 0 when set and well
 * formed. */
static int env_pair(const char *name, long *k, long *n)
{
	const char *value = getenv(name);
	char *end;

	if (!value)
		return -1;
	*k = strtol(value, &end, 10);
	if (end == value || *end != ':')
		return -1;
	*n = strtol(end + 1, &end, 10);
	return *end == '\0' ? 0 : -1;
}

/* "K:xF" in RTCL_TEST_SLOW_DEVICE: device K and the factor F; 0 when so. */
static int slow_factor(long *k, double *factor)
{
	const char *value = getenv("RTCL_TEST_SLOW_DEVICE");
	char *end;

	if (!value)
		return -1;
	*k = strtol(value, &end, 10);
	if (end == value || end[0] != ':' || end[1] != 'x')
		return -1;
	*factor = strtod(end + 2, &end);
	return *end == '\0' && *factor >= 1 ? 0 : -1;
}

void checks_piece_delay(int device, double piece_ms)
{
	long k, ms;
	double factor, wait_ms = 0;

	if (slow_factor(&k, &factor) == 0)
		wait_ms = k == device ? (factor - 1) * piece_ms : 0;
	else if (env_pair("RTCL_TEST_SLOW_DEVICE", &k, &ms) == 0 && k == device)
		wait_ms = (double)ms;
	if (wait_ms > 0) {
		long long ns = (long long)(wait_ms * 1e6);
		struct timespec wait = {(time_t)(ns / 1000000000), (long)(ns % 1000000000)};
		nanosleep(&wait, NULL);
	}
}

int checks_piece_fault(int device, int nth_piece)
{
	long k, n;

	return env_pair("RTCL_TEST_FAIL_DEVICE", &k, &n) == 0 && k == device && n == nth_piece;
}

int checks_rank_dies(int rank, int taken, int none_left)
{
	long r, n;

	return env_pair("RTCL_TEST_RANK_DIES", &r, &n) == 0 && r == rank && r != 0 &&
	       (none_left ? taken < n : taken == n);
}

static int env_is_one(const char *name)
{
	const char *value = getenv(name);

	return value && strcmp(value, "1") == 0;
}

int checks_count_writes(void)
{
	return env_is_one("RTCL_TEST_CHECK_WRITES");
}

int checks_double_band(void)
{
	return env_is_one("RTCL_TEST_DOUBLE_BAND");
}

int checks_rename_fault(void)
{
	const char *value = getenv("RTCL_TEST_FAIL_RENAME");
	char *end;
	long n;

	if (!value)
		return 0;
	n = strtol(value, &end, 10);
	return end != value && *end == '\0' && n > 0 && n < 1000000 ? (int)n : 0;
}

void checks_commit_delay(void)
{
	const char *value = getenv("RTCL_TEST_COMMIT_DELAY");
	long ms = value ? strtol(value, NULL, 10) : 0;

	if (ms > 0) {
		struct timespec wait = {(time_t)(ms / 1000), (ms % 1000) * 1000000L};
		nanosleep(&wait, NULL);
	}
}
