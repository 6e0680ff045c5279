/* persistent: the "fully dynamic" scheduling the paper thought impossible on a
 * GPU. Persistent work-groups whose work-items each fetch their own work from a
 * global counter with atomic_add, RTCL_BATCH pixels at a time, with no barrier
 * and no lock: a work-item that drew cheap pixels simply fetches again, while
 * its neighbours are still tracing. (Aila & Laine 2009 fetch per warp through
 * a __local batch; OpenCL C 1.2 has no sub-groups, so each work-item fetches
 * for itself.)
 *
 * Pixels are handed out in tiles of the work-group's shape, row-major within a
 * tile and tiles in row-major order, so that work-items fetching at the same
 * time trace neighbouring pixels. Indices that fall outside the image (partial
 * tiles at the right and bottom edges) are skipped. */
#ifndef RTCL_BATCH
#define RTCL_BATCH 1
#endif

__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global uint *chunk_counter, __global ulong *counts,
		     __global uint *write_counts)
{
	struct tracer tr;
	uint tile_w = get_local_size(0);
	uint tile_h = get_local_size(1);
	uint tile_pixels = tile_w * tile_h;

	tracer_init(&tr, load_scene(scene_global, scene_local), counts);
	uint tiles_x = (tr.scene->width + tile_w - 1) / tile_w;
	uint tiles_y = (tr.scene->height + tile_h - 1) / tile_h;
	uint total = tiles_x * tiles_y * tile_pixels;

	for (uint first = atomic_add(chunk_counter, RTCL_BATCH); first < total;
	     first = atomic_add(chunk_counter, RTCL_BATCH)) {
		uint end = min(first + RTCL_BATCH, total);
		for (uint i = first; i < end; i++) {
			uint tile = i / tile_pixels;
			uint within = i % tile_pixels;
			int x = (tile % tiles_x) * tile_w + within % tile_w;
			int y = (tile / tiles_x) * tile_h + within / tile_w;
			if (x < tr.scene->width && y < tr.scene->height)
				render_pixel(&tr, image, write_counts, x, y);
		}
	}
	store_counts(&tr, counts, get_global_id(1) * get_global_size(0) + get_global_id(0));
}
