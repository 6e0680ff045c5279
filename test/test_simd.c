/* The SIMD efficiency model (report/simd.h, docs/RENDERING.md "SIMD
 * efficiency, modelled") on hand-made schedule maps and flops. */
#include <criterion/criterion.h>

#include <stdlib.h>

#include "report/simd.h"
#include "rtcl_shared.h"

static void set(uint32_t *schedule, size_t p, uint32_t group, uint32_t item, uint32_t ticket)
{
	schedule[RT_SCHEDULE_WORDS * p + RT_SCHEDULE_GROUP] = group;
	schedule[RT_SCHEDULE_WORDS * p + RT_SCHEDULE_ITEM] = item;
	schedule[RT_SCHEDULE_WORDS * p + RT_SCHEDULE_TICKET] = ticket;
}

Test(simd, one_equal_pixel_per_lane_is_full)
{
	uint32_t schedule[64 * RT_SCHEDULE_WORDS];
	uint64_t flops[64];
	struct simd_model m;

	for (uint32_t p = 0; p < 64; p++) {
		set(schedule, p, 0, p, p);
		flops[p] = 10;
	}
	cr_assert_eq(simd_model_compute(schedule, flops, 64, 32, &m), 0);
	cr_assert_float_eq(m.efficiency, 1.0, 1e-12);
	cr_assert_eq(m.warp_steps, 2);
	cr_assert_eq(m.flops, 640);
}

Test(simd, one_lane_of_32_is_a_32nd)
{
	uint32_t schedule[64 * RT_SCHEDULE_WORDS];
	uint64_t flops[64];
	struct simd_model m;

	for (uint32_t p = 0; p < 64; p++) {
		set(schedule, p, 0, 0, p); /* the serial kernel: one item, every pixel */
		flops[p] = 7 + p;
	}
	cr_assert_eq(simd_model_compute(schedule, flops, 64, 32, &m), 0);
	cr_assert_float_eq(m.efficiency, 1.0 / 32, 1e-12);
	cr_assert_eq(m.warp_steps, 64);
	cr_assert_eq(m.items_used, 1);
}

Test(simd, a_warp_step_costs_its_most_expensive_lane)
{
	uint32_t schedule[32 * RT_SCHEDULE_WORDS];
	uint64_t flops[32];
	struct simd_model m;

	for (uint32_t p = 0; p < 32; p++) {
		set(schedule, p, 3, p, p);
		flops[p] = p == 17 ? 100 : 1;
	}
	cr_assert_eq(simd_model_compute(schedule, flops, 32, 32, &m), 0);
	cr_assert_eq(m.capacity, 3200);
	cr_assert_float_eq(m.efficiency, 131.0 / 3200, 1e-12);
}

/* An item's steps are its pixels in ticket order, whatever their place in
 * the image; lanes 0 and 32 are different warps; pixels nobody started are
 * left out. */
Test(simd, steps_follow_the_tickets_and_warps_the_item_numbers)
{
	uint32_t schedule[6 * RT_SCHEDULE_WORDS];
	uint64_t flops[6] = {1, 10, 10, 1, 5, 99};
	struct simd_model m;

	set(schedule, 0, 0, 0, 5); /* item 0's second pixel */
	set(schedule, 1, 0, 0, 2); /* item 0's first */
	set(schedule, 2, 0, 1, 9); /* item 1's second */
	set(schedule, 3, 0, 1, 0); /* item 1's first */
	set(schedule, 4, 0, 32, 1); /* another warp */
	set(schedule, 5, 0xffffffffu, 0xffffffffu, 0xffffffffu);
	cr_assert_eq(simd_model_compute(schedule, flops, 6, 32, &m), 0);
	/* Steps 0 and 1 of warp 0 cost 10 each (10 with 1, then 1 with 10);
	 * warp 1's one step costs 5. */
	cr_assert_eq(m.warp_steps, 3);
	cr_assert_eq(m.items_used, 3);
	cr_assert_eq(m.flops, 27);
	cr_assert_eq(m.capacity, 32 * 25);
}

Test(simd, no_pixel_is_full_efficiency)
{
	uint32_t schedule[RT_SCHEDULE_WORDS] = {0xffffffffu, 0xffffffffu, 0xffffffffu};
	uint64_t flops[1] = {0};
	struct simd_model m;

	cr_assert_eq(simd_model_compute(schedule, flops, 1, 32, &m), 0);
	cr_assert_float_eq(m.efficiency, 1.0, 1e-12);
	cr_assert_eq(m.warp_steps, 0);
	cr_assert_eq(m.items_used, 0);
}
