/* The path integrator's lights (docs/RENDERING.md, "Lights and their
 * selection", "next_event"): the light groups (the scene's lights, the
 * emitters, the environment), a sample of one, and the pdf with which a
 * light found by a BSDF ray would have been sampled, for MIS. Part of the
 * tracer, only in programs built with RTCL_PATH: built after bsdf.cl. */
#ifdef RTCL_PATH

static inline float luminance(struct tracer *tr, float3 c)
{
	COUNT_FLOPS(tr, 5);
	return fma(0.0722f, c.z, fma(0.7152f, c.y, 0.2126f * c.x));
}

/* The power heuristic's weight of a strategy of density p against one of
 * density other, as 1 / (1 + (other/p)^2) so that no square overflows. */
static inline float mis_weight(struct tracer *tr, float p, float other)
{
	float r = other / p;

	COUNT_FLOPS(tr, 4);
	return 1.0f / (1.0f + r * r);
}

/* A light sample: the unit direction from the point lit, the largest t of
 * a hit that blocks it, what it brings over its pdf (E / p, a colour), and
 * p for MIS (0: a light no ray can find, weight 1). */
struct light_sample {
	float3 dir;
	float t_max;
	float3 radiance_over_pdf;
	float pdf;
	int sphere, triangle; /* the emitter sampled, which cannot block it; or -1 */
};

/* The direction of cone(w, c_max, s, t): uniform in the cone of cosine
 * c_max about unit w, whose solid angle is 2 pi one_minus_cmax. */
static float3 cone_direction(struct tracer *tr, float3 w, float one_minus_cmax, float2 st)
{
	struct frame f = frame_around(tr, w);
	float cos_theta = 1.0f - st.x * one_minus_cmax;
	float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
	float phi = 2.0f * M_PI_F * st.y;

	COUNT_FLOPS(tr, 2 + 4 + 2 + 2 + 2);
	return from_local(tr, &f, (float3)(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta));
}

/* 1 - cos(theta_max) of a sphere of radius r at distance d > r, written
 * sin^2 / (1 + cos) against cancellation; *sin2 the sine squared. */
static inline float sphere_cone(struct tracer *tr, float r, float d, float *sin2)
{
	*sin2 = (r * r) / (d * d);
	COUNT_FLOPS(tr, 3 + 4);
	return *sin2 / (1.0f + sqrt(fmax(0.0f, 1.0f - *sin2)));
}

/* Along dir from p, the distance to the near side of the sphere (c, r)
 * seen in it: D cos - sqrt(r^2 - D^2 sin^2). */
static inline float sphere_distance(struct tracer *tr, float3 p, float3 c, float r, float3 dir)
{
	float3 to_c = c - p;
	float along = dot3(to_c, dir);
	float d2 = dot3(to_c, to_c);

	COUNT_FLOPS(tr, FLOPS_ADD3 + 2 * FLOPS_DOT3 + 5);
	return along - sqrt(fmax(0.0f, r * r - (d2 - along * along)));
}

/* A sphere of radius r about c seen from p, sampled in its cone: false
 * from inside it. */
static bool sphere_sample(struct tracer *tr, float3 p, float3 c, float r, float2 st,
			  struct light_sample *ls, float *cone_pdf)
{
	float3 to_c = c - p;
	float d2 = dot3(to_c, to_c);
	float d = sqrt(d2), sin2;

	COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_DOT3 + 1);
	if (d <= r)
		return false;
	float one_minus = sphere_cone(tr, r, d, &sin2);
	COUNT_FLOPS(tr, FLOPS_MUL3 + 1);
	ls->dir = normalize3(cone_direction(tr, to_c * (1.0f / d), one_minus, st));
	ls->t_max = sphere_distance(tr, p, c, r, ls->dir);
	*cone_pdf = 1.0f / (2.0f * M_PI_F * one_minus);
	COUNT_FLOPS(tr, FLOPS_NORMALIZE3 + 3);
	return true;
}

/* Light i of the scene's lights (point, sphere, directional), p_group the
 * probability of its group. */
