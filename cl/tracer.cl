/* The tracer: what a pixel is (../shared/docs/RENDERING.md), written once and
 * used by every scheduling kernel. OpenCL C 1.2.
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

#ifdef RTCL_COUNT_FLOPS
#define COUNT_FLOPS(tr, n) ((tr)->flops += (n))
#define COUNT_RAY(tr) ((tr)->rays++)
#else
#define COUNT_FLOPS(tr, n) ((void)0)
#define COUNT_RAY(tr) ((void)0)
#endif

typedef RTCL_SCENE_SPACE const struct rt_scene *scene_ptr;

/* The scene as the tracer sees it, and the work-item's flop counter. */
struct tracer {
	scene_ptr scene;
	RTCL_SCENE_SPACE const struct rt_material *materials;
	RTCL_SCENE_SPACE const struct rt_sphere *spheres;
	RTCL_SCENE_SPACE const struct rt_plane *planes;
	RTCL_SCENE_SPACE const struct rt_light *lights;
#ifdef RTCL_COUNT_FLOPS
	ulong flops;
	ulong rays;		     /* primary, secondary and shadow rays traced */
	__global ulong *pixel_flops; /* flops spent on each pixel */
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

/* Counted 9, like the division by the length it stands for. */
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
#ifdef RTCL_COUNT_FLOPS
	tr->flops = 0;
	tr->rays = 0;
	tr->pixel_flops = counts + 2 * get_global_size(0) * get_global_size(1);
#else
	(void)counts;
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
	COUNT_FLOPS(tr, 2 + 2 + 4 + 1 + 1 + 3 + 5 + 5);
	return f;
}

