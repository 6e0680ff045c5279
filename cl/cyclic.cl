/* cyclic: the paper's static interleaving. The image is cut into chunks of the
 * work-group's shape; with GX×GY work-groups, chunk (cx, cy) goes to group
 * (cx mod GX, cy mod GY). With 8×8 work-groups and 25×25 groups on a 2000×2000
 * image, each group traces an 8×8 chunk in every cell of a 10×10 grid: the
 * paper's geometry. The assignment is fixed: work_counter only counts the
 * pixels done for the progress line. */
__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global long *sums,
		     __global uint *work_counter, __global ulong *counts,
		     __global uint *probe, struct rt_piece piece)
{
	struct tracer tr;

	tracer_init_counts(&tr, load_scene(scene_global, scene_local), counts);
	struct chunk_grid grid = chunk_grid(&piece);

	/* The group's chunks in each of its rows of chunks: counted once a row,
	 * so that the chunk loop stays as it is without the progress line (one
	 * atomic a chunk cost 9 % at one sample on the H100, batch 24). */
	uint row_chunks = get_group_id(0) < grid.across
				  ? (grid.across - 1 - get_group_id(0)) / get_num_groups(0) + 1
				  : 0;

	for (uint cy = get_group_id(1); cy < grid.down; cy += get_num_groups(1)) {
		for (uint cx = get_group_id(0); cx < grid.across; cx += get_num_groups(0))
			render_pixel_if_inside(&tr, &piece, image, sums, probe,
				chunk_pixel(&grid, cx, cy, get_local_id(0), get_local_id(1)));
		progress_chunk_done(work_counter, row_chunks * grid.chunk_w * grid.chunk_h);
	}
	store_counts(&tr, global_item());
}
