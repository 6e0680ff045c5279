/* The tracer: what a pixel is (docs/RENDERING.md), written once and used by
 * every scheduling kernel. OpenCL C 1.2.
 *
 * Read it top to bottom: counting, the scene as the tracer sees it,
 * intersection, shading, the per-ray step (ray_step), the two ways of walking a
 * pixel's ray tree with it (render_pixel's stack walk, trace_one for the
 * wavefront kernel), and last the helpers the scheduling kernels share. It is
 * one file of about 760 lines, over the usual 450, because the host hands the
 * OpenCL compiler exactly rtcl_shared.h, this file and one kernel file
 * (host/render.c, test/test_flops.c): splitting it means changing that list.
 *
 * Build-time options, set by the host (host/render.c):
 *   RTCL_MAX_DEPTH      the scene's max_depth; sizes the ray stack
 *   RTCL_SCENE_IN_LOCAL copy the scene into __local memory per work-group;
 *                       without it the tracer reads it from __global memory
 *   RTCL_COUNT_FLOPS    count floating-point operations and rays per work-item
 *   RTCL_COUNT_WRITES   count writes per pixel (tests only)
 *
 * Contraction into fused multiply-adds is off so that the same source gives the
 * same bits whichever kernel it is inlined into, and so that the flop counts
 * written beside the arithmetic stay true (RENDERING.md: an fma counts 2). The
 * hot arithmetic (dot products, the sphere test) is written with fma() instead:
 * an explicit fma rounds once, the same way on every device and in every
 * kernel, and runs as one instruction where the hardware has one.
 */
#pragma OPENCL FP_CONTRACT OFF

#ifndef RTCL_MAX_DEPTH
#error "RTCL_MAX_DEPTH must be defined by the host"
#endif
#ifdef RTCL_SCENE_IN_LOCAL
#define RTCL_SCENE_SPACE __local
#else
#define RTCL_SCENE_SPACE __global
#endif

/* Depth-first walk of the ray tree: a ray at depth d spawns at most two at
 * depth d+1, one of which is traced next, so at most one ray waits per level
 * 1..max_depth. */
#define RAY_STACK_SIZE (RTCL_MAX_DEPTH > 0 ? RTCL_MAX_DEPTH : 1)

/* Counting (RENDERING.md, "Counting floating-point operations"): each
 * COUNT_FLOPS stands beside the arithmetic it counts. Without
 * RTCL_COUNT_FLOPS it is a no-op. */
#ifdef RTCL_COUNT_FLOPS
#define COUNT_FLOPS(tr, n) ((tr)->flops += (n))
#define COUNT_RAY(tr) ((tr)->rays++)
#else
#define COUNT_FLOPS(tr, n) ((void)0)
#define COUNT_RAY(tr) ((void)0)
#endif

/* What the operations written below cost, by RENDERING.md's rules: +, −, ×,
 * ÷, sqrt, pow, min and max of floats 1 each, a fused multiply-add 2,
 * comparisons and integer work 0. Here also rsqrt 1, like the sqrt it
 * replaces, and a sign flip (unary −) 0. Scalar arithmetic is counted by
 * hand where it is written, one per operator. */
#define FLOPS_FMA 2
/* A 3-vector + or − a 3-vector, or a scalar added to one: 3. */
#define FLOPS_ADD3 3
/* A 3-vector × a scalar, or × a 3-vector component-wise: 3. */
#define FLOPS_MUL3 3
/* dot3: a product and two fmas, 5. */
#define FLOPS_DOT3 (1 + 2 * FLOPS_FMA)
/* normalize3: the squared length, its rsqrt and the scaling, 9. */
#define FLOPS_NORMALIZE3 (FLOPS_DOT3 + 1 + FLOPS_MUL3)
/* sphere_gap: two chains of three fmas, then an fma and a product, 15. */
#define FLOPS_SPHERE_GAP (6 * FLOPS_FMA + FLOPS_FMA + 1)

typedef RTCL_SCENE_SPACE const struct rt_scene *scene_ptr;

/* The scene header's scalars, in the camera vectors' w lanes
 * (rtcl_shared.h says why). */
