/* cyclic: the paper's static interleaving. The image is cut into chunks of the
 * work-group's shape; with GX×GY work-groups, chunk (cx, cy) goes to group
 * (cx mod GX, cy mod GY). With 8×8 work-groups and 25×25 groups on a 2000×2000
 * image, each group traces an 8×8 chunk in every cell of a 10×10 grid: the
 * paper's geometry. */
__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global uint *chunk_counter, __global ulong *counts,
		     __global uint *write_counts)
{
	struct tracer tr;
	int chunk_w = get_local_size(0);
	int chunk_h = get_local_size(1);

	(void)chunk_counter;
	tracer_init(&tr, load_scene(scene_global, scene_local), counts);
	int chunks_x = (tr.scene->width + chunk_w - 1) / chunk_w;
	int chunks_y = (tr.scene->height + chunk_h - 1) / chunk_h;

	for (int cy = get_group_id(1); cy < chunks_y; cy += get_num_groups(1)) {
		for (int cx = get_group_id(0); cx < chunks_x; cx += get_num_groups(0)) {
			int x = cx * chunk_w + get_local_id(0);
			int y = cy * chunk_h + get_local_id(1);
			if (x < tr.scene->width && y < tr.scene->height)
				render_pixel(&tr, image, write_counts, x, y);
		}
	}
	store_counts(&tr, counts, get_global_id(1) * get_global_size(0) + get_global_id(0));
}
