/* dynamic: persistent work-groups fetch chunks of the work-group's shape from a
 * global counter, in row-major chunk order, until the image is done. Work-item
 * (0,0) takes the next chunk with atomic_inc and shares it through __local
 * memory; the loop condition depends only on that shared value, so it is
 * uniform across the group and every work-item reaches every barrier. The
 * condition stands at the loop's head: PoCL 3.1 mis-compiled an earlier
 * version that left the loop from the middle of its body, after the barriers
 * (with flop counting on it wrote past the image at 61x47, and it hung with
 * POCL_WORK_GROUP_METHOD=loops). The host resets next_chunk_counter, the
 * number of the next chunk to hand out, to 0 before every launch; it is the
 * work counter's word RT_COUNTER_NEXT, which the host also reads for the
 * progress line (the chunks handed out). */
__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global long *sums,
		     __global uint *next_chunk_counter,
		     __global ulong *counts, __global uint *probe, struct rt_piece piece)
{
	__local uint group_chunk; /* the chunk item (0,0) took for the group */
	struct tracer tr;
	bool first_item = get_local_id(0) == 0 && get_local_id(1) == 0;

	tracer_init_counts(&tr, load_scene(scene_global, scene_local), counts);
	struct chunk_grid grid = chunk_grid(&piece);
	uint chunks = chunk_count(&grid);

	if (first_item)
		group_chunk = atomic_inc(next_chunk_counter);
	barrier(CLK_LOCAL_MEM_FENCE);
	uint chunk = group_chunk;
	while (chunk < chunks) {
		render_pixel_if_inside(&tr, &piece, image, sums, probe,
			numbered_chunk_pixel(&grid, chunk, get_local_id(0), get_local_id(1)));
		/* Everyone has read group_chunk before it is replaced. */
		barrier(CLK_LOCAL_MEM_FENCE);
		if (first_item)
			group_chunk = atomic_inc(next_chunk_counter);
		barrier(CLK_LOCAL_MEM_FENCE);
		chunk = group_chunk;
	}
	store_counts(&tr, global_item());
}
