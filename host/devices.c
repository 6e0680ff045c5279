#include "devices.h"

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>
#include <string.h>

/* Parses one "P:D" entry of len characters. */
static int parse_entry(const char *text, size_t len, struct device_spec *spec)
{
	char entry[32];
	char *colon, *end;

	if (len == 0 || len >= sizeof(entry))
		return -1;
	memcpy(entry, text, len);
	entry[len] = '\0';
	colon = strchr(entry, ':');
	if (!colon || strspn(entry, "0123456789:") != len || colon == entry || !colon[1] ||
	    strchr(colon + 1, ':') || colon - entry > 4 || strlen(colon + 1) > 4)
		return -1;
	spec->platform = (int)strtol(entry, &end, 10);
	spec->device = (int)strtol(colon + 1, &end, 10);
	return 0;
}

static int find_duplicate(const struct device_list *list, const struct device_spec *spec)
{
	for (int i = 0; i < list->count; i++)
		if (list->specs[i].platform == spec->platform &&
		    list->specs[i].device == spec->device)
			return 1;
	return 0;
}

int devices_parse(const char *text, struct device_list *list, char *err, size_t err_size)
{
	memset(list, 0, sizeof(*list));
	if (strcmp(text, "all") == 0) {
		list->all = 1;
		return 0;
	}
	for (const char *p = text;; p++) {
		size_t len = strcspn(p, ",");
		struct device_spec spec;

		if (parse_entry(p, len, &spec)) {
			snprintf(err, err_size,
				 "--devices: expected all or a list of PLATFORM:DEVICE indices "
				 "(e.g. 1:0,0:0; see --list-devices), got \"%s\"",
				 text);
			return -1;
		}
		if (find_duplicate(list, &spec)) {
			snprintf(err, err_size, "--devices: device %d:%d is listed twice",
				 spec.platform, spec.device);
			return -1;
		}
		if (list->count == DEVICES_MAX) {
			snprintf(err, err_size, "--devices: at most %d devices, got more in \"%s\"",
				 DEVICES_MAX, text);
			return -1;
		}
		list->specs[list->count++] = spec;
		p += len;
		if (*p == '\0')
			return 0;
	}
}

/* The entries `all` stands for: every GPU and CPU device, platform by
 * platform. */
static int expand_all(struct device_list *expanded, char *err, size_t err_size)
{
	int platforms[DEVICES_MAX], devices[DEVICES_MAX];
	int n = device_find_all(platforms, devices, DEVICES_MAX, err, err_size);

	if (n < 0)
		return -1;
	if (n == 0) {
		snprintf(err, err_size,
			 "--devices all: no GPU or CPU device found on any platform");
		return -1;
	}
	memset(expanded, 0, sizeof(*expanded));
	for (int i = 0; i < n; i++)
		expanded->specs[expanded->count++] = (struct device_spec){platforms[i], devices[i]};
	return 0;
}

/* Several devices in one process: PoCL's CPU device starts a worker thread
 * per core and takes every core, which starves the host threads that feed
 * the other devices (and a GPU's driver threads): on the H200 node the GPU
 * ran 4.4 times slower beside PoCL (docs/results/multidevice). Leave one core
 * free by capping PoCL's threads at cores - 1 through POCL_MAX_PTHREAD_COUNT,
 * which PoCL reads once, when its platform is first touched: so before any
 * device is opened, when the device types are not known yet. (PoCL 5 also
 * offers sub-devices by counts, but one must then be made and used in place
 * of the opened device in device.c, and whether its pthread driver then
 * runs fewer threads is not verified here.) Never over the user's own
 * setting; other platforms do not read it. */
static void reserve_a_core(const struct device_list *list)
{
	long cores = sysconf(_SC_NPROCESSORS_ONLN);
	char value[32];

	if ((list->all || list->count > 1) && cores > 1 && !getenv("POCL_MAX_PTHREAD_COUNT")) {
		snprintf(value, sizeof(value), "%ld", cores - 1);
		setenv("POCL_MAX_PTHREAD_COUNT", value, 0);
	}
}

int devices_open(const struct device_list *list, struct device *devs, int *count, char *err,
		 size_t err_size)
{
	struct device_list expanded = *list;
	char why[1024];

	*count = 0;
	reserve_a_core(list);
	if (list->all && expand_all(&expanded, err, err_size))
		return -1;
	for (int i = 0; i < expanded.count; i++) {
		const struct device_spec *spec = &expanded.specs[i];
		if (device_open(&devs[i], spec->platform, spec->device, why, sizeof(why))) {
			snprintf(err, err_size, "--devices %d:%d: %s", spec->platform, spec->device,
				 why);
			devices_close(devs, i);
			return -1;
		}
		*count = i + 1;
	}
	return 0;
}

void devices_close(struct device *devs, int count)
{
	for (int i = 0; i < count; i++)
		device_close(&devs[i]);
}