static inline float scene_half_width(scene_ptr scene)
{
	return scene->eye.w;
}

static inline float scene_half_height(scene_ptr scene)
{
	return scene->forward.w;
}

static inline float scene_epsilon(scene_ptr scene)
{
	return scene->right.w;
}

/* The scene as the tracer sees it, and the work-item's flop counter. */
struct tracer {
	scene_ptr scene;
	RTCL_SCENE_SPACE const struct rt_material *materials;
	RTCL_SCENE_SPACE const struct rt_sphere *spheres;
	RTCL_SCENE_SPACE const struct rt_plane *planes;
	RTCL_SCENE_SPACE const struct rt_light *lights;
	__global ulong *pixel_flops; /* flops spent on each pixel, when counting */
#ifdef RTCL_COUNT_FLOPS
	ulong flops;
	ulong rays; /* primary, secondary and shadow rays traced */
#endif
};

struct ray_job {
	float3 origin;
	float3 dir; /* unit length */
	float weight;
	int depth;
};

struct hit {
	float t;
	int sphere; /* index of the sphere hit, or -1 */
	int plane;  /* index of the plane hit, or -1 */
};

/* Vector helpers, written out so that each operation is what is counted. */
static inline float dot3(float3 a, float3 b)
{
	return fma(a.z, b.z, fma(a.y, b.y, a.x * b.x));
}

/* Counted FLOPS_NORMALIZE3: rsqrt stands for the division by the length. */
static inline float3 normalize3(float3 v)
{
	return v * rsqrt(dot3(v, v));
}

/* x^y for x >= 0, as pow() gives it (0^0 = 1) but through the hardware's
 * base-2 logarithm and exponential, a few instructions instead of pow's
 * careful dozens: the highlight's exponent needs no more than the 8 bits an
 * image keeps. Counted as the one pow it stands for. */
static inline float power(float x, float y)
{
	if (x > 0.0f)
		return native_exp2(y * native_log2(x));
	return y == 0.0f ? 1.0f : 0.0f;
}

static inline float component(float3 v, int axis)
{
	return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}

/* Counts, when counting: per launched work-item (flops, rays), row-major over
 * the global NDRange, then per pixel the flops spent on it. */
static void tracer_init(struct tracer *tr, scene_ptr scene, __global ulong *counts)
{
	RTCL_SCENE_SPACE const uchar *base = (RTCL_SCENE_SPACE const uchar *)scene;

	tr->scene = scene;
	tr->materials =
		(RTCL_SCENE_SPACE const struct rt_material *)(base + scene->material_offset);
	tr->spheres = (RTCL_SCENE_SPACE const struct rt_sphere *)(base + scene->sphere_offset);
	tr->planes = (RTCL_SCENE_SPACE const struct rt_plane *)(base + scene->plane_offset);
	tr->lights = (RTCL_SCENE_SPACE const struct rt_light *)(base + scene->light_offset);
	tr->pixel_flops = counts + 2 * get_global_size(0) * get_global_size(1);
#ifdef RTCL_COUNT_FLOPS
	tr->flops = 0;
	tr->rays = 0;
#endif
}

/* Returns the flops counted so far, 0 when not counting. */
static inline ulong tracer_flops(const struct tracer *tr)
{
#ifdef RTCL_COUNT_FLOPS
	return tr->flops;
#else
	(void)tr;
	return 0;
#endif
}

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

/* Where sphere_gap found the ray within the sphere's radius (gap <= radius²):
 * takes sphere i as the nearest hit if it meets the ray at some 0 < t <
 * *nearest, with t the smallest such root (the far one when the origin is
 * inside). With any_hit, once one hit is found, the rest are not looked at. */
