/* The path integrator's walk (docs/RENDERING.md, "The path"): a sample's
 * path, one intersection at a time, as walk.cl walks a Whitted ray tree:
 * walk_start and walk_step, which render_pixel (pixel.cl) calls for either
 * integrator. A step traces either the path's next segment or the shadow
 * ray of the last vertex's light sample, through the one intersect_scene
 * call, so that work-items at different points of their paths still step
 * together. Part of the tracer, only in programs built with RTCL_PATH:
 * built after light.cl. */
#ifdef RTCL_PATH

/* Russian roulette from this vertex on (RENDERING.md, "The path"). */
#define PATH_ROULETTE_VERTEX 3

/* The pairs of the sample sequence that vertex i takes ("The random
 * numbers of a path"): A the light choice, B the point on the light, C
 * the BSDF direction, D the lobe and the roulette. */
#define PAIR_LIGHT_CHOICE(i) (2u + 4u * (uint)(i))
#define PAIR_LIGHT_POINT(i) (3u + 4u * (uint)(i))
#define PAIR_BSDF(i) (4u + 4u * (uint)(i))
#define PAIR_LOBE(i) (5u + 4u * (uint)(i))

struct walk {
	float3 color;	    /* L, the radiance gathered */
	float3 beta;	    /* the path's throughput */
	struct ray_job ray; /* its next segment (the weight is beta's) */
	int vertex;	    /* of the next hit: 0 the primary ray's */
	bool specular;	    /* the last scattering was a delta lobe (or none yet) */
	float pdf_prev;	    /* the last BSDF sample's pdf */
	float3 x_prev;	    /* where that sample was taken */
	bool shadow;	    /* a shadow ray is to be traced next */
	bool done;	    /* the path ends after it */
	float3 shadow_origin, shadow_dir;
	float shadow_max;
	float3 shadow_color; /* what the light adds when the shadow ray is clear */
	int shadow_sphere, shadow_triangle; /* its emitter, which does not block it */
};

static inline float2 path_pair(struct tracer *tr, uint pair)
{
	return sample_pair(tr, tr->pixel_x, tr->pixel_y, tr->sample, tr->samples, pair);
}

/* Starts the path of pixel (x, y)'s sample k of n at offset. */
static void walk_start(struct tracer *tr, struct walk *w, int x, int y, float2 offset, uint k,
		       uint n)
{
	tracer_set_sample(tr, x, y, k, n);
	primary_ray(tr, x, y, offset, k, n, &w->ray);
	w->color = (float3)(0.0f);
	w->beta = (float3)(1.0f);
	w->vertex = 0;
	w->specular = true;
	w->pdf_prev = 0.0f;
	w->x_prev = w->ray.origin;
	w->shadow = false;
	w->done = false;
}

/* The hit being scattered: where, its normals and its BSDF. */
struct path_hit {
	struct hit hit;
	float3 emission; /* Le from the front side, its texture applied */
	float3 p, n, n_face;
	bool inside;
	int material;
	struct bsdf bsdf;
};

#ifdef RTCL_TEXTURES
/* A model's normal texture at a triangle's hit (RENDERING.md, "Models'
 * textures"): m = 2 T.rgb - 1 in the frame of the triangle's tangent dp/du
 * (from its texture coordinates) made orthogonal to the shading normal on
 * the front side, and its bitangent, turned to the side of dp/dv. The
 * shading normal is left as it is where the coordinates are degenerate. */
static void path_normal_map(struct tracer *tr, uint4 index, float3 texel, struct path_hit *h)
{
	float3 p0 = tr->vertices[index.x].position.xyz;
	float3 e1 = tr->vertices[index.y].position.xyz - p0;
	float3 e2 = tr->vertices[index.z].position.xyz - p0;
	struct rt_vertex_uv t0 = tr->uvs[index.x], t1 = tr->uvs[index.y], t2 = tr->uvs[index.z];
	float du1 = t1.u - t0.u, dv1 = t1.v - t0.v, du2 = t2.u - t0.u, dv2 = t2.v - t0.v;
	float det = du1 * dv2 - du2 * dv1;
	float3 n = h->inside ? -h->n : h->n; /* the front side's */

	COUNT_FLOPS(tr, 2 * FLOPS_ADD3 + 4 + 3);
	if (det == 0.0f)
		return;
	float3 dpdu = dv2 * e1 - dv1 * e2; /* times det, whose sign goes below */
	float3 dpdv = du1 * e2 - du2 * e1;
	float3 t = dpdu - dot3(n, dpdu) * n;
	float length2 = dot3(t, t);
	COUNT_FLOPS(tr, 4 * FLOPS_MUL3 + 2 * FLOPS_ADD3 + FLOPS_DOT3 + FLOPS_MUL3 + FLOPS_ADD3 +
				FLOPS_DOT3);
	if (!(length2 > 0.0f))
		return;
	t = t * (copysign(1.0f, det) * rsqrt(length2));
	float3 bitangent = cross3(n, t);
	if (dot3(bitangent, dpdv) * det < 0.0f)
		bitangent = -bitangent;
	float3 m = 2.0f * texel - 1.0f;
	float3 mapped = normalize3(m.x * t + m.y * bitangent + m.z * n);
	COUNT_FLOPS(tr, 2 + FLOPS_MUL3 + FLOPS_CROSS3 + FLOPS_DOT3 + 1 + 2 * FLOPS_ADD3 +
				3 * FLOPS_MUL3 + 2 * FLOPS_ADD3 + FLOPS_NORMALIZE3);
	h->n = h->inside ? -mapped : mapped;
}

