/* persistent: the "fully dynamic" scheduling the paper thought impossible on a
 * GPU. Persistent work-groups whose work-items each fetch their own work from a
 * global counter with atomic_add, RTCL_BATCH pixels at a time, with no barrier
 * and no lock: a work-item that drew cheap pixels simply fetches again, while
 * its neighbours are still tracing. (Aila & Laine 2009 fetch per warp through
 * a __local batch; OpenCL C 1.2 has no sub-groups, so each work-item fetches
 * for itself.)
 *
 * Pixels are numbered through the chunks of the work-group's shape, row-major
 * within a chunk and chunks in row-major order, so that work-items fetching at
 * the same time trace neighbouring pixels. Numbers that fall outside the image
 * (partial chunks at the right and bottom edges) are skipped. The host resets
 * next_pixel_counter, the number of the next pixel to hand out, to 0 before
 * every launch; it is the work counter's word RT_COUNTER_NEXT, which the host
 * also reads for the progress line (the pixels handed out). */
#ifndef RTCL_BATCH
#define RTCL_BATCH 1
#endif

__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global long *sums,
		     __global uint *next_pixel_counter,
		     __global ulong *counts, __global uint *probe, struct rt_piece piece)
{
	struct tracer tr;

	tracer_init_counts(&tr, load_scene(scene_global, scene_local), counts);
	struct chunk_grid grid = chunk_grid(&piece);
	uint chunk_pixels = grid.chunk_w * grid.chunk_h;
	uint pixels = chunk_count(&grid) * chunk_pixels; /* the edge chunks' overhang included */

	for (uint first = atomic_add(next_pixel_counter, RTCL_BATCH); first < pixels;
	     first = atomic_add(next_pixel_counter, RTCL_BATCH)) {
		uint end = min(first + RTCL_BATCH, pixels);
		for (uint i = first; i < end; i++) {
			uint within = i % chunk_pixels;
			render_pixel_if_inside(&tr, &piece, image, sums, probe,
					       numbered_chunk_pixel(&grid, i / chunk_pixels,
								    within % grid.chunk_w,
								    within / grid.chunk_w));
		}
	}
	store_counts(&tr, global_item());
}
