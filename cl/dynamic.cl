/* dynamic: persistent work-groups fetch chunks of the work-group's shape from a
 * global counter, in row-major chunk order, until the image is done. Work-item
 * (0,0) takes the next chunk with atomic_inc and shares it through __local
 * memory; the loop condition depends only on that shared value, so it is
 * uniform across the group and every work-item reaches every barrier. The
 * condition stands at the loop's head: PoCL 3.1 mis-compiled an earlier
 * version that left the loop from the middle of its body, after the barriers
 * (with flop counting on it wrote past the image at 61x47, and it hung with
 * POCL_WORK_GROUP_METHOD=loops). The host resets
 * the counter before every launch. */
__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global uint *chunk_counter, __global ulong *counts,
		     __global uint *write_counts)
{
	__local uint next_chunk;
	struct tracer tr;
	int chunk_w = get_local_size(0);
	int chunk_h = get_local_size(1);
	bool first_item = get_local_id(0) == 0 && get_local_id(1) == 0;

	tracer_init(&tr, load_scene(scene_global, scene_local), counts);
	uint chunks_x = (tr.scene->width + chunk_w - 1) / chunk_w;
	uint chunks = chunks_x * ((tr.scene->height + chunk_h - 1) / chunk_h);

	if (first_item)
		next_chunk = atomic_inc(chunk_counter);
	barrier(CLK_LOCAL_MEM_FENCE);
	uint chunk = next_chunk;
	while (chunk < chunks) {
		int x = (chunk % chunks_x) * chunk_w + get_local_id(0);
		int y = (chunk / chunks_x) * chunk_h + get_local_id(1);
		if (x < tr.scene->width && y < tr.scene->height)
			render_pixel(&tr, image, write_counts, x, y);
		/* Everyone has read next_chunk before it is replaced. */
		barrier(CLK_LOCAL_MEM_FENCE);
		if (first_item)
			next_chunk = atomic_inc(chunk_counter);
		barrier(CLK_LOCAL_MEM_FENCE);
		chunk = next_chunk;
	}
	store_counts(&tr, counts, get_global_id(1) * get_global_size(0) + get_global_id(0));
}
