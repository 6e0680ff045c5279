/* The tracer: what a pixel is (../shared/docs/RENDERING.md), written once and
 * used by every scheduling kernel. OpenCL C 1.2.
 *
 * Build-time options, set by the host (host/runtime.c):
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

static inline float3 normalize3(float3 v)
{
	return v / sqrt(dot3(v, v));
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

/* Returns the smallest t > 0 at which the ray meets the sphere (the far root
 * when the origin is inside), or 0 if it does not. The discriminant comes from
 * the distance between the centre and the ray (Haines et al., "Precision
 * Improvements for Ray/Sphere Intersection", Ray Tracing Gems, 2019): the
 * textbook b² − c loses most of its bits to cancellation when the sphere is
 * far away, and the hit points it gives are off the surface by more than
 * epsilon, which shows as speckled self-shadowing. */
static float intersect_sphere(struct tracer *tr, RTCL_SCENE_SPACE const struct rt_sphere *s,
			      float3 o, float3 d)
{
	float4 sphere = s->center; /* one load: the centre and radius² */
	float3 oc = o - sphere.xyz;
	float b = dot3(oc, d);
	float3 closest = fma((float3)(-b), d, oc); /* from the centre to the ray's closest point */
	float disc = sphere.w - dot3(closest, closest);

	COUNT_FLOPS(tr, 3 + 5 + 6 + 6);
	if (disc < 0.0f)
		return 0.0f;
	float far = sqrt(disc) - b;
	COUNT_FLOPS(tr, 2);
	if (b > 0.0f) /* the centre is behind the origin: only the far root can be ahead */
		return far > 0.0f ? far : 0.0f;
	/* The near root as c/far, free of the cancellation in −b − sqrt(disc). */
	float near = (dot3(oc, oc) - sphere.w) / far;
	COUNT_FLOPS(tr, 7);
	return near > 0.0f ? near : far;
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

/* Returns the nearest object the ray hits; hit.t is 0 when it hits nothing. */
static struct hit nearest_hit(struct tracer *tr, float3 o, float3 d)
{
	struct hit best = {0.0f, -1, -1};
	float nearest = INFINITY;

	for (int i = 0; i < tr->scene->sphere_count; i++) {
		float t = intersect_sphere(tr, &tr->spheres[i], o, d);
		if (t > 0.0f && t < nearest) {
			nearest = t;
			best.sphere = i;
		}
	}
	for (int i = 0; i < tr->scene->plane_count; i++) {
		float t = intersect_plane(tr, &tr->planes[i], o, d);
		if (t > 0.0f && t < nearest) {
			nearest = t;
			best.sphere = -1;
			best.plane = i;
		}
	}
	if (best.sphere >= 0 || best.plane >= 0)
		best.t = nearest;
	return best;
}

/* Returns whether any object lies on the ray with 0 < t < max_t. */
static bool occluded(struct tracer *tr, float3 o, float3 d, float max_t)
{
	for (int i = 0; i < tr->scene->sphere_count; i++) {
		float t = intersect_sphere(tr, &tr->spheres[i], o, d);
		if (t > 0.0f && t < max_t)
			return true;
	}
	for (int i = 0; i < tr->scene->plane_count; i++) {
		float t = intersect_plane(tr, &tr->planes[i], o, d);
		if (t > 0.0f && t < max_t)
			return true;
	}
	return false;
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

/* Returns the local colour at p (RENDERING.md step 4): ambient plus, for each
 * light not in shadow, Blinn-Phong diffuse and specular terms. */
static float3 shade_local(struct tracer *tr, RTCL_SCENE_SPACE const struct rt_material *m,
			  float3 base, float3 p, float3 n, float3 d)
{
	scene_ptr scene = tr->scene;
	float3 color = m->color.w * base * scene->ambient.xyz;
	float3 shadow_origin = p + scene->right.w * n;

	COUNT_FLOPS(tr, 6 + 6);
	for (int i = 0; i < scene->light_count; i++) {
		RTCL_SCENE_SPACE const struct rt_light *light = &tr->lights[i];
		float3 to_light = light->position.xyz - p;
		float distance = sqrt(dot3(to_light, to_light));
		float3 l = to_light / distance;
		float diffuse = m->diffuse * fmax(0.0f, dot3(n, l));
		COUNT_FLOPS(tr, 3 + 6 + 3 + 7);

		float specular = 0.0f;
		float3 half_vector = l - d;
		float half_length2 = dot3(half_vector, half_vector);
		COUNT_FLOPS(tr, 3 + 5);
		if (half_length2 > 0.0f) {
			float3 h = half_vector / sqrt(half_length2);
			specular = m->specular * pow(fmax(0.0f, dot3(n, h)), m->shininess);
			COUNT_FLOPS(tr, 4 + 5 + 3);
		}
		/* A term that adds nothing needs no shadow ray. */
		if (diffuse == 0.0f && specular == 0.0f)
			continue;
		COUNT_RAY(tr);
		if (occluded(tr, shadow_origin, l, distance))
			continue;
		color += (diffuse * base + specular) * light->color.xyz;
		COUNT_FLOPS(tr, 3 + 3 + 3 + 3);
	}
	return color;
}

/* Traces one ray of the tree (RENDERING.md trace, steps 1-5): returns what it
 * adds to its pixel, weight included, and writes the rays it spawns into
 * children[0..*spawned): the refracted ray, then the reflected one. Used by the
 * tree walk below and by the wavefront kernel. */
static float3 trace_one(struct tracer *tr, const struct ray_job *ray, struct ray_job children[2],
			int *spawned)
{
	scene_ptr scene = tr->scene;
	float epsilon = scene->right.w;
	struct hit hit = nearest_hit(tr, ray->origin, ray->dir);

	*spawned = 0;
	COUNT_RAY(tr);
	if (hit.t == 0.0f) {
		COUNT_FLOPS(tr, 3);
		return ray->weight * scene->background.xyz;
	}

	float3 p = ray->origin + hit.t * ray->dir;
	float3 normal;
	float3 base;
	RTCL_SCENE_SPACE const struct rt_material *m;
	COUNT_FLOPS(tr, 6);
	if (hit.sphere >= 0) {
		RTCL_SCENE_SPACE const struct rt_sphere *s = &tr->spheres[hit.sphere];
		normal = (p - s->center.xyz) * s->inv_radius;
		m = &tr->materials[s->material];
		base = m->color.xyz;
		COUNT_FLOPS(tr, 6);
	} else {
		RTCL_SCENE_SPACE const struct rt_plane *pl = &tr->planes[hit.plane];
		normal = pl->normal.xyz;
		m = &tr->materials[pl->material];
		base = plane_color(tr, pl, m->color.xyz, p);
	}
	bool inside = dot3(normal, ray->dir) > 0.0f;
	float3 n = inside ? -normal : normal;
	COUNT_FLOPS(tr, 5);

	float3 contribution = ray->weight * shade_local(tr, m, base, p, n, ray->dir);
	COUNT_FLOPS(tr, 3);
	if (ray->depth >= RTCL_MAX_DEPTH || ray->depth >= scene->max_depth)
		return contribution;

	/* Secondary directions are renormalised: in float, |d| drifts from 1
	 * over a chain of bounces, and the intersection tests assume a unit d
	 * (without it, 0.16% of tir.json's pixels stray from the reference). */
	float reflect_weight = m->reflect;
	if (m->transmit > 0.0f) {
		float eta = inside ? m->ior : m->inv_ior;
		float c = -dot3(ray->dir, n);
		float k = 1.0f - eta * eta * (1.0f - c * c);
		COUNT_FLOPS(tr, 5 + 5);
		if (k < 0.0f) {
			/* Total internal reflection: the light goes the reflected way. */
			reflect_weight += m->transmit;
			COUNT_FLOPS(tr, 1);
		} else {
			float3 t_dir = normalize3(eta * ray->dir + (eta * c - sqrt(k)) * n);
			children[(*spawned)++] = (struct ray_job){
				p - epsilon * n, t_dir, ray->weight * m->transmit, ray->depth + 1};
			COUNT_FLOPS(tr, 12 + 9 + 6 + 1);
		}
	}
	if (reflect_weight > 0.0f) {
		float3 r_dir = normalize3(ray->dir - 2.0f * dot3(ray->dir, n) * n);
		children[(*spawned)++] = (struct ray_job){
			p + epsilon * n, r_dir, ray->weight * reflect_weight, ray->depth + 1};
		COUNT_FLOPS(tr, 12 + 9 + 6 + 1);
	}
	return contribution;
}

/* Returns the colour seen along the primary ray: the ray tree walked depth
 * first (OpenCL C has no recursion). The walk goes on with the last ray a hit
 * spawns, which stays in registers; a refracted ray that has a reflected
 * sibling waits on a stack in private memory. This is the order of a stack
 * onto which both children are pushed, so the sum is the same. */
static float3 trace(struct tracer *tr, float3 origin, float3 dir)
{
	struct ray_job waiting[RAY_STACK_SIZE];
	int top = 0;
	struct ray_job ray = {origin, dir, 1.0f, 0};
	float3 color = (float3)(0.0f);

	for (;;) {
		struct ray_job children[2];
		int spawned;

		color += trace_one(tr, &ray, children, &spawned);
		COUNT_FLOPS(tr, 3);
		if (spawned == 2)
			waiting[top++] = children[0];
		if (spawned > 0)
			ray = children[spawned - 1];
		else if (top > 0)
			ray = waiting[--top];
		else
			break;
	}
	return color;
}

/* Returns the unit direction of pixel (x, y)'s primary ray. */
static float3 primary_direction(struct tracer *tr, int x, int y)
{
	scene_ptr scene = tr->scene;
	float sx = (2.0f * ((float)x + 0.5f) / (float)scene->width - 1.0f) * scene->eye.w;
	float sy = (1.0f - 2.0f * ((float)y + 0.5f) / (float)scene->height) * scene->forward.w;

	COUNT_FLOPS(tr, 10 + 6 + 6 + 9);
	return normalize3(scene->forward.xyz + sx * scene->right.xyz + sy * scene->up.xyz);
}

/* Traces pixel (x, y), which must lie inside the image, and stores it. */
static void render_pixel(struct tracer *tr, __global float *image, __global uint *write_counts,
			 int x, int y)
{
	int index = y * tr->scene->width + x;
#ifdef RTCL_COUNT_FLOPS
	ulong flops_before = tr->flops;
#endif
	float3 color = trace(tr, tr->scene->eye.xyz, primary_direction(tr, x, y));

	vstore3(color, index, image);
#ifdef RTCL_COUNT_FLOPS
	tr->pixel_flops[index] = tr->flops - flops_before;
#endif
#ifdef RTCL_COUNT_WRITES
	atomic_inc(&write_counts[index]);
#else
	(void)write_counts;
#endif
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
