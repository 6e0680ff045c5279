/* Shading (docs/RENDERING.md, trace steps 2-5): the base colour, the lights
 * and their shadow rays, and the reflected and refracted rays a hit spawns.
 * Part of the tracer: built after intersect.cl. */

/* Returns the base colour C at p on the plane: its material colour, or the
 * checker colour on the odd squares. */
static float3 plane_color(struct tracer *tr, RTCL_SCENE_SPACE const struct rt_plane *pl,
			  float3 material_color, float3 p)
{
	if (!pl->has_checker)
		return material_color;
	float4 checker = pl->checker_color; /* the colour and the square size */
	float size = checker_size(checker);
	/* p is relative to the eye: the plane's checker origin puts the squares
	 * back where the world has them. */
	float3 world = p + pl->checker_origin.xyz;
	int square = (int)floor(component(world, pl->checker_s_axis) / size) +
		     (int)floor(component(world, pl->checker_t_axis) / size);
	COUNT_FLOPS(tr, 2 + FLOPS_ADD3);
	return (square & 1) ? checker.xyz : material_color;
}

/* Whether a hit's normals are used: by the lights' terms and shadow rays, or
 * by the rays a hit spawns. A scene without lights at max_depth 0 (the
 * primary rays of the comparison with TinyBVH, docs/bvh.md) uses neither, so
 * its hits skip them (RENDERING.md step 2): a triangle's normal read its
 * vertices again, 5-8 % of such a frame on an H100 (batch 86). */
#if defined(RTCL_NO_LIGHTS) && RTCL_MAX_DEPTH == 0
#define SHADING_NORMALS 0
#else
#define SHADING_NORMALS 1
#endif

/* A hit being shaded (RENDERING.md steps 2-4), carried across the shadow rays
 * it casts: the lights are taken one at a time, so that a shadow ray can go
 * through the same intersect_scene call as every other ray. */
struct shading {
	float3 p, n, base;
	float3 n_face; /* the geometric normal turned to the ray's side: where the
			  spawned rays start from (n itself but on a smooth triangle) */
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
#ifdef RTCL_AREA_LIGHTS
	int depth; /* of the ray being shaded: which pairs its light samples take */
#endif
};

/* RENDERING.md step 2 on a smooth triangle: the shading normal, interpolated
 * at the hit's barycentric (u, v) from the vertex normals, normalised and
 * turned to the side of n_face (the geometric normal facing the ray); n_face
 * itself where the interpolation gives the zero vector. */
static float3 triangle_shading_normal(struct tracer *tr, uint4 index, struct hit hit, float3 n_face)
{
	float w = 1.0f - hit.u - hit.v;
	float3 n = w * tr->normals[index.x].normal.xyz + hit.u * tr->normals[index.y].normal.xyz +
		   hit.v * tr->normals[index.z].normal.xyz;
	float length2 = dot3(n, n);
	/* w (2), three scalings and two sums, the squared length */
	COUNT_FLOPS(tr, 2 + 3 * FLOPS_MUL3 + 2 * FLOPS_ADD3 + FLOPS_DOT3);
	if (length2 == 0.0f)
		return n_face;
	n = n * rsqrt(length2);
	COUNT_FLOPS(tr, 1 + FLOPS_MUL3 + FLOPS_DOT3);
	return dot3(n, n_face) < 0.0f ? -n : n;
}

/* A triangle's unit geometric normal, normalize(e1 × e2) (RENDERING.md step
 * 2) from the vertices as the triangle test reads them. The cross product is
 * first scaled by its largest component, since its squared length could
 * overflow or underflow in float for coordinates near 1e18 or tiny edges.
 * Where it is 0 in float (a sliver whose vertices rounded to a line), the
 * triangle faces the ray: -d. */
