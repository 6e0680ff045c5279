/* persistent: the "fully dynamic" scheduling the paper thought impossible on a
 * GPU. Persistent work-groups whose work-items each fetch their own work from a
 * global counter, RTCL_BATCH pixels at a time, with no barrier in the loop and
 * no lock: a work-item that drew cheap pixels simply fetches again, while its
 * neighbours are still tracing.
 *
 * Pixels are numbered through the chunks of the work-group's shape, row-major
 * within a chunk and chunks in row-major order, so that work-items fetching at
 * the same time trace neighbouring pixels. Numbers that fall outside the image
 * (partial chunks at the right and bottom edges) are skipped. The host resets
 * next_pixel_counter, the number of the next pixel to hand out, to 0 before
 * every launch; it is the work counter's word RT_COUNTER_NEXT, which the host
 * also reads for the progress line (the pixels handed out).
 *
 * How a work-item fetches (--fetch, docs/wavefront.md):
 *   item (default)       atomic_add of RTCL_BATCH pixels on the global counter;
 *   RTCL_FETCH_GROUP     the work-group takes a block of one fetch per work-item
 *                        from the global counter into __local memory, and its
 *                        work-items take their fetches from that block;
 *   RTCL_FETCH_SUBGROUP  the active lanes of a warp take theirs with one atomic
 *                        (RTCL_WARP_PTX: NVIDIA's activemask, popc and shfl;
 *                        without it each work-item is a sub-group of one).
 *
 * RTCL_REGENERATE (--regenerate, the path integrator; Novák, Havran and
 * Dachsbacher 2010): one loop of path steps instead of a loop over pixels
 * around a loop over a pixel's steps. A work-item whose path ended adds its
 * sample and starts the next path at once, its pixel's next sample or the
 * first of the next pixel it takes, so that the lanes of a warp go on
 * stepping together rather than idle until the warp's longest path ends. */
#ifndef RTCL_BATCH
#define RTCL_BATCH 1
#endif

#ifdef RTCL_FETCH_GROUP
/* The work-group's block, in one 64-bit word so that one atomic reads all of
 * it: the number of its first pixel in the high 32 bits, the fetches drawn
 * from it in the low 32. A block holds `slots` fetches of RTCL_BATCH pixels,
 * one per work-item of the group. */
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable

/* The block lives in global memory, a word per work-group after the work
 * counter's words (the host makes room: singlepass.c,
 * counter_group_bytes), zeroed by nobody: block_init writes it. Not in
 * __local memory: there the 64-bit atomics of work-items that fetch at
 * different moments (--regenerate) lost or repeated a few fetches on an
 * H100 (2-21 pixels of 262,144 untraced or traced twice, batch 105,
 * docs/results/h100-regen/diag-group.sh), as global memory's never did;
 * and a kernel-scope __local variable was shared between work-groups by
 * PoCL 3.1's optimised build. */
static volatile __global ulong *group_block(__global uint *counter)
{
	__global ulong *blocks = (__global ulong *)(counter + RT_COUNTER_WORDS);

	return blocks + get_group_id(1) * get_num_groups(0) + get_group_id(0);
}

static inline ulong block_word(uint first_pixel, uint drawn)
{
	return (ulong)first_pixel << 32 | drawn;
}

/* Takes the group's first block; every work-item must call it (a barrier),
 * before the loop. */
static void block_init(volatile __global ulong *block, __global uint *counter, uint slots)
{
	if (get_local_id(0) == 0 && get_local_id(1) == 0)
		atom_xchg(block, block_word(atomic_add(counter, slots * RTCL_BATCH), 0));
	barrier(CLK_GLOBAL_MEM_FENCE);
}

/* Returns the first pixel number of the work-item's next fetch from the
 * group's block (pixels or more when the image is done). Wait-free: one
 * __local atomic draws a fetch; the work-item that draws the fetch just past
 * the block's last refills it (one global atomic for the next block, which
 * it stores with its own fetch, the block's first, drawn), and a work-item
 * that draws while that refill is under way takes its pixels from the global
 * counter itself, so that no work-item ever waits for another. A block is
 * replaced only by the work-item that drew past its end, after every fetch
 * of it was drawn; a work-item leaves the loop only when the block it drew
 * from, or the global counter, is past the image, so every fetch drawn from
 * a block is traced. */
static uint fetch_pixels(__global uint *counter, volatile __global ulong *block, uint slots,
			 uint pixels)
{
	ulong word = atom_add(block, 1UL);
	uint first = (uint)(word >> 32), drawn = (uint)word;

	if (first >= pixels) /* the image is done */
		return first;
	if (drawn < slots)
		return first + drawn * RTCL_BATCH;
	if (drawn == slots) {
		uint next = atomic_add(counter, slots * RTCL_BATCH);
		atom_xchg(block, block_word(next, 1));
		return next;
	}
	return atomic_add(counter, RTCL_BATCH);
}
#else
#ifdef RTCL_WARP_PTX
/* A warp's lanes through inline PTX (NVIDIA, compute capability 7.0 or
 * more): those executing this call, this lane's number, and a value from
 * lane `from` (shfl.sync waits for every lane of mask). */
static inline uint warp_active(void)
{
	uint mask;

	__asm__ volatile("activemask.b32 %0;" : "=r"(mask));
	return mask;
}

static inline uint warp_lane(void)
{
	uint lane;

	__asm__ volatile("mov.u32 %0, %%laneid;" : "=r"(lane));
	return lane;
}

