/* The tracer: what a pixel is (docs/RENDERING.md), written once and used by
 * every scheduling kernel. OpenCL C 1.2.
 *
 * The tracer is twelve files, built in this order before the kernel file
 * (host/render/program.c lists them) and read best in the same order:
 *   tracer.cl      counting, the scene as the tracer sees it, vector helpers
 *   sample.cl      where a pixel's samples lie
 *   texture.cl     texture lookups and alpha cut-outs (RTCL_TEXTURES)
 *   intersect.cl   the nearest (or any) hit over spheres, triangles and planes
 *   traverse.cl    the same over the spheres and triangles through the BVH
 *                  (RTCL_BVH)
 *   shade.cl       the base colour, lights and shadow rays, spawned rays
 *   walk.cl        ray_step, one ray by one intersection; the Whitted walk;
 *                  primary rays
 *   bsdf.cl        the path integrator's BSDFs (RTCL_PATH; empty without)
 *   light.cl       its lights: choosing one, sampling it, its pdf (RTCL_PATH)
 *   path.cl        its walk: a path, one intersection at a time (RTCL_PATH)
 *   pixel.cl       a pixel's samples walked and summed (render_pixel)
 *   scheduling.cl  what the scheduling kernels share: scene loading, counts,
 *                  the chunk grid over the piece being rendered
 * host/render/reference.cpp computes the same model in double precision, written
 * independently from RENDERING.md: it is the readable version of it.
 *
 * Build-time options, set by the host (host/render/program.c):
 *   RTCL_MAX_DEPTH      the scene's max_depth; sizes the ray stack (0 under
 *                       RTCL_PATH, whose paths need none)
 *   RTCL_SCENE_IN_LOCAL copy the scene into __local memory per work-group;
 *                       without it the tracer reads it from __global memory
 *   RTCL_BVH            find sphere hits through the scene's BVH rather than
 *                       by testing every sphere (--accel bvh)
 *   RTCL_TEXTURES       a material has a texture or an alpha cut-out
 *   RTCL_COUNT_FLOPS    count floating-point operations, rays and BVH node
 *                       visits per work-item
 *   RTCL_COUNT_WRITES   count writes per pixel (tests only)
 *   RTCL_PATH           the path integrator (RENDERING.md, "Path tracing")
 *                       instead of Whitted's trace
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

/* The host builds scenes without triangles with RTCL_NO_TRIANGLES: leaving
 * the triangle code out frees registers (on an H100 the sphere scenes spilled
 * 140 bytes with it, docs/performance.md). Nothing else changes: without
 * triangles that code never runs. */
#ifdef RTCL_NO_TRIANGLES
#define SCENE_HAS_TRIANGLES false
#else
#define SCENE_HAS_TRIANGLES true
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
#define COUNT_NODE_VISIT(tr) ((tr)->node_visits++)
#define COUNT_LEAF_VISIT(tr) ((tr)->leaf_visits++)
#define COUNT_PRIM_TEST(tr) ((tr)->prim_tests++)
#else
#define COUNT_FLOPS(tr, n) ((void)0)
#define COUNT_RAY(tr) ((void)0)
#define COUNT_NODE_VISIT(tr) ((void)0)
#define COUNT_LEAF_VISIT(tr) ((void)0)
#define COUNT_PRIM_TEST(tr) ((void)0)
#endif

/* SIMD efficiency, measured (RTCL_SIMD_MEASURE: the counting build on an
 * NVIDIA device, whose OpenCL takes inline PTX): at each step of a phase,
 * the work-item counts the step, and the lowest active lane of its warp
 * (activemask, laneid) counts one warp-step for the warp; over every
 * work-item, steps / (32 × warp-steps) is the phase's SIMD efficiency. */