static void sphere_consider(struct tracer *tr, float4 sphere, float gap, float3 o, float3 d, int i,
			    bool any_hit, float *nearest, struct hit *best)
{
	float radius2 = sphere_radius2(sphere);

	if (!(gap <= radius2) || (any_hit && best->sphere >= 0))
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
	if (t > 0.0f && t < *nearest) {
		*nearest = t;
		best->sphere = i;
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

#if RT_SPHERE_GROUP != 4
#error "intersect_scene tests spheres four at a time"
#endif

/* Returns the nearest object on the ray with 0 < t < max_t; hit.t is 0 when
 * there is none. With any_hit, returns the first such object found instead:
 * enough for a shadow ray. The one loop serves both kinds of ray, so that
 * work-items of a SIMD group tracing different kinds still run it together. */
static struct hit intersect_scene(struct tracer *tr, float3 o, float3 d, float max_t, bool any_hit)
{
	struct hit best = {0.0f, -1, -1};
	float nearest = max_t;

	/* RT_SPHERE_GROUP spheres at a time, so that when the ray misses them
	 * all, as it mostly does, they cost one branch. */
	struct ray_frame frame = ray_frame(tr, o, d);
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
	for (int i = 0; i < tr->scene->plane_count && !(any_hit && best.sphere >= 0); i++) {
		float t = intersect_plane(tr, &tr->planes[i], o, d);
		if (t > 0.0f && t < nearest) {
			nearest = t;
			best.sphere = -1;
			best.plane = i;
			if (any_hit)
				break;
		}
	}
	if (best.sphere >= 0 || best.plane >= 0)
		best.t = nearest;
	return best;
}

/* Returns the base colour C at p on the plane: its material colour, or the
 * checker colour on the odd squares. */
static float3 plane_color(struct tracer *tr, RTCL_SCENE_SPACE const struct rt_plane *pl,
			  float3 material_color, float3 p)
{
	if (!pl->has_checker)
		return material_color;
	float4 checker = pl->checker_color; /* the colour and the square size */
	float size = checker_size(checker);
	int square = (int)floor(component(p, pl->checker_s_axis) / size) +
		     (int)floor(component(p, pl->checker_t_axis) / size);
	COUNT_FLOPS(tr, 2);
	return (square & 1) ? checker.xyz : material_color;
}

/* A hit being shaded (RENDERING.md steps 2-4), carried across the shadow rays
 * it casts: the lights are taken one at a time, so that a shadow ray can go
 * through the same intersect_scene call as every other ray. */
struct shading {
	float3 p, n, base;
	bool inside;
	RTCL_SCENE_SPACE const struct rt_material *m;
	float3 color;	      /* the local colour so far, weight not applied */
	float3 shadow_origin; /* p + epsilon·n */
	int next_light;	      /* the light to consider next */
	/* The light whose shadow ray is to be traced: */
	float3 to_light_dir;
	float light_distance;
	float diffuse, specular;
	int light;
};

/* Starts shading the hit of ray: the hit point, the normals, the base colour
 * and the ambient term. */
static void shading_begin(struct tracer *tr, const struct ray_job *ray, struct hit hit,
			  struct shading *sh)
{
	scene_ptr scene = tr->scene;
	float3 normal;

	sh->p = ray->origin + hit.t * ray->dir;
	COUNT_FLOPS(tr, FLOPS_MUL3 + FLOPS_ADD3);
	if (hit.sphere >= 0) {
		RTCL_SCENE_SPACE const struct rt_sphere *s = &tr->spheres[hit.sphere];
		normal = (sh->p - s->center.xyz) * s->inv_radius;
		sh->m = &tr->materials[s->material];
		sh->base = sh->m->color.xyz;
		COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_MUL3);
	} else {
		RTCL_SCENE_SPACE const struct rt_plane *pl = &tr->planes[hit.plane];
		normal = pl->normal.xyz;
		sh->m = &tr->materials[pl->material];
		sh->base = plane_color(tr, pl, sh->m->color.xyz, sh->p);
	}
	sh->inside = dot3(normal, ray->dir) > 0.0f;
	sh->n = sh->inside ? -normal : normal;
	COUNT_FLOPS(tr, FLOPS_DOT3);

	sh->color = material_ambient(sh->m->color) * sh->base * scene->ambient.xyz;
	sh->shadow_origin = sh->p + scene_epsilon(scene) * sh->n;
	sh->next_light = 0;
	COUNT_FLOPS(tr, 2 * FLOPS_MUL3 + FLOPS_MUL3 + FLOPS_ADD3);
}

/* Moves on to the next light that needs a shadow ray: computes its
 * Blinn-Phong terms and returns true, or returns false when no light is left.
 * A light whose terms add nothing needs no shadow ray. d: the ray's direction. */
static bool shading_next_light(struct tracer *tr, struct shading *sh, float3 d)
{
	while (sh->next_light < tr->scene->light_count) {
		int i = sh->next_light++;
		RTCL_SCENE_SPACE const struct rt_material *m = sh->m;
		float3 to_light = tr->lights[i].position.xyz - sh->p;
		float distance2 = dot3(to_light, to_light);
		float inv_distance = rsqrt(distance2);
		float distance = distance2 * inv_distance;
		float3 l = to_light * inv_distance;
		float diffuse = m->diffuse * fmax(0.0f, dot3(sh->n, l));
		/* to_light, distance2, rsqrt, distance, l, diffuse */
		COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_DOT3 + 1 + 1 + FLOPS_MUL3 + FLOPS_DOT3 + 2);

		float specular = 0.0f;
		float3 half_vector = l - d;
		float half_length2 = dot3(half_vector, half_vector);
		COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_DOT3);
		if (half_length2 > 0.0f) {
			float3 h = half_vector * rsqrt(half_length2);
			specular = m->specular * power(fmax(0.0f, dot3(sh->n, h)), m->shininess);
			/* h: rsqrt and scale; ks, max, pow */
			COUNT_FLOPS(tr, 1 + FLOPS_MUL3 + FLOPS_DOT3 + 3);
		}
		if (diffuse == 0.0f && specular == 0.0f)
			continue;
		sh->to_light_dir = l;
		sh->light_distance = distance;
		sh->diffuse = diffuse;
		sh->specular = specular;
		sh->light = i;
		COUNT_RAY(tr);
		return true;
	}
	return false;
}

