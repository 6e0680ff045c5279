#include "base/test_hooks.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

int hook_binary_bvh(void)
{
	const char *value = getenv("RTCL_TEST_BVH2");

	return value && strcmp(value, "1") == 0;
}

int hook_device_fault(void)
{
	const char *fault = getenv("RTCL_TEST_DEVICE_FAULT");

	return fault && strcmp(fault, "1") == 0;
}

void hook_cache_write_delay(void)
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

void hook_piece_delay(int device, double piece_ms)
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

int hook_piece_fault(int device, int nth_piece)
{
	long k, n;

	return env_pair("RTCL_TEST_FAIL_DEVICE", &k, &n) == 0 && k == device && n == nth_piece;
}

int hook_rank_dies(int rank, int taken, int none_left)
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

int hook_count_writes(void)
{
	return env_is_one("RTCL_TEST_CHECK_WRITES");
}

int hook_devices_as_gpus(void)
{
	return env_is_one("RTCL_TEST_AS_GPUS");
}

void hook_sums_delay(void)
{
	const char *value = getenv("RTCL_TEST_SLOW_SUMS");
	long ms = value ? strtol(value, NULL, 10) : 0;

	if (ms > 0)
		nanosleep(&(struct timespec){ms / 1000, ms % 1000 * 1000000L}, NULL);
}

const char *hook_oidn_filter(void)
{
	const char *name = getenv("RTCL_TEST_OIDN_FILTER");

	return name && *name ? name : NULL;
}

int hook_double_band(void)
{
	return env_is_one("RTCL_TEST_DOUBLE_BAND");
}

int hook_rename_fault(void)
{
	const char *value = getenv("RTCL_TEST_FAIL_RENAME");
	char *end;
	long n;

	if (!value)
		return 0;
	n = strtol(value, &end, 10);
	return end != value && *end == '\0' && n > 0 && n < 1000000 ? (int)n : 0;
}

int hook_pass_samples(void)
{
	const char *value = getenv("RTCL_TEST_PASS_SAMPLES");
	char *end;
	long n;

	if (!value)
		return 0;
	n = strtol(value, &end, 10);
	return end != value && *end == '\0' && n > 0 && n < 1000000 ? (int)n : 0;
}

void hook_commit_delay(void)
{
	const char *value = getenv("RTCL_TEST_COMMIT_DELAY");
	long ms = value ? strtol(value, NULL, 10) : 0;

	if (ms > 0) {
		struct timespec wait = {(time_t)(ms / 1000), (ms % 1000) * 1000000L};
		nanosleep(&wait, NULL);
	}
}