/* A model's textures at a triangle's hit (RENDERING.md, "Models'
 * textures"): the base colour, the metallic-roughness (G scales the
 * roughness, B the metallic factor) and the emission. */
static void path_model_textures(struct tracer *tr, RTCL_SCENE_SPACE const struct rt_bsdf *b,
				uint4 index, struct hit hit, struct path_hit *h)
{
	struct bsdf *out = &h->bsdf;
	float2 barycentric = (float2)(hit.u, hit.v);

	out->color = fmin(triangle_base_color(tr, index, barycentric, out->color), (float3)(1.0f));
	if (b->metallic_roughness_texture < 0 && b->emissive_texture < 0 && b->normal_texture < 0)
		return;
	float2 uv = triangle_uv(tr, index, barycentric);
	if (b->metallic_roughness_texture >= 0) {
		float4 t = texture_lookup(tr, b->metallic_roughness_texture, uv);
		float roughness = b->roughness * t.y;
		out->metallic = b->metallic * t.z;
		out->alpha = fmax(roughness * roughness, BSDF_SMOOTH_ALPHA);
		COUNT_FLOPS(tr, 4);
	}
	if (b->emissive_texture >= 0) {
		h->emission *= texture_lookup(tr, b->emissive_texture, uv).xyz;
		COUNT_FLOPS(tr, FLOPS_MUL3);
	}
	if (b->normal_texture >= 0)
		path_normal_map(tr, index, texture_lookup(tr, b->normal_texture, uv).xyz, h);
}
#endif

/* Fills h for the hit of ray (RENDERING.md trace step 2 for the normals;
 * "The BSDFs" for the colours at the hit). kind is the material's BSDF
 * kind (RT_BSDF_*) when the caller knows it, a constant that lets the
 * compiler keep only that kind's code (the wavefront's shade kernels), or
 * -1: read from the material. */
static void path_surface(struct tracer *tr, const struct ray_job *ray, struct hit hit, int kind,
			 struct path_hit *h)
{
	struct shading sh;

	h->hit = hit;
	h->p = ray->origin + hit.t * ray->dir;
	COUNT_FLOPS(tr, FLOPS_MUL3 + FLOPS_ADD3 + FLOPS_DOT3);
	float3 normal = hit_surface(tr, hit, h->p, ray->dir, &sh);
	h->inside = dot3(normal, ray->dir) > 0.0f;
	h->n_face = h->inside ? -normal : normal;
	h->n = h->n_face;
	if (SCENE_HAS_TRIANGLES && hit.triangle >= 0) {
		uint4 index = tr->triangles[hit.triangle].index;
		if (triangle_smooth(index))
			h->n = triangle_shading_normal(tr, index, hit, h->n_face);
	}
	h->material = (int)(sh.m - tr->materials);

	RTCL_SCENE_SPACE const struct rt_bsdf *b = &tr->bsdfs[h->material];
	struct bsdf *out = &h->bsdf;
	out->type = kind >= 0 ? kind : b->type;
	out->alpha = b->color.w;
	out->eta = h->inside ? 1.0f / b->emission.w : b->emission.w;
	out->mirror = b->mirror;
	out->metallic = b->metallic;
	out->transmission = b->transmission;
	out->tint = b->mirror_tint ? sh.base : (float3)(1.0f);
	COUNT_FLOPS(tr, 1);
	if (out->type == RT_BSDF_MAPPED) {
		out->color = fmin(b->diffuse * sh.base, (float3)(1.0f));
		COUNT_FLOPS(tr, FLOPS_MUL3 + 3);
	} else if (hit.plane >= 0) {
		out->color = fmin(plane_color(tr, &tr->planes[hit.plane], b->color.xyz, h->p),
				  (float3)(1.0f));
		COUNT_FLOPS(tr, 3);
	} else {
		out->color = b->color.xyz;
	}
	h->emission = b->emission.xyz;
#ifdef RTCL_TEXTURES
	if (hit.triangle >= 0 && out->type != RT_BSDF_MAPPED)
		path_model_textures(tr, b, tr->triangles[hit.triangle].index, hit, h);
#endif
}