/* Adds the light of the last shading_next_light, whose shadow ray was clear. */
static void shading_add_light(struct tracer *tr, struct shading *sh)
{
	sh->color += (sh->diffuse * sh->base + sh->specular) * tr->lights[sh->light].color.xyz;
	COUNT_FLOPS(tr, FLOPS_MUL3 + FLOPS_ADD3 + FLOPS_MUL3 + FLOPS_ADD3);
}

/* What shading_spawn spawned: a bit per ray. */
#define SPAWNED_REFRACTED 1
#define SPAWNED_REFLECTED 2
#define SPAWNED_BOTH (SPAWNED_REFRACTED | SPAWNED_REFLECTED)

/* Makes the rays the shaded hit spawns (RENDERING.md step 5) and returns
 * which: SPAWNED_* bits, with *refracted and *reflected set for those. */
static int shading_spawn(struct tracer *tr, const struct ray_job *ray, const struct shading *sh,
			 struct ray_job *refracted, struct ray_job *reflected)
{
	scene_ptr scene = tr->scene;
	RTCL_SCENE_SPACE const struct rt_material *m = sh->m;
	float epsilon = scene_epsilon(scene);
	float3 n = sh->n;
	int spawned = 0;

	if (ray->depth >= RTCL_MAX_DEPTH || ray->depth >= scene->max_depth)
		return 0;
	/* Secondary directions are renormalised: in float, |d| drifts from 1
	 * over a chain of bounces, and the intersection tests assume a unit d
	 * (without it, 0.16% of tir.json's pixels stray from the reference). */
	float reflect_weight = m->reflect;
	if (m->transmit > 0.0f) {
		float eta = sh->inside ? m->ior : m->inv_ior;
		float c = -dot3(ray->dir, n);
		float k = 1.0f - eta * eta * (1.0f - c * c);
		COUNT_FLOPS(tr, FLOPS_DOT3 + 5);
		if (k < 0.0f) {
			/* Total internal reflection: the light goes the reflected way. */
			reflect_weight += m->transmit;
			COUNT_FLOPS(tr, 1);
		} else {
			float3 t_dir = normalize3(eta * ray->dir + (eta * c - sqrt(k)) * n);
			*refracted = (struct ray_job){sh->p - epsilon * n, t_dir,
						      ray->weight * m->transmit, ray->depth + 1};
			spawned |= SPAWNED_REFRACTED;
			/* t_dir before normalizing: eta d, eta c − sqrt(k) (3), × n, + */
			COUNT_FLOPS(tr, FLOPS_MUL3 + 3 + FLOPS_MUL3 + FLOPS_ADD3 +
						FLOPS_NORMALIZE3 + FLOPS_MUL3 + FLOPS_ADD3 + 1);
		}
	}
	if (reflect_weight > 0.0f) {
		float3 r_dir = normalize3(ray->dir - 2.0f * dot3(ray->dir, n) * n);
		*reflected = (struct ray_job){sh->p + epsilon * n, r_dir,
					      ray->weight * reflect_weight, ray->depth + 1};
		spawned |= SPAWNED_REFLECTED;
		/* r_dir before normalizing: d·n, 2×, × n, d − */
		COUNT_FLOPS(tr, FLOPS_DOT3 + 1 + FLOPS_MUL3 + FLOPS_ADD3 + FLOPS_NORMALIZE3 +
					FLOPS_MUL3 + FLOPS_ADD3 + 1);
	}
	return spawned;
}