#ifdef RTCL_SIMD_MEASURE
#define SIMD_STEP(tr, phase) simd_step((tr)->lane_steps + (phase), (tr)->warp_steps + (phase))
static inline void simd_step(ulong *lane_steps, ulong *warp_steps)
{
	uint mask, lane;

	__asm__ volatile("activemask.b32 %0;" : "=r"(mask));
	__asm__ volatile("mov.u32 %0, %%laneid;" : "=r"(lane));
	*lane_steps += 1;
	if ((mask & ((1u << lane) - 1u)) == 0u)
		*warp_steps += 1;
}
#else
#define SIMD_STEP(tr, phase) ((void)0)
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
/* cross3: per component a product and an fma, 9. */
#define FLOPS_CROSS3 (3 * (1 + FLOPS_FMA))
/* triangle_hit (Moller-Trumbore) in stages, each counted when reached:
 * e1 = v1 − v0, e2 = v2 − v0, p = d × e2 and det = e1·p, 20; then 1/det,
 * s = o − v0, u = (s·p)/det, 10 more; then q = s × e1, v = (d·q)/det and
 * u + v, 16 more; then t = (e2·q)/det, 6 more: a ray that reaches t costs 52. */
#define FLOPS_TRIANGLE_DET (2 * FLOPS_ADD3 + FLOPS_CROSS3 + FLOPS_DOT3)
#define FLOPS_TRIANGLE_U (1 + FLOPS_ADD3 + FLOPS_DOT3 + 1)
#define FLOPS_TRIANGLE_V (FLOPS_CROSS3 + FLOPS_DOT3 + 1 + 1)
#define FLOPS_TRIANGLE_T (FLOPS_DOT3 + 1)
/* triangle_normal: the edges (6), their cross product (9) and its largest
 * component in size (2 maxima), 17; then, unless that is 0, the scaling by
 * its reciprocal (1 + 3) and the normalisation (9), 13 more: 30. */
#define FLOPS_TRIANGLE_CROSS (2 * FLOPS_ADD3 + FLOPS_CROSS3 + 2)
/* The BVH's per-ray set-up: 1/d, three divisions, and o/d, three products. */
#define FLOPS_BOX_SETUP (3 + FLOPS_MUL3)
/* box_hit, one box: six slab fmas, a min and a max per axis, the entry as
 * the max of three and 0, the exit as the min of three and the nearest hit
 * so far: 12 + 6 + 3 + 3 = 24. */
#define FLOPS_BOX_TEST (6 * FLOPS_FMA + 6 + 3 + 3)

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
	RTCL_SCENE_SPACE const struct rt_triangle *triangles;
	RTCL_SCENE_SPACE const struct rt_vertex *vertices;
	RTCL_SCENE_SPACE const struct rt_vertex_normal *normals;
#ifdef RTCL_BVH4
	RTCL_SCENE_SPACE const struct rt_bvh4_node *nodes; /* four-wide: a CPU's */
#else
	RTCL_SCENE_SPACE const struct rt_bvh_node *nodes;
#endif
	RTCL_SCENE_SPACE const uint *refs; /* the BVH leaves' primitives (RT_PRIM_*) */
	RTCL_SCENE_SPACE const struct rt_leaf_triangle *leaf_triangles; /* RT_LEAF_TRIANGLES */
#ifdef RTCL_TEXTURES
	RTCL_SCENE_SPACE const struct rt_vertex_uv *uvs;
	RTCL_SCENE_SPACE const struct rt_material_map *material_maps;
	RTCL_SCENE_SPACE const struct rt_texture *textures;
	RTCL_SCENE_SPACE const float *texture_table; /* RT_TEXTURE_TABLE */
#endif
#ifdef RTCL_PATH
	/* The emitter a shadow ray goes to, which does not block it
	   (RENDERING.md, "next_event"): a device sphere, a triangle, or -1. */
	int skip_sphere, skip_triangle;
	RTCL_SCENE_SPACE const struct rt_path *path;
	RTCL_SCENE_SPACE const struct rt_bsdf *bsdfs;	    /* one per material */
	RTCL_SCENE_SPACE const struct rt_emitter *emitters; /* path->emitter_count */