static bool scene_light_sample(struct tracer *tr, int i, float p_group, float3 p, float2 st,
			       struct light_sample *ls)
{
	float4 position = tr->lights[i].position;
	float3 color = tr->lights[i].color.xyz;
	float size = position.w; /* a sphere's radius, or tan of the angle */

	ls->pdf = 0.0f; /* no ray finds these lights: no MIS */
	if (tr->lights[i].color.w != 0.0f) { /* directional: xyz the unit way to it */
		ls->t_max = INFINITY;
		if (size == 0.0f) {
			ls->dir = position.xyz;
			ls->radiance_over_pdf = color / p_group;
			COUNT_FLOPS(tr, FLOPS_MUL3);
			return true;
		}
		float tan2 = size * size;
		float sin2 = tan2 / (1.0f + tan2);
		float one_minus = sin2 / (1.0f + rsqrt(1.0f + tan2));
		ls->dir = normalize3(cone_direction(tr, position.xyz, one_minus, st));
		/* E0 / (pi sin^2) over (p_group / (2 pi (1 - cos))) */
		ls->radiance_over_pdf = color * (2.0f * one_minus / (sin2 * p_group));
		COUNT_FLOPS(tr, 1 + 2 + 4 + FLOPS_NORMALIZE3 + 4 + FLOPS_MUL3);
		return true;
	}
	if (size == 0.0f) { /* a point: I / dist^2, a delta */
		float3 to_light = position.xyz - p;
		float dist2 = dot3(to_light, to_light);
		float inv = rsqrt(dist2);
		ls->dir = to_light * inv;
		ls->t_max = dist2 * inv;
		ls->radiance_over_pdf = color / (dist2 * p_group);
		COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_DOT3 + 1 + FLOPS_MUL3 + 1 + 1 + FLOPS_MUL3);
		return dist2 > 0.0f;
	}
	float cone_pdf;
	if (!sphere_sample(tr, p, position.xyz, size, st, ls, &cone_pdf))
		return false;
	/* radiance I / (pi R^2) over p_group cone_pdf */
	ls->radiance_over_pdf = color * (1.0f / (M_PI_F * size * size * p_group * cone_pdf));
	COUNT_FLOPS(tr, 5 + FLOPS_MUL3);
	return true;
}

/* Emitter e's material's emission. */
static inline float3 emitter_emission(struct tracer *tr, int material)
{
	return tr->bsdfs[material].emission.xyz;
}

/* A triangle's vertices, its unnormalised normal (v1 - v0) x (v2 - v0). */
static float3 triangle_cross(struct tracer *tr, uint4 index, float3 *v0, float3 *v1, float3 *v2)
{
	*v0 = tr->vertices[index.x].position.xyz;
	*v1 = tr->vertices[index.y].position.xyz;
	*v2 = tr->vertices[index.z].position.xyz;
	COUNT_FLOPS(tr, 2 * FLOPS_ADD3 + FLOPS_CROSS3);
	return cross3(*v1 - *v0, *v2 - *v0);
}

/* The emitter chosen by t among the emitters (the first whose cdf exceeds
 * t), sampled from p. p_group: the emitters group's probability. */
static bool emitter_sample(struct tracer *tr, float p_group, float t, float3 p, float2 st,
			   struct hit at, struct light_sample *ls)
{
	RTCL_SCENE_SPACE const struct rt_path *path = tr->path;
	int lo = 0, hi = path->emitter_count - 1;

