/* naive: one work-item per pixel over a 2D NDRange whose global size is the
 * piece's rectangle rounded up to whole work-groups; work-items outside it
 * only help copy the scene. Nothing is handed out at run time: work_counter
 * only counts the groups done for the progress line. */
__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global long *sums,
		     __global uint *work_counter, __global ulong *counts,
		     __global uint *probe, struct rt_piece piece)
{
	struct tracer tr;

	tracer_init_counts(&tr, load_scene(scene_global, scene_local), counts);
	render_pixel_if_inside(&tr, &piece, image, sums, probe,
		(int2)(piece.x0 + (int)get_global_id(0), piece.y0 + (int)get_global_id(1)));
	progress_chunk_done(work_counter, get_local_size(0) * get_local_size(1));
	store_counts(&tr, global_item());
}
