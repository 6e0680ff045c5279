/* naive: one work-item per pixel over a 2D NDRange whose global size is the
 * image rounded up to whole work-groups; work-items outside the image only
 * help copy the scene. */
__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global uint *chunk_counter, __global ulong *counts,
		     __global uint *write_counts)
{
	struct tracer tr;
	int x = get_global_id(0);
	int y = get_global_id(1);

	(void)chunk_counter;
	tracer_init(&tr, load_scene(scene_global, scene_local), counts);
	if (x < tr.scene->width && y < tr.scene->height)
		render_pixel(&tr, image, write_counts, x, y);
	store_counts(&tr, counts, y * get_global_size(0) + x);
}