	while (lo < hi) {
		int mid = (lo + hi) / 2;
		if (t < tr->emitters[mid].cdf)
			hi = mid;
		else
			lo = mid + 1;
	}
	uint prim = tr->emitters[lo].prim;
	int index = (int)(prim & RT_PRIM_INDEX_MASK);
	float3 le;
	/* An emitter is no light at its own points: none of it is seen from
	   its surface, which rounding could decide otherwise. */
	if (prim >> RT_PRIM_KIND_SHIFT == RT_PRIM_SPHERE ? index == at.sphere
							   : index == at.triangle)
		return false;
	if (prim >> RT_PRIM_KIND_SHIFT == RT_PRIM_SPHERE) {
		ls->sphere = index;
		RTCL_SCENE_SPACE const struct rt_sphere *s = &tr->spheres[index];
		float cone_pdf;
		if (!sphere_sample(tr, p, s->center.xyz, s->radius, st, ls, &cone_pdf))
			return false;
		le = emitter_emission(tr, s->material);
		float p_e = luminance(tr, le) * 4.0f * M_PI_F * s->radius * s->radius *
			    path->inv_emitter_weight;
		ls->pdf = p_group * p_e * cone_pdf;
		ls->t_max -= 2.0f * scene_epsilon(tr->scene); /* not the emitter itself */
		COUNT_FLOPS(tr, 5 + 2 + 2);
	} else {
		ls->triangle = index;
		uint4 tri = tr->triangles[index].index;
		float3 v0, v1, v2;
		float3 c = triangle_cross(tr, tri, &v0, &v1, &v2);
		float r = sqrt(st.x);
		float3 y = (1.0f - r) * v0 + (r * (1.0f - st.y)) * v1 + (r * st.y) * v2;
		float3 to_y = y - p;
		float dist2 = dot3(to_y, to_y);
		float inv = rsqrt(dist2);
		float cross_len = sqrt(dot3(c, c));
		ls->dir = to_y * inv;
		/* the cosine at y: -dir . n_e, n_e = c / |c| */
		float cos_l = -dot3(ls->dir, c) / cross_len;
		COUNT_FLOPS(tr, 1 + 4 + 3 * FLOPS_MUL3 + 2 * FLOPS_ADD3 + FLOPS_ADD3 + FLOPS_DOT3 +
					1 + FLOPS_DOT3 + 1 + FLOPS_MUL3 + FLOPS_DOT3 + 1);
		if (!(cos_l > 0.0f) || !(dist2 > 0.0f))
			return false;
		le = emitter_emission(tr, triangle_material(tri));
		/* P_e pdf_e = lum area / W * dist^2 / (area cos): the area cancels */
		ls->pdf = p_group * luminance(tr, le) * path->inv_emitter_weight * dist2 / cos_l;
#ifdef RTCL_TEXTURES
		int texture = tr->bsdfs[triangle_material(tri)].emissive_texture;
		if (texture >= 0) { /* at y, of barycentric (r (1 - t), r t) */
			float2 uv = triangle_uv(tr, tri, (float2)(r * (1.0f - st.y), r * st.y));
			le *= texture_lookup(tr, texture, uv).xyz;
			COUNT_FLOPS(tr, 3 + FLOPS_MUL3);
		}
#endif
		ls->t_max = dist2 * inv - 2.0f * scene_epsilon(tr->scene);
		COUNT_FLOPS(tr, 4 + 3);
	}
	ls->radiance_over_pdf = le / ls->pdf;
	COUNT_FLOPS(tr, FLOPS_MUL3);
	return ls->pdf > 0.0f;
}

/* The environment map (RENDERING.md, "The environment"): its arrays. */
static inline RTCL_SCENE_SPACE const float4 *env_texels(struct tracer *tr)
{
	return (RTCL_SCENE_SPACE const float4 *)((RTCL_SCENE_SPACE const uchar *)tr->scene +
						  tr->path->env_texel_offset);
}

static inline RTCL_SCENE_SPACE const float *env_cdf(struct tracer *tr, uint offset)
{
	return (RTCL_SCENE_SPACE const float *)((RTCL_SCENE_SPACE const uchar *)tr->scene + offset);
}

/* The weight of texel (j, k) over the sum of them all, times W H. */
static inline float env_texel_density(struct tracer *tr, float3 radiance, int k)
{
	RTCL_SCENE_SPACE const struct rt_path *path = tr->path;
	float sin_row = sin(M_PI_F * ((float)k + 0.5f) / (float)path->env_height);

	COUNT_FLOPS(tr, 4 + 3);
	return luminance(tr, radiance) * sin_row * path->env_inv_weight *
	       (float)(path->env_width * path->env_height);
}

