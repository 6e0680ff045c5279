/* Intersection (docs/RENDERING.md, trace step 1): the nearest hit of a ray
 * over every sphere, triangle and plane, or any hit for shadow rays. Part of the
 * tracer: built after tracer.cl (host/render/program.c lists the order). */

/* A frame across a ray: unit u and v, perpendicular to its direction d and to
 * each other (Duff et al., "Building an Orthonormal Basis, Revisited", JCGT
 * 2017, branch-free), and the origin's coordinates along them, negated. A
 * sphere's centre c, projected on u and v, gives the offset (x, y) of c from
 * the ray in the plane across it, so the squared distance between c and the
 * ray is x² + y²: 8 arithmetic instructions per sphere instead of 12 for
 * o − c, b = (o − c)·d and |o − c − b d|². Like the closest-point form of
 * Haines et al. ("Precision Improvements for Ray/Sphere Intersection", Ray
 * Tracing Gems, 2019) it takes no difference of squares, whose cancellation
 * puts the hit points of far spheres off the surface by more than epsilon
 * (speckled self-shadowing with the textbook b² − c). d must be unit. */
struct ray_frame {
	float3 u, v;
	float ou, ov; /* −o·u, −o·v */
};

static struct ray_frame ray_frame(struct tracer *tr, float3 o, float3 d)
{
	float sign = copysign(1.0f, d.z);
	float a = -1.0f / (sign + d.z);
	float b = d.x * d.y * a;
	struct ray_frame f;

	f.u = (float3)(1.0f + sign * d.x * d.x * a, sign * b, -sign * d.x);
	f.v = (float3)(b, sign + d.y * d.y * a, -d.y);
	f.ou = -dot3(o, f.u);
	f.ov = -dot3(o, f.v);
	COUNT_FLOPS(tr, 13 + 2 * FLOPS_DOT3); /* by hand: a 2, b 2, u 6, v 3 */
	return f;
}

/* Returns the squared distance between the sphere's centre and the ray, which
 * is more than radius² when the ray misses. The caller counts its
 * FLOPS_SPHERE_GAP. sphere: the centre, with radius² in w. */
static float sphere_gap(float4 sphere, const struct ray_frame *f)
{
	float x = fma(sphere.z, f->u.z, fma(sphere.y, f->u.y, fma(sphere.x, f->u.x, f->ou)));
	float y = fma(sphere.z, f->v.z, fma(sphere.y, f->v.y, fma(sphere.x, f->v.x, f->ov)));

	return fma(y, y, x * x);
}

/* Device sphere i's index in the scene: with a BVH the device's spheres are
 * in leaf order (host/layout/scene_block.c); brute force keeps the scene's order. */
static inline int scene_order(struct tracer *tr, int i)
{
#ifdef RTCL_BVH
	return tr->spheres[i].scene_index;
#else
	return i;
#endif
}

/* Where sphere_gap found the ray within the sphere's radius (gap <= radius²):
 * takes sphere i as the nearest hit if it meets the ray at some 0 < t <
 * *nearest, with t the smallest such root (the far one when the origin is
 * inside). With any_hit, once one hit is found, the rest are not looked at. */
static void sphere_consider(struct tracer *tr, float4 sphere, float gap, float3 o, float3 d, int i,
			    bool any_hit, float *nearest, struct hit *best)
{
	float radius2 = sphere_radius2(sphere);

	if (!(gap <= radius2) || (any_hit && (best->sphere >= 0 || best->triangle >= 0)) ||
	    shadow_skips_sphere(tr, i))
		return;
	float3 oc = o - sphere.xyz;
	float b = dot3(oc, d);
	float far = sqrt(radius2 - gap) - b;
	float t;
	COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_DOT3 + 3);
	if (b > 0.0f) { /* the centre is behind the origin: only the far root can be ahead */
		t = far;
	} else {
		/* The near root as c/far, free of the cancellation in −b − sqrt(disc). */
		float near = (dot3(oc, oc) - radius2) / far;
		COUNT_FLOPS(tr, FLOPS_DOT3 + 2);
		t = near > 0.0f ? near : far;
	}
	/* Equal distances go to the lower index in the scene, and a sphere
	 * beats a triangle, as brute force's order (spheres by index, then
	 * triangles) gives, so that the BVH's order of visits and of the
	 * device's spheres (leaf order, host/layout/scene_block.c) gives the same hits. */
	if (t > 0.0f &&
	    (t < *nearest ||
	     (t == *nearest &&
	      (best->triangle >= 0 ||
	       (best->sphere >= 0 && scene_order(tr, i) < scene_order(tr, best->sphere)))))) {
		*nearest = t;
		best->sphere = i;
		best->triangle = -1;
	}
}