#endif
	__global ulong *item_counts;	   /* RT_ITEM_COUNTS per work-item, when counting */
	__global ulong *pixel_flops;	   /* flops spent on each pixel, when counting */
#ifdef RTCL_COUNT_FLOPS
	ulong flops;
	ulong rays;	   /* primary, secondary and shadow rays traced */
	ulong node_visits; /* BVH nodes visited, every ray's */
	ulong leaf_visits; /* BVH leaves visited, every ray's */
	ulong prim_tests;  /* spheres and triangles tested in the leaves visited */
#endif
#ifdef RTCL_SIMD_MEASURE
	ulong lane_steps[RT_SIMD_PHASES]; /* steps this work-item took */
	ulong warp_steps[RT_SIMD_PHASES]; /* of them, those it led for its warp */
#endif
#if defined(RTCL_COUNT_FLOPS) && defined(RTCL_PATH)
	ulong path_lengths[RT_PATH_LENGTH_BINS]; /* paths ended, by segments (RT_ITEM_PATH_*) */
	ulong path_max, path_segments;		 /* the longest's segments; their sum */
#endif
#if defined(RTCL_AREA_LIGHTS) || defined(RTCL_PATH)
	/* The sample being traced, whose further pairs place the light samples
	   and the path's bounces (tracer_set_sample). */
	int pixel_x, pixel_y;
	uint sample, samples;
#endif
};

/* A ray's weight, the product of the kr and kt along its path: a colour
 * where a Fresnel conductor tints reflections (RTCL_FRESNEL), else a number,
 * as before Fresnel existed. A product with a weight counts FLOPS_WEIGHT. */
#ifdef RTCL_FRESNEL
typedef float3 ray_weight_t;
#define FLOPS_WEIGHT 3
#else
typedef float ray_weight_t;
#define FLOPS_WEIGHT 1
#endif

struct ray_job {
	float3 origin;
	float3 dir; /* unit length */
	ray_weight_t weight;
	int depth;
};

struct hit {
	float t;
	int sphere;   /* index of the sphere hit, or -1 */
	int plane;    /* index of the plane hit, or -1 */
	int triangle; /* index of the triangle hit, or -1 */
	float u, v;   /* on a triangle: the barycentric coordinates of v1 and v2 */
};

/* Vector helpers, written out so that each operation is what is counted. */
static inline float dot3(float3 a, float3 b)
{
	return fma(a.z, b.z, fma(a.y, b.y, a.x * b.x));
}