/* Returns the squared distance between the sphere's centre and the ray, which
 * is more than radius² when the ray misses. The caller counts its 15 flops
 * (two fma chains of 6, one fma and one product). */
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
static void sphere_consider(struct tracer *tr, float4 sphere, float gap, float3 o, float3 d,
			    int i, bool any_hit, float *nearest, struct hit *best)
{
	if (!(gap <= sphere.w) || (any_hit && best->sphere >= 0))
		return;
	float3 oc = o - sphere.xyz;
	float b = dot3(oc, d);
	float far = sqrt(sphere.w - gap) - b;
	float t;
	COUNT_FLOPS(tr, 3 + 5 + 1 + 2);
	if (b > 0.0f) { /* the centre is behind the origin: only the far root can be ahead */
		t = far;
	} else {
		/* The near root as c/far, free of the cancellation in −b − sqrt(disc). */
		float near = (dot3(oc, oc) - sphere.w) / far;
		COUNT_FLOPS(tr, 7);
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
	float3 n = pl->normal.xyz;
	float denom = dot3(n, d);

	COUNT_FLOPS(tr, 5);
	if (denom == 0.0f)
		return 0.0f;
	float t = (pl->normal.w - dot3(n, o)) / denom;
	COUNT_FLOPS(tr, 7);
	return t > 0.0f ? t : 0.0f;
}

#if RT_SPHERE_GROUP != 4
#error "intersect_scene tests spheres four at a time"
#endif

/* Returns the nearest object on the ray with 0 < t < max_t; hit.t is 0 when
 * there is none. With any_hit, returns the first such object found instead:
 * enough for a shadow ray. The one loop serves both kinds of ray, so that
 * work-items of a SIMD group tracing different kinds still run it together. */
static struct hit intersect_scene(struct tracer *tr, float3 o, float3 d, float max_t,
				  bool any_hit)
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

		COUNT_FLOPS(tr, 15 * min(RT_SPHERE_GROUP, tr->scene->sphere_count - i));
		if ((g0 <= s0.w) | (g1 <= s1.w) | (g2 <= s2.w) | (g3 <= s3.w)) {
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
	float size = pl->checker_color.w;
	int square = (int)floor(component(p, pl->checker_s_axis) / size) +
		     (int)floor(component(p, pl->checker_t_axis) / size);
	COUNT_FLOPS(tr, 2);
	return (square & 1) ? pl->checker_color.xyz : material_color;
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
	COUNT_FLOPS(tr, 6);
	if (hit.sphere >= 0) {
		RTCL_SCENE_SPACE const struct rt_sphere *s = &tr->spheres[hit.sphere];
		normal = (sh->p - s->center.xyz) * s->inv_radius;
		sh->m = &tr->materials[s->material];
		sh->base = sh->m->color.xyz;
		COUNT_FLOPS(tr, 6);
	} else {
		RTCL_SCENE_SPACE const struct rt_plane *pl = &tr->planes[hit.plane];
		normal = pl->normal.xyz;
		sh->m = &tr->materials[pl->material];
		sh->base = plane_color(tr, pl, sh->m->color.xyz, sh->p);
	}
	sh->inside = dot3(normal, ray->dir) > 0.0f;
	sh->n = sh->inside ? -normal : normal;
	COUNT_FLOPS(tr, 5);

	sh->color = sh->m->color.w * sh->base * scene->ambient.xyz;
	sh->shadow_origin = sh->p + scene->right.w * sh->n;
	sh->next_light = 0;
	COUNT_FLOPS(tr, 6 + 6);
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
		COUNT_FLOPS(tr, 3 + 5 + 1 + 1 + 3 + 7);

		float specular = 0.0f;
		float3 half_vector = l - d;
		float half_length2 = dot3(half_vector, half_vector);
		COUNT_FLOPS(tr, 3 + 5);
		if (half_length2 > 0.0f) {
			float3 h = half_vector * rsqrt(half_length2);
			specular = m->specular * power(fmax(0.0f, dot3(sh->n, h)), m->shininess);
			COUNT_FLOPS(tr, 4 + 5 + 3);
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
	COUNT_FLOPS(tr, 3 + 3 + 3 + 3);
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
	float epsilon = scene->right.w;
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
		COUNT_FLOPS(tr, 5 + 5);
		if (k < 0.0f) {
			/* Total internal reflection: the light goes the reflected way. */
			reflect_weight += m->transmit;
			COUNT_FLOPS(tr, 1);
		} else {
			float3 t_dir = normalize3(eta * ray->dir + (eta * c - sqrt(k)) * n);
			*refracted = (struct ray_job){sh->p - epsilon * n, t_dir,
						      ray->weight * m->transmit, ray->depth + 1};
			spawned |= SPAWNED_REFRACTED;
			COUNT_FLOPS(tr, 12 + 9 + 6 + 1);
		}
	}
	if (reflect_weight > 0.0f) {
		float3 r_dir = normalize3(ray->dir - 2.0f * dot3(ray->dir, n) * n);
		*reflected = (struct ray_job){sh->p + epsilon * n, r_dir,
					      ray->weight * reflect_weight, ray->depth + 1};
		spawned |= SPAWNED_REFLECTED;
		COUNT_FLOPS(tr, 12 + 9 + 6 + 1);
	}
	return spawned;
}

/* Traces one ray of the tree (RENDERING.md trace, steps 1-5) with its shadow
 * rays: returns what it adds to its pixel, weight included, and writes the
 * rays it spawns into children[0..*spawned): the refracted ray, then the
 * reflected one. The wavefront kernel's step; walk_step below interleaves
 * the same steps. */
static float3 trace_one(struct tracer *tr, const struct ray_job *ray, struct ray_job children[2],
			int *spawned)
{
	struct hit hit = intersect_scene(tr, ray->origin, ray->dir, INFINITY, false);
	struct shading sh;

	*spawned = 0;
	COUNT_RAY(tr);
	if (hit.t == 0.0f) {
		COUNT_FLOPS(tr, 3);
		return ray->weight * tr->scene->background.xyz;
	}
	shading_begin(tr, ray, hit, &sh);
	while (shading_next_light(tr, &sh, ray->dir))
		if (intersect_scene(tr, sh.shadow_origin, sh.to_light_dir, sh.light_distance, true)
			    .t == 0.0f)
			shading_add_light(tr, &sh);
	COUNT_FLOPS(tr, 3);
	int which = shading_spawn(tr, ray, &sh, &children[0], &children[1]);
	if (which == SPAWNED_REFLECTED)
		children[0] = children[1];
	*spawned = popcount(which);
	return ray->weight * sh.color;
}

/* A pixel's ray tree being walked depth first (OpenCL C has no recursion),
 * each ray's shadow rays right after it, one intersection at a time. Every
 * ray, of either kind, goes through the one intersect_scene call of
 * walk_step: work-items of a SIMD group at different points of their trees
 * (one on a shadow ray, another on a reflection, or, in the persistent
 * kernel, another on a new pixel) run the costly loop over the objects
 * together instead of one after the other.
 *
 * The walk goes on with the last ray a hit spawns, which stays in registers;
 * a refracted ray that has a reflected sibling waits on a stack in private
 * memory, waiting[RAY_STACK_SIZE], kept apart from struct walk: a compiler
 * puts a struct with a dynamically indexed array in it wholly in memory, and
 * the walk's other fields are used at every step. This is the order of a
 * stack onto which both children are pushed, and the sums are those of
 * trace_one. */
struct walk {
	int top; /* rays waiting */
	struct ray_job ray;
	struct shading sh;
	bool shadow; /* the ray to intersect next: a shadow ray of sh, or ray */
	float3 color;
	int pixel; /* y * width + x */
#ifdef RTCL_COUNT_FLOPS
	ulong flops_before;
#endif
};

/* Returns the unit direction of pixel (x, y)'s primary ray. */
static float3 primary_direction(struct tracer *tr, int x, int y)
{
	scene_ptr scene = tr->scene;
	float sx = (2.0f * ((float)x + 0.5f) / (float)scene->width - 1.0f) * scene->eye.w;
	float sy = (1.0f - 2.0f * ((float)y + 0.5f) / (float)scene->height) * scene->forward.w;

	COUNT_FLOPS(tr, 10 + 6 + 6 + 9);
	return normalize3(scene->forward.xyz + sx * scene->right.xyz + sy * scene->up.xyz);
}

/* Starts the walk of pixel (x, y), which must lie inside the image. */
static void walk_start(struct tracer *tr, struct walk *w, int x, int y)
{
#ifdef RTCL_COUNT_FLOPS
	w->flops_before = tr->flops;
#endif
	w->pixel = y * tr->scene->width + x;
	w->ray = (struct ray_job){tr->scene->eye.xyz, primary_direction(tr, x, y), 1.0f, 0};
	w->top = 0;
	w->shadow = false;
	w->color = (float3)(0.0f);
}

/* Traces the walk's next ray and returns whether the walk is done; w->color is
 * then the pixel's colour. */
static bool walk_step(struct tracer *tr, struct walk *w, struct ray_job *waiting)
{
	bool shadow = w->shadow;
	struct hit hit = intersect_scene(tr, shadow ? w->sh.shadow_origin : w->ray.origin,
					 shadow ? w->sh.to_light_dir : w->ray.dir,
					 shadow ? w->sh.light_distance : INFINITY, shadow);
	struct ray_job refracted, reflected;
	int spawned = 0;

	if (!shadow)
		COUNT_RAY(tr);
	if (!shadow && hit.t == 0.0f) {
		w->color += w->ray.weight * tr->scene->background.xyz;
		COUNT_FLOPS(tr, 3 + 3);
	} else {
		if (!shadow)
			shading_begin(tr, &w->ray, hit, &w->sh);
		else if (hit.t == 0.0f)
			shading_add_light(tr, &w->sh);
		w->shadow = shading_next_light(tr, &w->sh, w->ray.dir);
		if (w->shadow)
			return false;
		w->color += w->ray.weight * w->sh.color;
		COUNT_FLOPS(tr, 3 + 3);
		spawned = shading_spawn(tr, &w->ray, &w->sh, &refracted, &reflected);
	}
	/* The tree below this ray is done or spawned: on to the next ray. */
	if (spawned == SPAWNED_BOTH)
		waiting[w->top++] = refracted;
	if (spawned & SPAWNED_REFLECTED)
		w->ray = reflected;
	else if (spawned & SPAWNED_REFRACTED)
		w->ray = refracted;
	else if (w->top > 0)
		w->ray = waiting[--w->top];
	else
		return true;
	return false;
}

/* Stores the colour of a finished walk, and what it cost when counting. */
static void walk_store(struct tracer *tr, const struct walk *w, __global float *image,
		       __global uint *write_counts)
{
	vstore3(w->color, w->pixel, image);
#ifdef RTCL_COUNT_FLOPS
	tr->pixel_flops[w->pixel] = tr->flops - w->flops_before;
#endif
#ifdef RTCL_COUNT_WRITES
	atomic_inc(&write_counts[w->pixel]);
#else
	(void)write_counts;
#endif
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