/* Returns t > 0 where the ray meets the plane, or 0 if it does not (parallel
 * or behind). */
static float intersect_plane(struct tracer *tr, RTCL_SCENE_SPACE const struct rt_plane *pl,
			     float3 o, float3 d)
{
	float4 normal = pl->normal; /* the normal and the plane's offset */
	float3 n = normal.xyz;
	float denom = dot3(n, d);

	COUNT_FLOPS(tr, FLOPS_DOT3);
	if (denom == 0.0f)
		return 0.0f;
	float t = (plane_offset(normal) - dot3(n, o)) / denom;
	COUNT_FLOPS(tr, FLOPS_DOT3 + 2);
	return t > 0.0f ? t : 0.0f;
}

/* The ray-triangle test, one triangle by index (Moller and Trumbore, "Fast,
 * Minimum Storage Ray/Triangle Intersection", JGT 1997): true when the ray
 * meets triangle i, from either side, at 0 < t < t_max, with *t and the
 * barycentric coordinates of v1 and v2 in *uv. A ray in the triangle's plane
 * (det 0) misses it. Counts its flops, stage by stage (FLOPS_TRIANGLE_*): the
 * brute-force loop below and an acceleration structure's leaves call it. */
static bool triangle_hit_at(struct tracer *tr, float3 v0, float3 v1, float3 v2, float3 o,
			    float3 d, float t_max, float *t, float2 *uv)
{
	float3 e1 = v1 - v0;
	float3 e2 = v2 - v0;
	float3 p = cross3(d, e2);
	float det = dot3(e1, p);

	COUNT_FLOPS(tr, FLOPS_TRIANGLE_DET);
	if (det == 0.0f)
		return false;
	float inv_det = 1.0f / det;
	float3 s = o - v0;
	float u = dot3(s, p) * inv_det;
	COUNT_FLOPS(tr, FLOPS_TRIANGLE_U);
	if (u < 0.0f || u > 1.0f)
		return false;
	float3 q = cross3(s, e1);
	float v = dot3(d, q) * inv_det;
	COUNT_FLOPS(tr, FLOPS_TRIANGLE_V);
	if (v < 0.0f || u + v > 1.0f)
		return false;
	float hit_t = dot3(e2, q) * inv_det;
	COUNT_FLOPS(tr, FLOPS_TRIANGLE_T);
	if (!(hit_t > 0.0f && hit_t < t_max))
		return false;
	*t = hit_t;
	*uv = (float2)(u, v);
	return true;
}

/* triangle_hit_at with triangle i's vertices. */
static inline bool triangle_hit(struct tracer *tr, int i, float3 o, float3 d, float t_max,
				float *t, float2 *uv)
{
	uint4 index = tr->triangles[i].index;

	return triangle_hit_at(tr, tr->vertices[index.x].position.xyz,
			       tr->vertices[index.y].position.xyz,
			       tr->vertices[index.z].position.xyz, o, d, t_max, t, uv);
}

/* Every triangle in turn (--accel none): takes the nearest hit below
 * *nearest into *best, or with any_hit the first. */
static void triangles_brute_force(struct tracer *tr, float3 o, float3 d, bool any_hit,
				  float *nearest, struct hit *best)
{
	for (int i = 0; i < tr->scene->triangle_count; i++) {
		float t;
		float2 uv;

		if (shadow_skips_triangle(tr, i) || !triangle_hit(tr, i, o, d, *nearest, &t, &uv) ||
		    triangle_cut_out(tr, i, uv))
			continue;
		*nearest = t;
		best->sphere = -1;
		best->triangle = i;
		best->u = uv.x;
		best->v = uv.y;
		if (any_hit)
			return;
	}
}

#ifdef RTCL_BVH
/* Triangle i met in a BVH leaf, in whatever order the traversal reaches it:
 * takes it as the nearest hit by the rule brute force's order gives
 * (triangles_brute_force after the spheres, each replacing the hit only when
 * strictly nearer), so that the image is the same: an equal distance goes to
 * a sphere, else to the lower triangle index; a triangle cut out there is
 * not taken (asked only of a hit that would be). With any_hit, once one hit
 * is found, the rest are not looked at. */
static void triangle_take(struct tracer *tr, int i, float t, float2 uv, float *nearest,
			  struct hit *best)
{
	if ((t < *nearest || (t == *nearest && best->sphere < 0 && i < best->triangle)) &&
	    !shadow_skips_triangle(tr, i) && !triangle_cut_out(tr, i, uv)) {
		*nearest = t;
		best->sphere = -1;
		best->triangle = i;
		best->u = uv.x;
		best->v = uv.y;
	}
}

