/* rays: rtcl's intersection (intersect_scene, through the BVH with RTCL_BVH)
 * over rays given by the host, one work-item per ray: the kernel of
 * rtcl-rays (host/cmd/rays.c), the instrument that traces the same rays as a
 * peer's traversal (docs/bvh.md, "Incoherent rays against TinyBVH"). It is not
 * a renderer: no pixel, no shading. Ray i is rays[2i] = (origin, t_max),
 * rays[2i + 1] = (direction, 0); with any_hit (shadow rays) the traversal
 * stops at the first hit with 0 < t < t_max. hits[i] is the hit's t (0: none)
 * and the triangle's index as a float's bits (-1: none). With
 * RTCL_COUNT_FLOPS (rtcl-rays --counts) each work-item stores its counts
 * (RT_ITEM_COUNTS words: flops, node and leaf visits, primitive tests) in
 * counts[RT_ITEM_COUNTS * i]. */
__kernel void trace_rays(__global const uint4 *scene_global, __local uint4 *scene_local,
			 __global const float4 *rays, __global float2 *hits, uint count,
			 int any_hit, __global ulong *counts)
{
	struct tracer tr;
	uint i = get_global_id(0);

	tracer_init(&tr, load_scene(scene_global, scene_local), counts, 0);
	if (i >= count)
		return;
	float4 o = rays[2 * (size_t)i], d = rays[2 * (size_t)i + 1];
	struct hit h = intersect_scene(&tr, o.xyz, d.xyz, o.w, any_hit != 0);
	hits[i] = (float2)(h.t, as_float(h.triangle));
	COUNT_RAY(&tr);
	store_counts(&tr, i);
}