/* One ray of a pixel's tree being traced (RENDERING.md trace, steps 1-5),
 * one intersection at a time: first the ray itself, then a shadow ray for
 * each light that could add to its hit. Both ways of walking the tree, the
 * stack walk below and the wavefront kernel's trace_one, advance a ray only
 * through ray_step. */
struct ray_progress {
	struct ray_job ray;
	struct shading sh; /* the hit of ray being shaded */
	bool shadow;	   /* the next intersection: a shadow ray of sh, or ray */
};

/* What a finished ray gives: its colour, weight applied, and the rays it
 * spawned (SPAWNED_* bits; refracted and reflected are set for those). */
struct ray_outcome {
	float3 color;
	int spawned;
	struct ray_job refracted, reflected;
};

/* The per-ray step: intersects the next ray of rp, the ray itself or one of
 * its shadow rays, and takes the hit. Returns true when the ray is done,
 * with *out set, false when a shadow ray is to be traced next. The one
 * intersect_scene call serves both kinds of ray, so that work-items of a
 * SIMD group at different points of their trees still run the costly loop
 * over the objects together. */
static inline bool ray_step(struct tracer *tr, struct ray_progress *rp, struct ray_outcome *out)
{
	bool shadow = rp->shadow;
	struct hit hit = intersect_scene(tr, shadow ? rp->sh.shadow_origin : rp->ray.origin,
					 shadow ? rp->sh.to_light_dir : rp->ray.dir,
					 shadow ? rp->sh.light_distance : INFINITY, shadow);

	if (!shadow)
		COUNT_RAY(tr);
	if (!shadow && hit.t == 0.0f) {
		out->color = rp->ray.weight * tr->scene->background.xyz;
		out->spawned = 0;
		COUNT_FLOPS(tr, FLOPS_MUL3);
		return true;
	}
	if (!shadow)
		shading_begin(tr, &rp->ray, hit, &rp->sh);
	else if (hit.t == 0.0f)
		shading_add_light(tr, &rp->sh);
	rp->shadow = shading_next_light(tr, &rp->sh, rp->ray.dir);
	if (rp->shadow)
		return false;
	out->color = rp->ray.weight * rp->sh.color;
	COUNT_FLOPS(tr, FLOPS_MUL3);
	out->spawned = shading_spawn(tr, &rp->ray, &rp->sh, &out->refracted, &out->reflected);
	return true;
}

/* Traces one ray of the tree with its shadow rays: returns what it adds to
 * its pixel, weight included, and writes the rays it spawns into
 * children[0..*spawned): the refracted ray, then the reflected one. The
 * wavefront kernel's bounce. (With ray_step's one intersect_scene call
 * instead of one for the ray and one for its shadow rays, clang's NVPTX code
 * for the bounce has a 160-byte stack frame instead of 176.) */
static float3 trace_one(struct tracer *tr, const struct ray_job *ray, struct ray_job children[2],
			int *spawned)
{
	struct ray_progress rp;
	struct ray_outcome out;
	int n = 0;

	rp.ray = *ray;
	rp.shadow = false;
	while (!ray_step(tr, &rp, &out))
		;
	if (out.spawned & SPAWNED_REFRACTED)
		children[n++] = out.refracted;
	if (out.spawned & SPAWNED_REFLECTED)
		children[n++] = out.reflected;
	*spawned = n;
	return out.color;
}

