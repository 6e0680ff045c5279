#include "report/simd.h"

#include <stdlib.h>
#include <string.h>

#include "rtcl_shared.h"

/* One pixel as the model sees it: where in the schedule, and its cost. */
struct lane_step {
	uint32_t group, item, ticket;
	uint32_t warp; /* item / width */
	uint32_t step; /* the item's step: its pixels in ticket order */
	uint64_t flops;
};

static int by_item_then_ticket(const void *pa, const void *pb)
{
	const struct lane_step *a = pa, *b = pb;

	if (a->group != b->group)
		return a->group < b->group ? -1 : 1;
	if (a->item != b->item)
		return a->item < b->item ? -1 : 1;
	return a->ticket < b->ticket ? -1 : a->ticket > b->ticket;
}

static int by_warp_step(const void *pa, const void *pb)
{
	const struct lane_step *a = pa, *b = pb;

	if (a->group != b->group)
		return a->group < b->group ? -1 : 1;
	if (a->warp != b->warp)
		return a->warp < b->warp ? -1 : 1;
	return a->step < b->step ? -1 : a->step > b->step;
}

static int same_warp_step(const struct lane_step *a, const struct lane_step *b)
{
	return a->group == b->group && a->warp == b->warp && a->step == b->step;
}

double simd_measured(const struct render_result *c, int phase)
{
	return c->warp_steps[phase]
		       ? (double)c->lane_steps[phase] / (SIMD_WARP_WIDTH * (double)c->warp_steps[phase])
		       : 1.0;
}

double simd_measured_all(const struct render_result *c)
{
	return simd_measured_first(c, RT_SIMD_TRAVERSAL + 1);
}

double simd_measured_first(const struct render_result *c, int phases)
{
	double steps = 0, warp_steps = 0;

	for (int phase = 0; phase < phases; phase++) {
		steps += (double)c->lane_steps[phase];
		warp_steps += (double)c->warp_steps[phase];
	}
	return warp_steps > 0 ? steps / (SIMD_WARP_WIDTH * warp_steps) : 1.0;
}

int simd_model_compute(const uint32_t *schedule, const uint64_t *pixel_flops, size_t pixels,
		       int width, struct simd_model *out)
{
	struct lane_step *steps = malloc((pixels ? pixels : 1) * sizeof(*steps));
	size_t n = 0;

	memset(out, 0, sizeof(*out));
	out->width = width;
	out->efficiency = 1.0;
	if (!steps)
		return -1;
	for (size_t p = 0; p < pixels; p++) {
		const uint32_t *word = schedule + RT_SCHEDULE_WORDS * p;
		if (word[RT_SCHEDULE_GROUP] == 0xffffffffu)
			continue;
		uint32_t item = word[RT_SCHEDULE_ITEM];
		steps[n++] = (struct lane_step){word[RT_SCHEDULE_GROUP], item,
						word[RT_SCHEDULE_TICKET], item / (uint32_t)width, 0,
						pixel_flops[p]};
	}
	qsort(steps, n, sizeof(*steps), by_item_then_ticket);
	out->items_used = n > 0;
	for (size_t k = 1; k < n; k++) {
		if (steps[k].group == steps[k - 1].group && steps[k].item == steps[k - 1].item)
			steps[k].step = steps[k - 1].step + 1;
		else
			out->items_used++;
	}
	qsort(steps, n, sizeof(*steps), by_warp_step);
	uint64_t cost = 0;
	for (size_t k = 0; k < n; k++) {
		if (k == 0 || !same_warp_step(&steps[k], &steps[k - 1])) {
			out->capacity += (uint64_t)width * cost;
			out->warp_steps++;
			cost = 0;
		}
		cost = steps[k].flops > cost ? steps[k].flops : cost;
		out->flops += steps[k].flops;
	}
	out->capacity += (uint64_t)width * cost;
	if (out->capacity)
		out->efficiency = (double)out->flops / (double)out->capacity;
	free(steps);
	return 0;
}