/* a × b, counted FLOPS_CROSS3: each component a product and an fma. */
static inline float3 cross3(float3 a, float3 b)
{
	return (float3)(fma(a.y, b.z, -(a.z * b.y)), fma(a.z, b.x, -(a.x * b.z)),
			fma(a.x, b.y, -(a.y * b.x)));
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

/* Counts, when counting: item_counts per launched work-item (RT_ITEM_COUNTS:
 * flops, rays, BVH node visits),
 * row-major over the global NDRange; pixel_flops per pixel of the image, added
 * to by every piece and pass that traces the pixel. */
static void tracer_init(struct tracer *tr, scene_ptr scene, __global ulong *item_counts,
			__global ulong *pixel_flops)
{
	RTCL_SCENE_SPACE const uchar *base = (RTCL_SCENE_SPACE const uchar *)scene;

	tr->scene = scene;
	tr->materials =
		(RTCL_SCENE_SPACE const struct rt_material *)(base + scene->material_offset);
	tr->spheres = (RTCL_SCENE_SPACE const struct rt_sphere *)(base + scene->sphere_offset);
	tr->planes = (RTCL_SCENE_SPACE const struct rt_plane *)(base + scene->plane_offset);
	tr->lights = (RTCL_SCENE_SPACE const struct rt_light *)(base + scene->light_offset);
	tr->triangles =
		(RTCL_SCENE_SPACE const struct rt_triangle *)(base + scene->triangle_offset);
	tr->vertices = (RTCL_SCENE_SPACE const struct rt_vertex *)(base + scene->vertex_offset);
	tr->normals =
		(RTCL_SCENE_SPACE const struct rt_vertex_normal *)(base + scene->normal_offset);
#ifdef RTCL_BVH4
	tr->nodes = (RTCL_SCENE_SPACE const struct rt_bvh4_node *)(base + scene->bvh_node_offset);
#else
	tr->nodes = (RTCL_SCENE_SPACE const struct rt_bvh_node *)(base + scene->bvh_node_offset);
#endif
	tr->refs = (RTCL_SCENE_SPACE const uint *)(base + scene->bvh_ref_offset);
	tr->leaf_triangles =
		(RTCL_SCENE_SPACE const struct rt_leaf_triangle *)(base + scene->bvh_triangle_offset);
#ifdef RTCL_TEXTURES
	tr->uvs = (RTCL_SCENE_SPACE const struct rt_vertex_uv *)(base + scene->uv_offset);
	tr->material_maps =
		(RTCL_SCENE_SPACE const struct rt_material_map *)(base + scene->material_map_offset);
	tr->textures = (RTCL_SCENE_SPACE const struct rt_texture *)(base + scene->texture_offset);
	tr->texture_table = (RTCL_SCENE_SPACE const float *)(base + scene->texture_table_offset);
#endif
#ifdef RTCL_PATH
	tr->skip_sphere = tr->skip_triangle = -1;
	tr->path = (RTCL_SCENE_SPACE const struct rt_path *)(base + scene->path_offset);
	tr->bsdfs = (RTCL_SCENE_SPACE const struct rt_bsdf *)(base + tr->path->bsdf_offset);
	tr->emitters = (RTCL_SCENE_SPACE const struct rt_emitter *)(base + tr->path->emitter_offset);
#endif
	tr->item_counts = item_counts;
	tr->pixel_flops = pixel_flops;
#ifdef RTCL_COUNT_FLOPS
	tr->flops = 0;
	tr->rays = 0;
	tr->node_visits = 0;
	tr->leaf_visits = 0;
	tr->prim_tests = 0;
#endif
#ifdef RTCL_SIMD_MEASURE
	for (int p = 0; p < RT_SIMD_PHASES; p++)
		tr->lane_steps[p] = tr->warp_steps[p] = 0;
#endif
#if defined(RTCL_COUNT_FLOPS) && defined(RTCL_PATH)
	for (int b = 0; b < RT_PATH_LENGTH_BINS; b++)
		tr->path_lengths[b] = 0;
	tr->path_max = tr->path_segments = 0;
#endif
}

/* Whether the shadow ray being traced ignores device sphere i or triangle
 * i: its own emitter, under the path integrator. */
static inline bool shadow_skips_sphere(const struct tracer *tr, int i)
{
#ifdef RTCL_PATH
	return i == tr->skip_sphere;
#else
	(void)tr;
	(void)i;
	return false;
#endif
}

static inline bool shadow_skips_triangle(const struct tracer *tr, int i)
{
#ifdef RTCL_PATH
	return i == tr->skip_triangle;
#else
	(void)tr;
	(void)i;
	return false;
#endif
}

/* Sets the sample being traced: sample k of n of pixel (x, y). Only the
 * light samples need it (RTCL_AREA_LIGHTS). */
static inline void tracer_set_sample(struct tracer *tr, int x, int y, uint k, uint n)
{
#if defined(RTCL_AREA_LIGHTS) || defined(RTCL_PATH)
	tr->pixel_x = x;
	tr->pixel_y = y;
	tr->sample = k;
	tr->samples = n;
#else
	(void)tr;
	(void)x;
	(void)y;
	(void)k;
	(void)n;
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