/* The map's direction of (u, v), turned about +y. */
static float3 env_direction(struct tracer *tr, float u, float v, float *sin_theta)
{
	RTCL_SCENE_SPACE const struct rt_path *path = tr->path;
	float theta = M_PI_F * v, phi = 2.0f * M_PI_F * u;
	float st = sin(theta);
	float3 d0 = (float3)(-st * sin(phi), cos(theta), st * cos(phi));

	*sin_theta = st;
	COUNT_FLOPS(tr, 3 + 5 + 2 + 6);
	return (float3)(d0.x * path->env_cos + d0.z * path->env_sin, d0.y,
			-d0.x * path->env_sin + d0.z * path->env_cos);
}

/* The texel direction d falls in (*j, *k), and sin(theta) of d. */
static void env_texel_of(struct tracer *tr, float3 d, int *j, int *k, float *sin_theta)
{
	RTCL_SCENE_SPACE const struct rt_path *path = tr->path;
	float x0 = d.x * path->env_cos - d.z * path->env_sin;
	float z0 = d.x * path->env_sin + d.z * path->env_cos;
	float y0 = clamp(d.y, -1.0f, 1.0f);
	float phi = atan2(-x0, z0);

	if (phi < 0.0f)
		phi += 2.0f * M_PI_F;
	*sin_theta = sqrt(fmax(0.0f, 1.0f - y0 * y0));
	*j = min(path->env_width - 1, (int)floor((float)path->env_width * phi / (2.0f * M_PI_F)));
	*k = min(path->env_height - 1, (int)floor((float)path->env_height * acos(y0) / M_PI_F));
	*j = max(*j, 0);
	*k = max(*k, 0);
	COUNT_FLOPS(tr, 6 + 2 + 1 + 4 + 3 + 4);
}

/* The radiance of a ray leaving the scene along d, and *pdf, the density
 * (selection included) with which next_event samples d; 0 where the
 * environment is not a light. */
static float3 environment_radiance(struct tracer *tr, float3 d, float *pdf)
{
	RTCL_SCENE_SPACE const struct rt_path *path = tr->path;
	float p_group = path->env_is_light ? 1.0f / (float)path->group_count : 0.0f;

	COUNT_FLOPS(tr, 1);
	if (path->environment != RT_ENVIRONMENT_MAP) {
		*pdf = p_group * (0.25f * M_1_PI_F);
		COUNT_FLOPS(tr, 1);
		return tr->scene->background.xyz;
	}
	int j, k;
	float sin_theta;
	env_texel_of(tr, d, &j, &k, &sin_theta);
	float3 radiance = env_texels(tr)[k * path->env_width + j].xyz;
	*pdf = sin_theta > 0.0f ? p_group * env_texel_density(tr, radiance, k) /
					  (2.0f * M_PI_F * M_PI_F * sin_theta)
				: 0.0f;
	COUNT_FLOPS(tr, 4);
	return radiance;
}

/* The first index i of cdf[0 .. n) with x < cdf[i] (the last is 1), and
 * where x lies within its interval, in [0, 1). */
static int cdf_find(RTCL_SCENE_SPACE const float *cdf, int n, float x, float *within)
{
	int lo = 0, hi = n - 1;

	while (lo < hi) {
		int mid = (lo + hi) / 2;
		if (x < cdf[mid])
			hi = mid;
		else
			lo = mid + 1;
	}
	float before = lo > 0 ? cdf[lo - 1] : 0.0f;
	float width = cdf[lo] - before;
	*within = width > 0.0f ? fmin((x - before) / width, 0x1.fffffep-1f) : 0.5f;
	return lo;
}

/* The environment's sample: uniform on the sphere of directions (pdf
 * 1/(4 pi)), or the map's by its weights. */
static bool environment_sample(struct tracer *tr, float p_group, float2 st,
			       struct light_sample *ls)
{
	RTCL_SCENE_SPACE const struct rt_path *path = tr->path;

