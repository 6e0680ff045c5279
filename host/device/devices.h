/* Several devices in one process (--devices LIST|all): the list as the
 * user gives it, and the devices it names, opened. */
#ifndef RTCL_DEVICES_H
#define RTCL_DEVICES_H

#include <stddef.h>

#include "device/device.h"

/* The most devices one process renders on. */
#define DEVICES_MAX 16

/* One entry of --devices: platform:device, both indices as --list-devices
 * prints them. */
struct device_spec {
	int platform, device;
};

/* --devices as given: `all`, or a list of entries. */
struct device_list {
	int all; /* every GPU and CPU device of every platform */
	int count;
	struct device_spec specs[DEVICES_MAX];
};

/* Parses "P:D,P:D,..." or "all" into list. Returns 0, or -1 with one message
 * in err (bad syntax, too many entries, an entry given twice). */
int devices_parse(const char *text, struct device_list *list, char *err, size_t err_size);

/* Opens every device the list names, in its order (for `all`: platform by
 * platform, GPUs and CPUs in their index order; with a kind (-t), those of
 * that kind, and each listed device must be of it), into devs[DEVICES_MAX];
 * *count says how many. Returns 0, or -1 with one message in err naming the
 * entry and what exists, with nothing left open. */
int devices_open(const struct device_list *list, enum device_kind kind, struct device *devs,
		 int *count, char *err, size_t err_size);

void devices_close(struct device *devs, int count);

#endif
