#include "schedule/dispenser.h"

#include <stdlib.h>
#include <string.h>

const char *split_name(enum split split)
{
	return split == SPLIT_STATIC ? "static" : split == SPLIT_SAMPLES ? "samples" : "dynamic";
}

int dispenser_static_first(int k, int n, int count)
{
	return (int)((long long)k * count / n);
}

int dispenser_init(struct dispenser *d, int pieces, int devices, enum split split)
{
	memset(d, 0, sizeof(*d));
	d->split = split;
	d->pieces = pieces;
	d->devices = devices;
	d->next_static = malloc((size_t)(devices > 0 ? devices : 1) * sizeof(int));
	if (!d->next_static)
		return -1;
	for (int k = 0; k < devices; k++)
		d->next_static[k] = dispenser_static_first(k, devices, pieces);
	return 0;
}

void dispenser_free(struct dispenser *d)
{
	free(d->next_static);
	d->next_static = NULL;
}

int dispenser_take(struct dispenser *d, int k)
{
	if (d->split != SPLIT_DYNAMIC) {
		int end = dispenser_static_first(k + 1, d->devices, d->pieces);
		return d->next_static[k] < end ? d->next_static[k]++ : -1;
	}
	return d->next < d->pieces ? d->next++ : -1;
}
