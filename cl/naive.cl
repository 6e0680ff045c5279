/* naive: one work-item per pixel over a 2D NDRange whose global size is the
 * image rounded up to whole work-groups; work-items outside the image only
 * help copy the scene. Nothing is handed out at run time, so work_counter is
 * unused. */
__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global uint *work_counter, __global ulong *counts,
		     __global uint *write_counts)
{
	struct tracer tr;

	(void)work_counter;
	tracer_init(&tr, load_scene(scene_global, scene_local), counts);
	render_pixel_if_inside(&tr, image, write_counts,
			       (int2)(get_global_id(0), get_global_id(1)));
	store_counts(&tr, counts, global_item());
}
