/* Walking a pixel's ray tree: ray_step advances one ray by one
 * intersection; walk_step walks the tree depth first with a stack (for
 * render_pixel, pixel.cl), and trace_one gives the wavefront kernel one
 * ray's colour and children; the primary rays of every integrator. Part of
 * the tracer: built after shade.cl. Under the path integrator (RTCL_PATH)
 * path.cl gives the walk instead. */

/* One ray of a pixel's tree being traced (RENDERING.md trace, steps 1-5),
 * one intersection at a time: first the ray itself, then a shadow ray for
 * each light that could add to its hit. The stack walk below advances a ray
 * only through ray_step; the wavefront's trace_one does the same from the
 * same pieces (ray_missed, shading_*, ray_shaded) in one loop. */
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

/* A ray that hits nothing adds the background, its weight applied. */
static inline float3 ray_missed(struct tracer *tr, const struct ray_job *ray)
{
	COUNT_FLOPS(tr, FLOPS_MUL3);
	return ray->weight * tr->scene->background.xyz;
}

/* A ray whose shading (sh) is complete adds its colour, weight applied, and
 * spawns its refracted and reflected rays (returns the SPAWNED_* bits). */
static inline float3 ray_shaded(struct tracer *tr, const struct ray_job *ray,
				const struct shading *sh, struct ray_job *refracted,
				struct ray_job *reflected, int *spawned)
{
	COUNT_FLOPS(tr, FLOPS_MUL3);
	*spawned = shading_spawn(tr, ray, sh, refracted, reflected);
	return ray->weight * sh->color;
}

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
		out->color = ray_missed(tr, &rp->ray);
		out->spawned = 0;
		return true;
	}
	if (!shadow)
		shading_begin(tr, &rp->ray, hit, &rp->sh);
	else if (hit.t == 0.0f)
		shading_add_light(tr, &rp->sh);
	rp->shadow = shading_next_light(tr, &rp->sh, rp->ray.dir);
	if (rp->shadow)
		return false;
	out->color =
		ray_shaded(tr, &rp->ray, &rp->sh, &out->refracted, &out->reflected, &out->spawned);
	return true;
}

/* Traces one ray of the tree with its shadow rays: returns what it adds to
 * its pixel, weight included, and writes the rays it spawns into
 * children[0..*spawned): the refracted ray, then the reflected one. The
 * wavefront kernel's bounce. It does what ray_step does, from the same
 * pieces, as one loop over the lights rather than through ray_step: going
 * through ray_step made the wavefront 3.3 % slower on an H100 (1.665 against
 * 1.612 ms, default scene, median of 20 launches in each of three rounds),
 * since the bounce has no other rays to keep in step with. */
static float3 trace_one(struct tracer *tr, const struct ray_job *ray, struct ray_job children[2],
			int *spawned)
{
	struct hit hit = intersect_scene(tr, ray->origin, ray->dir, INFINITY, false);
	struct shading sh;
	int which;

	COUNT_RAY(tr);
	*spawned = 0;
	if (hit.t == 0.0f)
		return ray_missed(tr, ray);
	shading_begin(tr, ray, hit, &sh);
	while (shading_next_light(tr, &sh, ray->dir))
		if (intersect_scene(tr, sh.shadow_origin, sh.to_light_dir, sh.light_distance, true)
			    .t == 0.0f)
			shading_add_light(tr, &sh);
	float3 color = ray_shaded(tr, ray, &sh, &children[0], &children[1], &which);
	if (which == SPAWNED_REFLECTED)
		children[0] = children[1];
	*spawned = popcount(which);
	return color;
}

/* Returns the direction of pixel (x, y)'s pinhole ray through the point
 * offset (in [0, 1)^2, from the pixel's top-left corner; 0.5 is the centre),
 * before normalising: its component along forward is 1. */
static float3 pinhole_direction(struct tracer *tr, int x, int y, float2 offset)
{
	scene_ptr scene = tr->scene;
	float sx = (2.0f * ((float)x + offset.x) / (float)scene->width - 1.0f) *
		   scene_half_width(scene);
	float sy = (1.0f - 2.0f * ((float)y + offset.y) / (float)scene->height) *
		   scene_half_height(scene);

	/* sx and sy 5 each, by hand; two scaled vectors added */
	COUNT_FLOPS(tr, 10 + 2 * (FLOPS_MUL3 + FLOPS_ADD3));
	return scene->forward.xyz + sx * scene->right.xyz + sy * scene->up.xyz;
}

/* Sets *ray to sample k (of n) of pixel (x, y): the primary ray through
 * offset, from the eye, or with a lens (RTCL_THIN_LENS) from the point of the
 * lens that the sample's pair 1 gives, through the point of the pinhole ray
 * on the focus plane (RENDERING.md, "The thin lens"). (Written in place:
 * returning the struct cost the walk a store in NVPTX code.) */
static inline void primary_ray(struct tracer *tr, int x, int y, float2 offset, uint k, uint n,
			       struct ray_job *ray)
{
	scene_ptr scene = tr->scene;
	float3 q = pinhole_direction(tr, x, y, offset);

	COUNT_FLOPS(tr, FLOPS_NORMALIZE3);
#ifdef RTCL_THIN_LENS
	float2 lens = sample_disk(tr, sample_pair(tr, x, y, k, n, 1));
	float3 on_lens = (scene->lens_radius * lens.x) * scene->right.xyz +
			 (scene->lens_radius * lens.y) * scene->up.xyz;
	/* A·a, A·b; the offset; F·q and its difference; the origin */
	COUNT_FLOPS(tr, 2 + FLOPS_MUL3 + FLOPS_MUL3 + FLOPS_ADD3 + FLOPS_MUL3 + FLOPS_ADD3 +
				FLOPS_ADD3);
	*ray = (struct ray_job){scene->eye.xyz + on_lens,
				normalize3(scene->focus_distance * q - on_lens), (ray_weight_t)(1.0f),
				0};
#else
	(void)k;
	(void)n;
	*ray = (struct ray_job){scene->eye.xyz, normalize3(q), (ray_weight_t)(1.0f), 0};
#endif
}

#ifndef RTCL_PATH /* the path integrator's walk is path.cl's */
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
};

/* Starts the walk of pixel (x, y)'s sample k of n at offset; the pixel must
 * lie inside the image. */
static void walk_start(struct tracer *tr, struct walk *w, int x, int y, float2 offset, uint k,
		       uint n)
{
	tracer_set_sample(tr, x, y, k, n);
	primary_ray(tr, x, y, offset, k, n, &w->rp.ray);
	w->top = 0;
	w->rp.shadow = false;
	w->color = (float3)(0.0f);
}

/* Takes the walk's next ray_step and returns whether the walk is done;
 * w->color is then the sample's colour. */
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
#endif