/* A pixel's ray tree being walked depth first (OpenCL C has no recursion),
 * each ray's shadow rays right after it, one ray_step at a time, so that in
 * the persistent kernel a work-item on a new pixel and one deep in a tree
 * still step together.
 *
 * The walk goes on with the last ray a hit spawns, which stays in registers;
 * a refracted ray that has a reflected sibling waits on a stack in private
 * memory, waiting[RAY_STACK_SIZE], kept apart from struct walk: a compiler
 * puts a struct with a dynamically indexed array in it wholly in memory, and
 * the walk's other fields are used at every step (docs/performance.md step
 * 5). This is the order of a stack onto which both children are pushed, and
 * the sums are those of trace_one. */
struct walk {
	int top; /* rays waiting */
	struct ray_progress rp;
	float3 color;
	int pixel;	    /* y * width + x */
	ulong flops_before; /* the work-item's count when the pixel began */
};

/* Returns the unit direction of pixel (x, y)'s primary ray. */
static float3 primary_direction(struct tracer *tr, int x, int y)
{
	scene_ptr scene = tr->scene;
	float sx =
		(2.0f * ((float)x + 0.5f) / (float)scene->width - 1.0f) * scene_half_width(scene);
	float sy =
		(1.0f - 2.0f * ((float)y + 0.5f) / (float)scene->height) * scene_half_height(scene);

	/* sx and sy 5 each, by hand; two scaled vectors added; the normalize */
	COUNT_FLOPS(tr, 10 + 2 * (FLOPS_MUL3 + FLOPS_ADD3) + FLOPS_NORMALIZE3);
	return normalize3(scene->forward.xyz + sx * scene->right.xyz + sy * scene->up.xyz);
}

/* Sets *ray to pixel (x, y)'s primary ray. (Written in place: returning the
 * struct cost the walk a store in NVPTX code.) */
static inline void primary_ray(struct tracer *tr, int x, int y, struct ray_job *ray)
{
	*ray = (struct ray_job){tr->scene->eye.xyz, primary_direction(tr, x, y), 1.0f, 0};
}

/* Starts the walk of pixel (x, y), which must lie inside the image. */
static void walk_start(struct tracer *tr, struct walk *w, int x, int y)
{
	w->flops_before = tracer_flops(tr);
	w->pixel = y * tr->scene->width + x;
	primary_ray(tr, x, y, &w->rp.ray);
	w->top = 0;
	w->rp.shadow = false;
	w->color = (float3)(0.0f);
}

/* Takes the walk's next ray_step and returns whether the walk is done;
 * w->color is then the pixel's colour. */
static bool walk_step(struct tracer *tr, struct walk *w, struct ray_job *waiting)
{
	struct ray_outcome out;

	if (!ray_step(tr, &w->rp, &out))
		return false;
	w->color += out.color;
	COUNT_FLOPS(tr, FLOPS_ADD3);
	/* The tree below this ray is done or spawned: on to the next ray. A
	 * done ray leaves rp.shadow false, as a new ray needs it. */
	if (out.spawned == SPAWNED_BOTH)
		waiting[w->top++] = out.refracted;
	if (out.spawned & SPAWNED_REFLECTED)
		w->rp.ray = out.reflected;
	else if (out.spawned & SPAWNED_REFRACTED)
		w->rp.ray = out.refracted;
	else if (w->top > 0)
		w->rp.ray = waiting[--w->top];
	else
		return true;
	return false;
}

/* Counts a write of pixel, when the tests ask for it (RTCL_COUNT_WRITES). */
static inline void count_write(__global uint *write_counts, int pixel)
{
#ifdef RTCL_COUNT_WRITES
	atomic_inc(&write_counts[pixel]);
#else
	(void)write_counts;
	(void)pixel;
#endif
}

/* Stores flops as pixel's cost, when counting. */
static inline void store_pixel_flops(__global ulong *pixel_flops, int pixel, ulong flops)
{
#ifdef RTCL_COUNT_FLOPS
	pixel_flops[pixel] = flops;
#else
	(void)pixel_flops;
	(void)pixel;
	(void)flops;
#endif
}