static float3 triangle_normal(struct tracer *tr, uint4 index, float3 d)
{
	float3 v0 = tr->vertices[index.x].position.xyz;
	float3 n = cross3(tr->vertices[index.y].position.xyz - v0,
			  tr->vertices[index.z].position.xyz - v0);
	float largest = fmax(fmax(fabs(n.x), fabs(n.y)), fabs(n.z));

	COUNT_FLOPS(tr, FLOPS_TRIANGLE_CROSS);
	if (largest == 0.0f)
		return -d;
	n = n * (1.0f / largest);
	COUNT_FLOPS(tr, 1 + FLOPS_MUL3 + FLOPS_NORMALIZE3);
	return n * rsqrt(dot3(n, n));
}

/* The geometric normal at the hit (step 2; -d where nothing uses it,
 * SHADING_NORMALS), the material and base colour (step 3). A triangle's
 * shading normal is left to shading_begin. */
static float3 hit_surface(struct tracer *tr, struct hit hit, float3 p, float3 d, struct shading *sh)
{
	float3 normal;

	if (hit.sphere >= 0) {
		RTCL_SCENE_SPACE const struct rt_sphere *s = &tr->spheres[hit.sphere];
		normal = -d;
		if (SHADING_NORMALS) {
			normal = (p - s->center.xyz) * s->inv_radius;
			COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_MUL3);
		}
		sh->m = &tr->materials[s->material];
		sh->base = sh->m->color.xyz;
	} else if (SCENE_HAS_TRIANGLES && hit.triangle >= 0) {
		uint4 index = tr->triangles[hit.triangle].index;
		normal = SHADING_NORMALS ? triangle_normal(tr, index, d) : -d;
		sh->m = &tr->materials[triangle_material(index)];
		sh->base = sh->m->color.xyz;
#ifdef RTCL_TEXTURES
		sh->base = triangle_base_color(tr, index, (float2)(hit.u, hit.v), sh->base);
#endif
	} else {
		RTCL_SCENE_SPACE const struct rt_plane *pl = &tr->planes[hit.plane];
		normal = pl->normal.xyz;
		sh->m = &tr->materials[pl->material];
		sh->base = plane_color(tr, pl, sh->m->color.xyz, p);
	}
	return normal;
}

/* Starts shading the hit of ray: the hit point, the normals, the base colour
 * and the ambient term. */
static void shading_begin(struct tracer *tr, const struct ray_job *ray, struct hit hit,
			  struct shading *sh)
{
	scene_ptr scene = tr->scene;

	sh->p = ray->origin + hit.t * ray->dir;
	COUNT_FLOPS(tr, FLOPS_MUL3 + FLOPS_ADD3);
	float3 normal = hit_surface(tr, hit, sh->p, ray->dir, sh);
	sh->inside = SHADING_NORMALS && dot3(normal, ray->dir) > 0.0f;
	sh->n_face = sh->inside ? -normal : normal;
	sh->n = sh->n_face;
	if (SHADING_NORMALS)
		COUNT_FLOPS(tr, FLOPS_DOT3);
	if (SHADING_NORMALS && SCENE_HAS_TRIANGLES && hit.triangle >= 0) {
		uint4 index = tr->triangles[hit.triangle].index;
		if (triangle_smooth(index))
			sh->n = triangle_shading_normal(tr, index, hit, sh->n_face);
	}

	sh->color = material_ambient(sh->m->color) * sh->base * scene->ambient.xyz;
	sh->shadow_origin = sh->p + scene_epsilon(scene) * sh->n_face;
	sh->next_light = 0;
#ifdef RTCL_AREA_LIGHTS
	sh->depth = ray->depth;
#endif
	COUNT_FLOPS(tr, 2 * FLOPS_MUL3 + FLOPS_MUL3 + FLOPS_ADD3);
}

#ifdef RTCL_AREA_LIGHTS
/* Light i's sample for the hit (RENDERING.md, "Light samples"): the point of
 * the disk of radius `size` across unit w at offset, given by the pair of the
 * sample that belongs to the light and the depth of the ray shaded, through
 * Duff et al.'s frame across w. Returns size·a·b1 + size·b·b2. */
