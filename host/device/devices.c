#include "device/devices.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/quote.h"

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
				 quote_text(text));
			return -1;
		}
		if (find_duplicate(list, &spec)) {
			snprintf(err, err_size, "--devices: device %d:%d is listed twice",
				 spec.platform, spec.device);
			return -1;
		}
		if (list->count == DEVICES_MAX) {
			snprintf(err, err_size, "--devices: at most %d devices, got more in \"%s\"",
				 DEVICES_MAX, quote_text(text));
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

/* Whether dev is of the kind (device_find_all finds only GPUs and CPUs). */
static int is_kind(const struct device *dev, enum device_kind kind)
{
	return kind == DEVICE_KIND_ANY || (kind == DEVICE_KIND_GPU) == (dev->is_gpu != 0);
}

int devices_open(const struct device_list *list, enum device_kind kind, struct device *devs,
		 int *count, char *err, size_t err_size)
{
	struct device_list expanded = *list;
	char why[1024];

	*count = 0;
	if (list->all && expand_all(&expanded, err, err_size))
		return -1;
	for (int i = 0; i < expanded.count; i++) {
		const struct device_spec *spec = &expanded.specs[i];
		struct device *dev = &devs[*count];
		/* `all` with -t keeps the devices of that kind. */
		if (device_open_kind(dev, spec->platform, spec->device,
				     list->all ? DEVICE_KIND_ANY : kind, why, sizeof(why))) {
			snprintf(err, err_size, "--devices %d:%d: %s", spec->platform, spec->device,
				 why);
			devices_close(devs, *count);
			*count = 0;
			return -1;
		}
		if (is_kind(dev, kind))
			(*count)++;
		else
			device_close(dev);
	}
	if (*count > 0)
		return 0;
	snprintf(err, err_size, "--devices all: no %s found; --list-devices shows what there is",
		 kind == DEVICE_KIND_GPU ? "GPU" : "CPU");
	return -1;
}

void devices_close(struct device *devs, int count)
{
	for (int i = 0; i < count; i++)
		device_close(&devs[i]);
}
