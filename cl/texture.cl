/* Textures and alpha cut-outs (docs/RENDERING.md, "Textures" and "Alpha
 * cut-out"): a triangle hit's texture coordinates, a bilinear texture
 * lookup and the cut-out test. Part of the tracer: built after sample.cl,
 * before intersect.cl, whose triangle tests ask triangle_cut_out; all of it
 * only in programs built with RTCL_TEXTURES (a scene whose materials have a
 * texture or a cut-out), so that other scenes build the program of before. */
#ifdef RTCL_TEXTURES

/* uv = w·uv0 + u·uv1 + v·uv2, w = 1 − u − v, at the barycentric (u, v) of a
 * hit of the triangle whose vertex indices are index: 2 + 6 products + 4
 * sums, 12. */
#define FLOPS_TRIANGLE_UV 12
/* A lookup: x (2), y (3), fx and fy (2), three lerps of 3 on 4 channels (36). */
#define FLOPS_TEXTURE_LOOKUP 43
/* The texels' coordinates are clamped to ±2^24 before floor (exact integers
 * in float; their wrapped indices fit an int). */
#define TEXTURE_COORD_MAX 0x1p24f

static float2 triangle_uv(struct tracer *tr, uint4 index, float2 barycentric)
{
	RTCL_SCENE_SPACE const struct rt_vertex_uv *uvs = tr->uvs;
	float w = 1.0f - barycentric.x - barycentric.y;
	float2 uv0 = (float2)(uvs[index.x].u, uvs[index.x].v);
	float2 uv1 = (float2)(uvs[index.y].u, uvs[index.y].v);
	float2 uv2 = (float2)(uvs[index.z].u, uvs[index.z].v);

	COUNT_FLOPS(tr, FLOPS_TRIANGLE_UV);
	return w * uv0 + barycentric.x * uv1 + barycentric.y * uv2;
}

/* Index k of an axis of n texels under the wrap mode (integer work). */
static int texture_wrap(int k, int n, uint mode)
{
	if (mode == RT_WRAP_CLAMP)
		return clamp(k, 0, n - 1);
	if (mode == RT_WRAP_MIRROR) {
		int m = k % (2 * n);
		m = m < 0 ? m + 2 * n : m;
		return m < n ? m : 2 * n - 1 - m;
	}
	int m = k % n;
	return m < 0 ? m + n : m;
}

/* Texel (i, j) of the texture, linear RGBA: 8-bit ones through the decode
 * table (sRGB for RGB, i/255 for alpha), float ones as they are. */
static float4 texture_texel(struct tracer *tr, RTCL_SCENE_SPACE const struct rt_texture *tex,
			    int i, int j)
{
	RTCL_SCENE_SPACE const uchar *base = (RTCL_SCENE_SPACE const uchar *)tr->scene;
	size_t at = (size_t)j * (size_t)tex->width + (size_t)i;

	if (tex->flags & RT_TEXTURE_FLOAT)
		return vload4(at, (RTCL_SCENE_SPACE const float *)(base + tex->offset));
	uchar4 c = vload4(at, base + tex->offset);
	RTCL_SCENE_SPACE const float *table = tr->texture_table;
	RTCL_SCENE_SPACE const float *rgb = table + (tex->flags & RT_TEXTURE_LINEAR ? 256 : 0);
	return (float4)(rgb[c.x], rgb[c.y], rgb[c.z], table[256 + c.w]);
}

/* a + f·(b − a), per channel, each product and sum rounded. */
static inline float4 texture_lerp(float4 a, float4 b, float f)
{
	return a + f * (b - a);
}

/* Texture t at uv, bilinear with texel centres at half-integers. */
static float4 texture_lookup(struct tracer *tr, int t, float2 uv)
{
	RTCL_SCENE_SPACE const struct rt_texture *tex = &tr->textures[t];
	int w = tex->width, h = tex->height;
	uint wrap_s = tex->flags & RT_WRAP_MASK, wrap_t = (tex->flags >> RT_WRAP_T_SHIFT) & RT_WRAP_MASK;
	float x = uv.x * (float)w - 0.5f;
	float y = (1.0f - uv.y) * (float)h - 0.5f;

	/* Comparisons, 0 flops; NaN goes to the low end. */
	x = x >= -TEXTURE_COORD_MAX ? x : -TEXTURE_COORD_MAX;
	x = x <= TEXTURE_COORD_MAX ? x : TEXTURE_COORD_MAX;
	y = y >= -TEXTURE_COORD_MAX ? y : -TEXTURE_COORD_MAX;
	y = y <= TEXTURE_COORD_MAX ? y : TEXTURE_COORD_MAX;
	float fi = floor(x), fj = floor(y);
	float fx = x - fi, fy = y - fj;
	int i = (int)fi, j = (int)fj;
	int i0 = texture_wrap(i, w, wrap_s), i1 = texture_wrap(i + 1, w, wrap_s);
	int j0 = texture_wrap(j, h, wrap_t), j1 = texture_wrap(j + 1, h, wrap_t);
	float4 top = texture_lerp(texture_texel(tr, tex, i0, j0), texture_texel(tr, tex, i1, j0), fx);
	float4 bottom =
		texture_lerp(texture_texel(tr, tex, i0, j1), texture_texel(tr, tex, i1, j1), fx);

	COUNT_FLOPS(tr, FLOPS_TEXTURE_LOOKUP);
	return texture_lerp(top, bottom, fy);
}

/* Whether triangle i's material cuts it out where a ray meets it at the
 * barycentric uv: its alpha there below its cutoff. */
static bool triangle_cut_out(struct tracer *tr, int i, float2 uv)
{
	uint4 index = tr->triangles[i].index;
	RTCL_SCENE_SPACE const struct rt_material_map *map =
		&tr->material_maps[triangle_material(index)];
	float cutoff = map->alpha_cutoff;

	if (!(cutoff > 0.0f))
		return false;
	float alpha = map->alpha_scale;
	int t = map->alpha_texture;
	if (t >= 0) {
		alpha *= texture_lookup(tr, t, triangle_uv(tr, index, uv)).w;
		COUNT_FLOPS(tr, 1);
	}
	return alpha < cutoff;
}

/* The base colour of a hit of the triangle whose vertex indices are index
 * (its material's colour, given): times the material's texture at the hit. */
static float3 triangle_base_color(struct tracer *tr, uint4 index, float2 barycentric,
				  float3 color)
{
	int t = tr->material_maps[triangle_material(index)].texture;

	if (t < 0)
		return color;
	COUNT_FLOPS(tr, FLOPS_MUL3);
	return color * texture_lookup(tr, t, triangle_uv(tr, index, barycentric)).xyz;
}

#else

static inline bool triangle_cut_out(struct tracer *tr, int i, float2 uv)
{
	(void)tr;
	(void)i;
	(void)uv;
	return false;
}

#endif