static float3 light_disk_offset(struct tracer *tr, const struct shading *sh, int i, float3 w,
				float size)
{
	uint pair = 2u + (uint)sh->depth * (uint)tr->scene->light_count + (uint)i;
	float2 disk = sample_disk(
		tr, sample_pair(tr, tr->pixel_x, tr->pixel_y, tr->sample, tr->samples, pair));
	float sign = copysign(1.0f, w.z);
	float e = -1.0f / (sign + w.z);
	float g = w.x * w.y * e;
	float3 b1 = (float3)(1.0f + sign * w.x * w.x * e, sign * g, -sign * w.x);
	float3 b2 = (float3)(g, sign + w.y * w.y * e, -w.y);

	/* the frame: e 2, g 2, b1 6, b2 3; size·a, size·b; the two scaled
	 * vectors and their sum */
	COUNT_FLOPS(tr, 13 + 2 + FLOPS_MUL3 + FLOPS_MUL3 + FLOPS_ADD3);
	return (size * disk.x) * b1 + (size * disk.y) * b2;
}

/* Where light i's shadow ray goes from the hit: the unit direction *l and
 * the distance to the light (INFINITY for a directional light). A point light
 * is computed as without RTCL_AREA_LIGHTS, bit for bit. Returns false when
 * the light adds nothing (the hit at a sphere light's centre). */
static bool light_direction(struct tracer *tr, const struct shading *sh, int i, float3 *l,
			    float *distance)
{
	float4 position = tr->lights[i].position;
	float size = position.w; /* a sphere's radius, or tan(angle) */

	if (tr->lights[i].color.w != 0.0f) { /* directional: xyz the unit way to it */
		*distance = INFINITY;
		*l = position.xyz;
		if (size > 0.0f) {
			*l = normalize3(*l + light_disk_offset(tr, sh, i, position.xyz, size));
			COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_NORMALIZE3);
		}
		return true;
	}
	float3 target = position.xyz;
	if (size > 0.0f) {
		float3 to_centre = target - sh->p;
		float length2 = dot3(to_centre, to_centre);
		COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_DOT3);
		if (length2 == 0.0f)
			return false;
		COUNT_FLOPS(tr, 1 + FLOPS_MUL3);
		target += light_disk_offset(tr, sh, i, to_centre * rsqrt(length2), size);
		COUNT_FLOPS(tr, FLOPS_ADD3);
	}
	float3 to_light = target - sh->p;
	float distance2 = dot3(to_light, to_light);
	float inv_distance = rsqrt(distance2);
	*distance = distance2 * inv_distance;
	*l = to_light * inv_distance;
	/* to_light, distance2, rsqrt, distance, l */
	COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_DOT3 + 1 + 1 + FLOPS_MUL3);
	return true;
}
#endif

/* Moves on to the next light that needs a shadow ray: computes its
 * Blinn-Phong terms and returns true, or returns false when no light is left.
 * A light whose terms add nothing needs no shadow ray. d: the ray's direction. */
