/* The auxiliary images of --aov and --denoise (docs/RENDERING.md, "Auxiliary
 * images"): each pixel's first-hit albedo, shading normal and depth, averaged
 * over the pixel's samples at the image's sample positions (sample.cl); under
 * the path integrator the albedo and normal of its BSDF (path_surface). A
 * pass of its own after the image, one work-item per pixel looping over the
 * samples in order, whatever kernel rendered the image: the same sums in the
 * same order, so the same bits for every kernel. Built only with RTCL_AOV,
 * after the tracer (it uses primary_ray, intersect_scene, hit_surface and, with
 * RTCL_PATH, path_surface). */
#ifdef RTCL_AOV

/* The unit normal at a hit (RENDERING.md step 2) turned to face the ray:
 * the sphere's or the plane's, a triangle's geometric one, or its shading
 * normal where it is smooth. Written here rather than taken from shading_begin,
 * which skips normals that its image does not use (SHADING_NORMALS). */
static float3 aov_normal(struct tracer *tr, struct hit hit, float3 p, float3 d)
{
	float3 n;

	if (hit.sphere >= 0) {
		RTCL_SCENE_SPACE const struct rt_sphere *s = &tr->spheres[hit.sphere];
		n = (p - s->center.xyz) * s->inv_radius;
	} else if (SCENE_HAS_TRIANGLES && hit.triangle >= 0) {
		uint4 index = tr->triangles[hit.triangle].index;
		n = triangle_normal(tr, index, d);
		if (dot3(n, d) > 0.0f)
			n = -n;
		return triangle_smooth(index) ? triangle_shading_normal(tr, index, hit, n) : n;
	} else {
		n = tr->planes[hit.plane].normal.xyz;
	}
	return dot3(n, d) > 0.0f ? -n : n;
}

/* aov holds 7 floats a pixel in three planes: the albedo (3 x pixels), the
 * normal (3 x pixels), then the depth (pixels), each the mean of samples
 * 0 .. samples_done - 1 of `samples` (fewer than all where an interrupt
 * stopped the image there). A 2D NDRange over the image rounded up to whole
 * work-groups; work-items outside only help copy the scene. A sample that hits nothing adds the background as its albedo and
 * nothing to the normal; the depth is the mean over the samples that hit,
 * 0 where none did. */
__kernel void aov(__global const uint4 *scene_global, __local uint4 *scene_local,
		  __global float *aov, int samples, int samples_done)
{
	struct tracer tr;
	scene_ptr scene = load_scene(scene_global, scene_local);
	int x = (int)get_global_id(0), y = (int)get_global_id(1);

	tracer_init(&tr, scene, NULL, NULL);
	if (x >= scene->width || y >= scene->height)
		return;
	int pixels = scene->width * scene->height, pixel = y * scene->width + x;
	uint n = samples > 1 ? (uint)samples : 1u;
	uint done = clamp(samples_done, 1, (int)n);
	float3 albedo = (float3)(0.0f), normal = (float3)(0.0f);
	float depth = 0.0f;
	int hits = 0;

	for (uint k = 0; k < done; k++) {
		struct ray_job ray;
		struct shading sh;

		tracer_set_sample(&tr, x, y, k, n);
		primary_ray(&tr, x, y, sample_offset(&tr, x, y, k, n), k, n, &ray);
		struct hit hit = intersect_scene(&tr, ray.origin, ray.dir, INFINITY, false);
		if (hit.t == 0.0f) {
			albedo += clamp(scene->background.xyz, 0.0f, 1.0f);
			continue;
		}
		float3 p = ray.origin + hit.t * ray.dir;
		hit_surface(&tr, hit, p, ray.dir, &sh);
#ifdef RTCL_PATH
		/* The path integrator's BSDF at the hit: its colour with the
		 * model's textures, and the normal its normal map gives. */
		struct path_hit h;
		path_surface(&tr, &ray, hit, -1, &h);
		albedo += clamp(h.bsdf.type == RT_BSDF_MAPPED ? sh.base : h.bsdf.color, 0.0f, 1.0f);
		normal += h.n;
#else
		albedo += clamp(sh.base, 0.0f, 1.0f);
		normal += aov_normal(&tr, hit, p, ray.dir);
#endif
		depth += hit.t;
		hits++;
	}
	vstore3(albedo / (float)done, pixel, aov);
	vstore3(normal / (float)done, pixel, aov + 3 * (size_t)pixels);
	aov[6 * (size_t)pixels + pixel] = hits ? depth / (float)hits : 0.0f;
}

#endif