/* next_event (RENDERING.md): a light sampled from h's point; when it
 * would add something, its shadow ray is made the walk's next. */
static void path_next_event(struct tracer *tr, struct walk *w, const struct path_hit *h,
			    const struct frame *f, float3 wo)
{
	uint2 choice = sample_pair_bits(tr->pixel_x, tr->pixel_y, tr->sample, tr->samples,
					PAIR_LIGHT_CHOICE(w->vertex));
	uint g = (uint)(((ulong)choice.x * (ulong)tr->path->group_count) >> SAMPLE_BITS);
	float t = (float)choice.y * 0x1p-24f;
	struct light_sample ls;

	COUNT_FLOPS(tr, 1);
	if (!light_sample(tr, g, t, path_pair(tr, PAIR_LIGHT_POINT(w->vertex)), h->p, h->hit, &ls))
		return;
	float3 l = to_local(tr, f, ls.dir);
	bool front = dot3(ls.dir, h->n_face) > 0.0f;
	COUNT_FLOPS(tr, FLOPS_DOT3);
	if (front != (l.z > 0.0f))
		return;
	float bsdf_pdf;
	float3 value = bsdf_eval(tr, &h->bsdf, wo, l, &bsdf_pdf);
	float weight = ls.pdf > 0.0f ? mis_weight(tr, ls.pdf, bsdf_pdf) : 1.0f;
	float3 add = w->beta * value * ls.radiance_over_pdf * (fabs(l.z) * weight);
	COUNT_FLOPS(tr, 1 + 3 * FLOPS_MUL3);
	if (!(max3(add) > 0.0f))
		return;
	float epsilon = scene_epsilon(tr->scene);
	if (!(ls.t_max > 0.0f)) { /* an emitter nearer than the offsets: nothing between */
		w->color += add;
		COUNT_FLOPS(tr, FLOPS_ADD3);
		return;
	}
	w->shadow = true;
	w->shadow_origin = h->p + (front ? epsilon : -epsilon) * h->n_face;
	w->shadow_dir = ls.dir;
	w->shadow_max = ls.t_max;
	w->shadow_color = add;
	w->shadow_sphere = ls.sphere;
	w->shadow_triangle = ls.triangle;
	COUNT_FLOPS(tr, FLOPS_MUL3 + FLOPS_ADD3);
	COUNT_RAY(tr);
}

/* Counts, when counting, the path that ends: its length in segments, the
 * rays it traced through the scene (RENDERING.md, "Paths per bounce"): the
 * vertex of its next hit is the one its last segment looked for. Called
 * where every form of every kernel learns that a path ends, path_vertex
 * and path_missed (a shadow ray still to trace is no segment). */
static inline void path_count_end(struct tracer *tr, const struct walk *w)
{
#ifdef RTCL_COUNT_FLOPS
	ulong segments = (ulong)w->vertex + 1;

	tr->path_lengths[min(segments, (ulong)RT_PATH_LENGTH_BINS) - 1]++;
	tr->path_max = max(tr->path_max, segments);
	tr->path_segments += segments;
#else
	(void)tr;
	(void)w;
#endif
}

/* The hit of the path's segment (RENDERING.md, "The path", one turn of the
 * loop): its emission, the light sample, the BSDF sample that continues
 * the path. Returns whether the path ends here (after the shadow ray, if
 * one was made). kind: as path_surface's. */