static bool shading_next_light(struct tracer *tr, struct shading *sh, float3 d)
{
#ifdef RTCL_NO_LIGHTS
	/* A scene without lights (the host builds it with RTCL_NO_LIGHTS): no
	 * light to take, so every shadow-ray path is left out of the program
	 * (1.07x on primary rays of meshes, docs/bvh.md). */
	(void)tr;
	(void)sh;
	(void)d;
	return false;
#endif
	while (sh->next_light < tr->scene->light_count) {
		int i = sh->next_light++;
		RTCL_SCENE_SPACE const struct rt_material *m = sh->m;
#ifdef RTCL_AREA_LIGHTS
		float3 l;
		float distance;
		if (!light_direction(tr, sh, i, &l, &distance))
			continue;
		float diffuse = m->diffuse * fmax(0.0f, dot3(sh->n, l));
		COUNT_FLOPS(tr, FLOPS_DOT3 + 2);
#else
		float3 to_light = tr->lights[i].position.xyz - sh->p;
		float distance2 = dot3(to_light, to_light);
		float inv_distance = rsqrt(distance2);
		float distance = distance2 * inv_distance;
		float3 l = to_light * inv_distance;
		float diffuse = m->diffuse * fmax(0.0f, dot3(sh->n, l));
		/* to_light, distance2, rsqrt, distance, l, diffuse */
		COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_DOT3 + 1 + 1 + FLOPS_MUL3 + FLOPS_DOT3 + 2);
#endif

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

#ifdef RTCL_FRESNEL
/* Schlick's (1 - c)^5 (RENDERING.md, "Fresnel"): 1 - c and four products. */
static inline float schlick_power(struct tracer *tr, float c)
{
	float x = 1.0f - c;

	COUNT_FLOPS(tr, 5);
	return x * x * x * x * x;
}

/* A Fresnel dielectric where the ray refracts: moves the share F of kt
 * that the surface reflects to *reflect_weight and leaves the rest in
 * *transmit_weight. c = -d·n; k as in the refraction (k >= 0). */
static void dielectric_fresnel(struct tracer *tr, RTCL_SCENE_SPACE const struct rt_material *m,
			       float eta, float c, float k, float *reflect_weight,
			       float *transmit_weight)
{
	float r0 = (m->ior - 1.0f) / (m->ior + 1.0f);

	r0 = r0 * r0;
	COUNT_FLOPS(tr, 4);
	if (eta > 1.0f) { /* leaving the denser side: the refracted ray's cosine */
		c = sqrt(k);
		COUNT_FLOPS(tr, 1);
	}
	float f = r0 + (1.0f - r0) * schlick_power(tr, c);
	*reflect_weight += f * m->transmit;
	*transmit_weight = (1.0f - f) * m->transmit;
	COUNT_FLOPS(tr, 3 + 4);
}

/* A Fresnel conductor's reflectance at the hit, a colour: the base colour
 * head-on, white at grazing angles. */
static float3 conductor_fresnel(struct tracer *tr, const struct shading *sh, float3 d)
{
	float power = schlick_power(tr, -dot3(d, sh->n));

	/* c; 1 - C, its product and the sum */
	COUNT_FLOPS(tr, FLOPS_DOT3 + 3 * FLOPS_ADD3);
	return sh->base + (1.0f - sh->base) * power;
}
#endif

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
	float reflect_weight = m->reflect, transmit_weight = m->transmit;
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
#ifdef RTCL_FRESNEL
			if (m->fresnel == RT_FRESNEL_DIELECTRIC)
				dielectric_fresnel(tr, m, eta, c, k, &reflect_weight,
						   &transmit_weight);
#endif
			float3 t_dir = normalize3(eta * ray->dir + (eta * c - sqrt(k)) * n);
			*refracted = (struct ray_job){sh->p - epsilon * sh->n_face, t_dir,
						      ray->weight * transmit_weight, ray->depth + 1};
			spawned |= SPAWNED_REFRACTED;
			/* t_dir before normalizing: eta d, eta c − sqrt(k) (3), × n, + */
			COUNT_FLOPS(tr, FLOPS_MUL3 + 3 + FLOPS_MUL3 + FLOPS_ADD3 +
						FLOPS_NORMALIZE3 + FLOPS_MUL3 + FLOPS_ADD3 +
						FLOPS_WEIGHT);
		}
	}
	if (reflect_weight > 0.0f) {
		float3 r_dir = normalize3(ray->dir - 2.0f * dot3(ray->dir, n) * n);
		ray_weight_t weight = ray->weight * reflect_weight;
#ifdef RTCL_FRESNEL
		if (m->fresnel == RT_FRESNEL_CONDUCTOR) {
			weight *= conductor_fresnel(tr, sh, ray->dir);
			COUNT_FLOPS(tr, FLOPS_MUL3);
		}
#endif
		*reflected = (struct ray_job){sh->p + epsilon * sh->n_face, r_dir, weight,
					      ray->depth + 1};
		spawned |= SPAWNED_REFLECTED;
		/* r_dir before normalizing: d·n, 2×, × n, d − */
		COUNT_FLOPS(tr, FLOPS_DOT3 + 1 + FLOPS_MUL3 + FLOPS_ADD3 + FLOPS_NORMALIZE3 +
					FLOPS_MUL3 + FLOPS_ADD3 + FLOPS_WEIGHT);
	}
	return spawned;
}
