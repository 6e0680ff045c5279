/* serial: one work-item renders every pixel of the piece in row-major order,
 * the paper's serial code run on the device. Launched as a single work-item; it hands out
 * no work: work_counter only counts the rows done for the progress line. */
__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global long *sums,
		     __global uint *work_counter, __global ulong *counts,
		     __global uint *probe, struct rt_piece piece)
{
	struct tracer tr;

	tracer_init_counts(&tr, load_scene(scene_global, scene_local), counts);
	for (int y = piece.y0; y < piece.y0 + piece.height; y++) {
		for (int x = piece.x0; x < piece.x0 + piece.width; x++)
			render_pixel(&tr, &piece, image, sums, probe, x, rt_piece_row(&piece, y));
		progress_chunk_done(work_counter, (uint)piece.width); /* a row of 1x1 chunks */
	}
	store_counts(&tr, global_item());
}