static bool path_scatter(struct tracer *tr, struct walk *w, struct hit hit, int kind)
{
	struct path_hit h;
	int i = w->vertex;

	path_surface(tr, &w->ray, hit, kind, &h);
	RTCL_SCENE_SPACE const struct rt_bsdf *b = &tr->bsdfs[h.material];
	if (!h.inside && b->emits) {
		float3 le = h.emission;
		float weight = 1.0f;
		if (!w->specular) {
			float p_light = emitter_pdf(tr, hit, w->x_prev, h.p, b->emission.xyz);
			if (p_light > 0.0f)
				weight = mis_weight(tr, w->pdf_prev, p_light);
		}
		w->color += w->beta * le * weight;
		COUNT_FLOPS(tr, 2 * FLOPS_MUL3 + FLOPS_ADD3);
	}
	if (i > tr->scene->max_depth)
		return true;

	struct frame f = frame_around(tr, h.n);
	float3 wo = to_local(tr, &f, -w->ray.dir);
	if (!(wo.z > 0.0f))
		return true;
	if (bsdf_has_density(&h.bsdf) && tr->path->group_count > 0)
		path_next_event(tr, w, &h, &f, wo);

	struct bsdf_sample s;
	float2 lobe = path_pair(tr, PAIR_LOBE(i));
	if (!bsdf_sample(tr, &h.bsdf, wo, path_pair(tr, PAIR_BSDF(i)), lobe.x, &s))
		return true;
	float3 wi = normalize3(from_local(tr, &f, s.wi));
	bool front = dot3(wi, h.n_face) > 0.0f;
	COUNT_FLOPS(tr, FLOPS_NORMALIZE3 + FLOPS_DOT3 + FLOPS_MUL3);
	if (front != (s.wi.z > 0.0f))
		return true;
	w->beta *= s.weight;
	if (!(max3(w->beta) > 0.0f))
		return true;
	if (i >= PATH_ROULETTE_VERTEX) {
		float q = fmin(1.0f, max3(w->beta));
		if (lobe.y >= q)
			return true;
		w->beta /= q;
		COUNT_FLOPS(tr, 3 + FLOPS_MUL3);
	}
	float epsilon = scene_epsilon(tr->scene);
	w->specular = s.delta;
	w->pdf_prev = s.pdf;
	w->x_prev = h.p;
	w->ray.origin = h.p + (front ? epsilon : -epsilon) * h.n_face;
	w->ray.dir = wi;
	w->vertex = i + 1;
	COUNT_FLOPS(tr, FLOPS_MUL3 + FLOPS_ADD3);
	return false;
}

/* path_scatter, and the path counted when it ends there. */
static bool path_vertex(struct tracer *tr, struct walk *w, struct hit hit, int kind)
{
	bool done = path_scatter(tr, w, hit, kind);

	if (done)
		path_count_end(tr, w);
	return done;
}

/* A ray that leaves the scene: the environment's light, weighted by MIS
 * where next_event could have sampled it; the path ends. */
static void path_missed(struct tracer *tr, struct walk *w)
{
	float p_light;
	float3 le = environment_radiance(tr, w->ray.dir, &p_light);
	float weight = 1.0f;

	if (!w->specular && p_light > 0.0f)
		weight = mis_weight(tr, w->pdf_prev, p_light);
	w->color += w->beta * le * weight;
	COUNT_FLOPS(tr, 2 * FLOPS_MUL3 + FLOPS_ADD3);
	path_count_end(tr, w);
}

/* The BSDF kind (RT_BSDF_*) of the material hit: no flops, only the
 * lookups hit_surface makes to find the material (the wavefront's logic
 * kernel sorts the paths by it, docs/wavefront.md). */
static int path_hit_kind(struct tracer *tr, struct hit hit)
{
	int material;

	if (hit.sphere >= 0)
		material = tr->spheres[hit.sphere].material;
	else if (SCENE_HAS_TRIANGLES && hit.triangle >= 0)
		material = (int)triangle_material(tr->triangles[hit.triangle].index);
	else
		material = tr->planes[hit.plane].material;
	return tr->bsdfs[material].type;
}

/* The path's next segment traced: its nearest hit (t 0: none). */
static struct hit path_extend(struct tracer *tr, const struct walk *w)
{
	struct hit hit = intersect_scene(tr, w->ray.origin, w->ray.dir, INFINITY, false);

	COUNT_RAY(tr);
	return hit;
}

/* The shadow ray of the last vertex's light sample traced: whether nothing
 * blocks it (its own emitter does not). */
static bool path_shadow_clear(struct tracer *tr, const struct walk *w)
{
	tr->skip_sphere = w->shadow_sphere;
	tr->skip_triangle = w->shadow_triangle;
	struct hit blocker =
		intersect_scene(tr, w->shadow_origin, w->shadow_dir, w->shadow_max, true);
	tr->skip_sphere = tr->skip_triangle = -1;
	return blocker.t == 0.0f;
}

/* What the light sample adds once its shadow ray is traced. */
static void path_light_arrives(struct tracer *tr, struct walk *w, bool clear)
{
	if (clear) {
		w->color += w->shadow_color;
		COUNT_FLOPS(tr, FLOPS_ADD3);
	}
	w->shadow = false;
}

/* Takes the path's next step, one intersection; returns whether the path
 * is done: w->color is then the sample's colour. (waiting: the Whitted
 * walk's stack, which a path does not need.) The wavefront's stages form
 * calls the same pieces from separate kernels (cl/wavefront.cl). */
static bool walk_step(struct tracer *tr, struct walk *w, struct ray_job *waiting)
{
	(void)waiting;
	if (w->shadow) {
		path_light_arrives(tr, w, path_shadow_clear(tr, w));
		return w->done;
	}
	struct hit hit = path_extend(tr, w);
	if (hit.t == 0.0f) {
		path_missed(tr, w);
		return true;
	}
	w->done = path_vertex(tr, w, hit, -1);
	return w->done && !w->shadow;
}

#endif