	ls->t_max = INFINITY;
	if (path->environment != RT_ENVIRONMENT_MAP) {
		float z = 1.0f - 2.0f * st.x;
		float r = sqrt(fmax(0.0f, 1.0f - z * z));
		float phi = 2.0f * M_PI_F * st.y;

		ls->dir = (float3)(r * cos(phi), r * sin(phi), z);
		ls->pdf = p_group * (0.25f * M_1_PI_F);
		ls->radiance_over_pdf = tr->scene->background.xyz / ls->pdf;
		COUNT_FLOPS(tr, 2 + 4 + 2 + 4 + 2 + FLOPS_MUL3);
		return true;
	}
	float in_row, in_column, sin_theta;
	int w = path->env_width, h = path->env_height;
	int k = cdf_find(env_cdf(tr, path->env_row_cdf_offset), h, st.y, &in_row);
	int j = cdf_find(env_cdf(tr, path->env_column_cdf_offset) + k * w, w, st.x, &in_column);
	float u = ((float)j + in_column) / (float)w, v = ((float)k + in_row) / (float)h;
	ls->dir = env_direction(tr, u, v, &sin_theta);
	float3 radiance = env_texels(tr)[k * w + j].xyz;
	ls->pdf = p_group * env_texel_density(tr, radiance, k) / (2.0f * M_PI_F * M_PI_F * sin_theta);
	ls->radiance_over_pdf = radiance / ls->pdf;
	COUNT_FLOPS(tr, 6 + 4 + 4 + 4 + FLOPS_MUL3);
	return sin_theta > 0.0f && ls->pdf > 0.0f;
}

/* next_event's light: group g of the scene's, then the emitters' choice t
 * and the point st on the light, seen from p, the point of hit at. False:
 * none. */
static bool light_sample(struct tracer *tr, uint g, float t, float2 st, float3 p, struct hit at,
			 struct light_sample *ls)
{
	int lights = tr->scene->light_count;
	float p_group = 1.0f / (float)tr->path->group_count;

	COUNT_FLOPS(tr, 1);
	ls->sphere = ls->triangle = -1;
	if ((int)g < lights)
		return scene_light_sample(tr, (int)g, p_group, p, st, ls);
	if ((int)g == lights && tr->path->emitter_count > 0)
		return emitter_sample(tr, p_group, t, p, st, at, ls);
	return environment_sample(tr, p_group, st, ls);
}

/* The light pdf (selection included) with which next_event would have
 * sampled the emitter hit at y, seen from x: for MIS of a BSDF ray's hit. */
static float emitter_pdf(struct tracer *tr, struct hit hit, float3 x, float3 y, float3 le)
{
	RTCL_SCENE_SPACE const struct rt_path *path = tr->path;
	float p_group = 1.0f / (float)path->group_count;
	float p_e = luminance(tr, le) * path->inv_emitter_weight;

	COUNT_FLOPS(tr, 2);
	if (hit.sphere >= 0) {
		RTCL_SCENE_SPACE const struct rt_sphere *s = &tr->spheres[hit.sphere];
		float3 to_c = s->center.xyz - x;
		float d = sqrt(dot3(to_c, to_c)), sin2;
		COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_DOT3 + 1);
		if (d <= s->radius)
			return 0.0f;
		float one_minus = sphere_cone(tr, s->radius, d, &sin2);
		COUNT_FLOPS(tr, 5 + 4);
		return p_group * p_e * 4.0f * M_PI_F * s->radius * s->radius /
		       (2.0f * M_PI_F * one_minus);
	}
	if (hit.triangle < 0)
		return 0.0f; /* a plane: not a light */
	float3 v0, v1, v2;
	float3 c = triangle_cross(tr, tr->triangles[hit.triangle].index, &v0, &v1, &v2);
	float3 to_y = y - x;
	float dist2 = dot3(to_y, to_y);
	float cos_l = fabs(dot3(to_y, c)) * rsqrt(dist2 * dot3(c, c));
	COUNT_FLOPS(tr, FLOPS_ADD3 + 3 * FLOPS_DOT3 + 2 + 3);
	return cos_l > 0.0f ? p_group * p_e * dist2 / cos_l : 0.0f;
}

#endif