static inline uint warp_broadcast(uint value, uint from, uint mask)
{
	uint out;

	__asm__ volatile("shfl.sync.idx.b32 %0, %1, %2, 0x1f, %3;"
			 : "=r"(out)
			 : "r"(value), "r"(from), "r"(mask));
	return out;
}
#else
/* Without warp primitives each work-item is a sub-group of one lane. */
static inline uint warp_active(void)
{
	return 1u;
}

static inline uint warp_lane(void)
{
	return 0u;
}

static inline uint warp_broadcast(uint value, uint from, uint mask)
{
	(void)from;
	(void)mask;
	return value;
}
#endif

/* Returns the first pixel number of the work-item's next RTCL_BATCH pixels
 * (pixels or more when the image is done): with RTCL_FETCH_SUBGROUP the
 * lowest of the warp's lanes fetching now takes the fetches of all of them
 * with one atomic and hands each its own, in lane order; else an atomic of
 * the work-item's own. */
static inline uint fetch_pixels(__global uint *counter, volatile __global ulong *block,
				uint slots, uint pixels)
{
	(void)block;
	(void)slots;
	(void)pixels;
#ifdef RTCL_FETCH_SUBGROUP
	uint mask = warp_active(), lane = warp_lane();
	uint leader = popcount((mask & -mask) - 1u);
	uint rank = popcount(mask & ((1u << lane) - 1u));
	uint first = 0;

	if (rank == 0)
		first = atomic_add(counter, popcount(mask) * RTCL_BATCH);
	return warp_broadcast(first, leader, mask) + rank * RTCL_BATCH;
#else
	return atomic_add(counter, RTCL_BATCH);
#endif
}
#endif

#ifdef RTCL_REGENERATE
/* The pixel numbers a work-item fetched and has not begun: [next, end). */
struct pixel_range {
	uint next, end;
};

/* Takes the work-item's next pixel inside the piece into *p (its column and
 * split row), fetching when its range is used up; returns false when the
 * image is done. */
static bool take_pixel(struct pixel_range *r, __global uint *counter,
		       volatile __global ulong *block, uint slots, const struct chunk_grid *grid,
		       const struct rt_piece *piece, int2 *p)
{
	uint chunk_pixels = grid->chunk_w * grid->chunk_h;
	uint pixels = chunk_count(grid) * chunk_pixels;

	for (;;) {
		if (r->next >= r->end) {
			uint first = fetch_pixels(counter, block, slots, pixels);
			if (first >= pixels)
				return false;
			r->next = first;
			r->end = min(first + RTCL_BATCH, pixels);
		}
		uint i = r->next++, within = i % chunk_pixels;
		int2 q = numbered_chunk_pixel(grid, i / chunk_pixels, within % grid->chunk_w,
					      within / grid->chunk_w);
		if (q.x < piece->x0 + piece->width && q.y < piece->y0 + piece->height) {
			*p = (int2)(q.x, rt_piece_row(piece, q.y));
			return true;
		}
	}
}
#endif

__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global long *sums,
		     __global uint *next_pixel_counter,
		     __global ulong *counts, __global uint *probe, struct rt_piece piece)
{
	struct tracer tr;
	uint slots = get_local_size(0) * get_local_size(1);

	tracer_init_counts(&tr, load_scene(scene_global, scene_local), counts);
	struct chunk_grid grid = chunk_grid(&piece);
#ifdef RTCL_FETCH_GROUP
	volatile __global ulong *block = group_block(next_pixel_counter);
	block_init(block, next_pixel_counter, slots);
#else
	volatile __global ulong *block = 0; /* no block */
#endif
#ifdef RTCL_REGENERATE
	struct walk w;
	struct ray_job waiting[RAY_STACK_SIZE];
	struct pixel_trace p;
	struct pixel_range range = {0, 0};
	int2 at;
	bool live = take_pixel(&range, next_pixel_counter, block, slots, &grid, &piece, &at);

	if (live) {
		pixel_begin(&tr, &piece, probe, at.x, at.y, &p);
		pixel_sample_start(&tr, &piece, &p, &w);
	}
	/* One step of the work-item's path a turn; a path that ends makes way
	 * for the next at once. */
	while (live) {
		if (!walk_step(&tr, &w, waiting))
			continue;
		pixel_sample_add(&tr, &piece, sums, &p, &w);
		if (!pixel_samples_left(&piece, &p)) {
			pixel_end(&tr, &piece, image, sums, probe, &p, &w);
			live = take_pixel(&range, next_pixel_counter, block, slots, &grid,
					  &piece, &at);
			if (!live)
				break;
			pixel_begin(&tr, &piece, probe, at.x, at.y, &p);
		}
		pixel_sample_start(&tr, &piece, &p, &w);
	}
#else
	uint chunk_pixels = grid.chunk_w * grid.chunk_h;
	uint pixels = chunk_count(&grid) * chunk_pixels; /* the edge chunks' overhang included */

	for (uint first = fetch_pixels(next_pixel_counter, block, slots, pixels);
	     first < pixels;
	     first = fetch_pixels(next_pixel_counter, block, slots, pixels)) {
		uint end = min(first + RTCL_BATCH, pixels);
		for (uint i = first; i < end; i++) {
			uint within = i % chunk_pixels;
			render_pixel_if_inside(&tr, &piece, image, sums, probe,
					       numbered_chunk_pixel(&grid, i / chunk_pixels,
								    within % grid.chunk_w,
								    within / grid.chunk_w));
		}
	}
#endif
	store_counts(&tr, global_item());
}