/* Stores the colour of a finished walk, and what it cost when counting. */
static void walk_store(struct tracer *tr, const struct walk *w, __global float *image,
		       __global uint *write_counts)
{
	vstore3(w->color, w->pixel, image);
	store_pixel_flops(tr->pixel_flops, w->pixel, tracer_flops(tr) - w->flops_before);
	count_write(write_counts, w->pixel);
}

/* Traces pixel (x, y), which must lie inside the image, and stores it. */
static void render_pixel(struct tracer *tr, __global float *image, __global uint *write_counts,
			 int x, int y)
{
	struct walk w;
	struct ray_job waiting[RAY_STACK_SIZE];

	walk_start(tr, &w, x, y);
	while (!walk_step(tr, &w, waiting))
		;
	walk_store(tr, &w, image, write_counts);
}

/* Copies the scene block into the work-group's __local memory when the scene
 * lives there, and returns the scene every work-item reads. Every work-item of
 * the group must call it (it contains a barrier). */
static scene_ptr load_scene(__global const uint4 *scene_global, __local uint4 *scene_local)
{
#ifdef RTCL_SCENE_IN_LOCAL
	uint words = ((__global const struct rt_scene *)scene_global)->total_bytes / 16;
	uint item = get_local_id(1) * get_local_size(0) + get_local_id(0);
	uint items = get_local_size(0) * get_local_size(1);

	for (uint i = item; i < words; i += items)
		scene_local[i] = scene_global[i];
	barrier(CLK_LOCAL_MEM_FENCE);
	return (scene_ptr)scene_local;
#else
	(void)scene_local;
	return (scene_ptr)scene_global;
#endif
}

/* Stores what this work-item counted, once, at its end. */
static void store_counts(struct tracer *tr, __global ulong *counts, uint item)
{
#ifdef RTCL_COUNT_FLOPS
	counts[2 * item] = tr->flops;
	counts[2 * item + 1] = tr->rays;
#else
	(void)tr;
	(void)counts;
	(void)item;
#endif
}

/* Returns this work-item's index, row-major over the global NDRange: where
 * it stores its counts. */
static inline uint global_item(void)
{
	return get_global_id(1) * get_global_size(0) + get_global_id(0);
}

/* The image cut into chunks of the work-group's shape, the unit of work the
 * scheduling kernels hand out. The chunks at the right and bottom edges may
 * reach past the image; their pixels outside it are skipped. */
struct chunk_grid {
	uint chunk_w, chunk_h; /* a chunk's size in pixels: the work-group's */
	uint across, down;     /* chunks per row and per column */
};

static inline struct chunk_grid chunk_grid(scene_ptr scene)
{
	struct chunk_grid g;

	g.chunk_w = get_local_size(0);
	g.chunk_h = get_local_size(1);
	g.across = (scene->width + g.chunk_w - 1) / g.chunk_w;
	g.down = (scene->height + g.chunk_h - 1) / g.chunk_h;
	return g;
}

/* Returns the number of chunks, numbered row-major from 0. */
static inline uint chunk_count(const struct chunk_grid *g)
{
	return g->across * g->down;
}

/* Returns pixel (dx, dy) of the chunk in column cx and row cy of the grid. */
static inline int2 chunk_pixel(const struct chunk_grid *g, uint cx, uint cy, uint dx, uint dy)
{
	return (int2)(cx * g->chunk_w + dx, cy * g->chunk_h + dy);
}

/* Returns pixel (dx, dy) of chunk number chunk. */
static inline int2 numbered_chunk_pixel(const struct chunk_grid *g, uint chunk, uint dx, uint dy)
{
	return chunk_pixel(g, chunk % g->across, chunk / g->across, dx, dy);
}

/* Traces and stores pixel p if it lies inside the image. */
static inline void render_pixel_if_inside(struct tracer *tr, __global float *image,
					  __global uint *write_counts, int2 p)
{
	if (p.x < tr->scene->width && p.y < tr->scene->height)
		render_pixel(tr, image, write_counts, p.x, p.y);
}
