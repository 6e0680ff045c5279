#include "job/record.h"

#include <stdio.h>
#include <string.h>

#include "render/render.h"

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

void record_count_flops(struct record *record)
{
	const struct render_result *c = &record->counted;

	flop_summary_compute(&record->flops, c->item_flops, c->item_count, c->total_rays);
	record->flops.node_visits = c->total_node_visits;
	record->flops.leaf_visits = c->total_leaf_visits;
	record->flops.prim_tests = c->total_prim_tests;
}

void record_device(struct record *record, const struct device *dev)
{
	struct device_identity *d = &record->device;

	snprintf(d->name, sizeof(d->name), "%s (%s)", dev->name, dev->platform_name);
	snprintf(d->version, sizeof(d->version), "%s", dev->version);
	snprintf(d->driver, sizeof(d->driver), "%s", dev->driver);
	d->on_device = 1;
	d->compute_units = dev->compute_units;
	d->max_clock_mhz = dev->max_clock_mhz;
}

void record_devices(struct record *record, const struct device *devs, int count)
{
	char *name = record->device.name;
	size_t size = sizeof(record->device.name);

	record_device(record, &devs[0]);
	int n = snprintf(name, size, "%d devices:", count);
	for (int k = 0; k < count && n > 0 && (size_t)n < size; k++)
		n += snprintf(name + n, size - (size_t)n, "%s %s", k ? "," : "", devs[k].name);
}

void record_free(struct record *record)
{
	render_result_free(&record->result);
	render_result_free(&record->counted);
}