static void triangle_consider(struct tracer *tr, int i, float3 o, float3 d, bool any_hit,
			      float *nearest, struct hit *best)
{
	float t;
	float2 uv;

	if (any_hit && (best->sphere >= 0 || best->triangle >= 0))
		return;
	/* No bound here: the tie needs t == *nearest, which the test's
	 * strict t < t_max would drop. */
	if (triangle_hit(tr, i, o, d, INFINITY, &t, &uv))
		triangle_take(tr, i, t, uv, nearest, best);
}

/* triangle_consider for leaf triangle k, its vertices inline. */
static void leaf_triangle_consider(struct tracer *tr, int k, float3 o, float3 d, bool any_hit,
				   float *nearest, struct hit *best)
{
	float t;
	float2 uv;
	float4 v0 = tr->leaf_triangles[k].v0;

	if (any_hit && (best->sphere >= 0 || best->triangle >= 0))
		return;
	if (triangle_hit_at(tr, v0.xyz, tr->leaf_triangles[k].v1.xyz,
			    tr->leaf_triangles[k].v2.xyz, o, d, INFINITY, &t, &uv))
		triangle_take(tr, as_int(v0.w), t, uv, nearest, best);
}
#endif

#if RT_SPHERE_GROUP != 4
#error "intersect_scene tests spheres four at a time"
#endif

#ifdef RTCL_BVH
/* cl/traverse.cl: the spheres' and triangles' part of intersect_scene through
 * the BVH. */
static void bvh_intersect(struct tracer *tr, const struct ray_frame *frame, float3 o, float3 d,
			  bool any_hit, float *nearest, struct hit *best);
#endif

/* Returns the nearest object on the ray with 0 < t < max_t; hit.t is 0 when
 * there is none. With any_hit, returns the first such object found instead:
 * enough for a shadow ray. The one loop serves both kinds of ray, so that
 * work-items of a SIMD group tracing different kinds still run it together. */
static struct hit intersect_scene(struct tracer *tr, float3 o, float3 d, float max_t, bool any_hit)
{
	struct hit best = {0.0f, -1, -1, -1, 0.0f, 0.0f};
	float nearest = max_t;

	SIMD_STEP(tr, RT_SIMD_INTERSECT);
	/* RT_SPHERE_GROUP spheres at a time, so that when the ray misses them
	 * all, as it mostly does, they cost one branch. */
	struct ray_frame frame = ray_frame(tr, o, d);
#ifdef RTCL_BVH
	bvh_intersect(tr, &frame, o, d, any_hit, &nearest, &best);
#else
	for (int i = 0; i < tr->scene->sphere_slots; i += RT_SPHERE_GROUP) {
		float4 s0 = tr->spheres[i].center; /* one load: the centre and radius² */
		float4 s1 = tr->spheres[i + 1].center;
		float4 s2 = tr->spheres[i + 2].center;
		float4 s3 = tr->spheres[i + 3].center;
		float g0 = sphere_gap(s0, &frame);
		float g1 = sphere_gap(s1, &frame);
		float g2 = sphere_gap(s2, &frame);
		float g3 = sphere_gap(s3, &frame);

		COUNT_FLOPS(tr,
			    FLOPS_SPHERE_GAP * min(RT_SPHERE_GROUP, tr->scene->sphere_count - i));
		if ((g0 <= sphere_radius2(s0)) | (g1 <= sphere_radius2(s1)) |
		    (g2 <= sphere_radius2(s2)) | (g3 <= sphere_radius2(s3))) {
			sphere_consider(tr, s0, g0, o, d, i, any_hit, &nearest, &best);
			sphere_consider(tr, s1, g1, o, d, i + 1, any_hit, &nearest, &best);
			sphere_consider(tr, s2, g2, o, d, i + 2, any_hit, &nearest, &best);
			sphere_consider(tr, s3, g3, o, d, i + 3, any_hit, &nearest, &best);
			if (any_hit && best.sphere >= 0)
				break;
		}
	}
	if (SCENE_HAS_TRIANGLES && !(any_hit && best.sphere >= 0))
		triangles_brute_force(tr, o, d, any_hit, &nearest, &best);
#endif
	for (int i = 0;
	     i < tr->scene->plane_count && !(any_hit && (best.sphere >= 0 || best.triangle >= 0));
	     i++) {
		float t = intersect_plane(tr, &tr->planes[i], o, d);
		if (t > 0.0f && t < nearest) {
			nearest = t;
			best.sphere = -1;
			best.triangle = -1;
			best.plane = i;
			if (any_hit)
				break;
		}
	}
	if (best.sphere >= 0 || best.plane >= 0 || best.triangle >= 0)
		best.t = nearest;
	return best;
}
