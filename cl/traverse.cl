/* BVH traversal (docs/bvh.md): the spheres' and triangles' part of
 * intersect_scene through the one hierarchy the host built (host/layout/bvh.c), when
 * built with RTCL_BVH. Part of the tracer: built after intersect.cl, whose
 * sphere and triangle tests it uses. Planes, unbounded, stay outside the
 * hierarchy and are tested by intersect_scene as before. */
#ifdef RTCL_BVH

#if RT_BVH_MAX_DEPTH > 64
#error "the traversal stack is sized by RT_BVH_MAX_DEPTH; keep it small"
#endif

/* The ray as the box test wants it: 1/d and o/d, so that a slab's distance
 * along the ray is one fma, plane·(1/d) − o/d. A component of d below
 * BOX_MIN_DIR in size is taken as BOX_MIN_DIR with its sign: a zero one would
 * give an infinite 1/d, and with o off 0, ∞ − ∞ = NaN on one side of the slab
 * and −∞ on the other, which fmin/fmax turn into a slab the ray never meets
 * (a box straddling 0 dropped for a ray inside it). A finite 1/d of 2^64
 * keeps the distances finite for any coordinate below 2^63 and moves such a
 * ray by less than 2^−64 of its length, far inside the boxes' padding; a ray
 * in a flat box's plane (a flat triangle's, before padding) is then inside
 * the slab, as the triangle test needs. */
#define BOX_MIN_DIR 0x1p-64f

struct box_ray {
	float3 inv_d, o_inv_d;
};

static struct box_ray box_ray(struct tracer *tr, float3 o, float3 d)
{
	struct box_ray r;
	float3 dir = select(d, copysign((float3)BOX_MIN_DIR, d), fabs(d) < BOX_MIN_DIR);

	/* The clamp is comparisons and a sign copy: 0 flops. */
	r.inv_d = (float3)(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
	r.o_inv_d = o * r.inv_d;
	COUNT_FLOPS(tr, FLOPS_BOX_SETUP);
	return r;
}

#ifndef RTCL_CPU
/* Returns whether the ray meets the box lo..hi somewhere in [0, nearest], and
 * where it enters it in *entry. The caller counts FLOPS_BOX_TEST. */
static inline bool box_hit(float4 lo, float4 hi, const struct box_ray *r, float nearest,
			   float *entry)
{
	float3 a = fma(lo.xyz, r->inv_d, -r->o_inv_d);
	float3 b = fma(hi.xyz, r->inv_d, -r->o_inv_d);
	float3 near = fmin(a, b), far = fmax(a, b);
	float enter = fmax(fmax(near.x, near.y), fmax(near.z, 0.0f));
	float leave = fmin(fmin(far.x, far.y), fmin(far.z, nearest));

	*entry = enter;
	return enter <= leave;
}
#else
/* The box test's minimum and maximum on a CPU: a comparison and a select,
 * one instruction (x86's minps/maxps), where fmin and fmax add a NaN test and
 * a blend each. The operands are never NaN (box_ray's clamp keeps the slab
 * distances finite; nearest is at most +inf), and for such operands this is
 * fmin's and fmax's value (a zero's sign aside, which no comparison sees). */
#define BOX_MIN(a, b) select((b), (a), (a) < (b))
#define BOX_MAX(a, b) select((b), (a), (a) > (b))

/* box_hit (above, for GPUs) for a node's two children at once, in the eight
 * lanes of a CPU's vector unit (AVX: one instruction per step for both
 * boxes, where box_hit's float3 steps use three lanes of four and shuffle for
 * the rest). Lanes 0-2 are child 0's x, y, z, lanes 4-6 child 1's; lanes 3
 * and 7, which hold the child's index and count bits, are zeroed before any
 * arithmetic. The same fma, minima and maxima as box_hit, in another order:
 * the same numbers. */
static inline int2 box_pair_hit(float4 lo0, float4 hi0, float4 lo1, float4 hi1,
				const struct box_ray *r, float nearest, float *entry0,
				float *entry1)
{
	const int8 xyz = (int8)(-1, -1, -1, 0, -1, -1, -1, 0);
	float8 inv_d = (float8)(r->inv_d, 0.0f, r->inv_d, 0.0f);
	float8 o_inv_d = (float8)(r->o_inv_d, 0.0f, r->o_inv_d, 0.0f);
	float8 lo = as_float8(as_int8((float8)(lo0, lo1)) & xyz);
	float8 hi = as_float8(as_int8((float8)(hi0, hi1)) & xyz);
	float8 a = fma(lo, inv_d, -o_inv_d);
	float8 b = fma(hi, inv_d, -o_inv_d);
	/* Lanes 3 and 7 of near are 0, the entry's lower bound; those of far
	 * become nearest, the exit's upper bound. */
	float8 near = BOX_MIN(a, b);
	float8 far = select((float8)(nearest), BOX_MAX(a, b), xyz);
	float8 enter = BOX_MAX(near, near.s10325476);
	float8 leave = BOX_MIN(far, far.s10325476);
	enter = BOX_MAX(enter, enter.s23016745);
	leave = BOX_MIN(leave, leave.s23016745);
	*entry0 = enter.s0;
	*entry1 = enter.s4;
	return (int2)(enter.s0 <= leave.s0, enter.s4 <= leave.s4);
}
#endif

/* Tests leaf triangles [first, first + count) of a leaf of triangles
 * (RT_LEAF_TRIANGLES); with any_hit, up to the first hit. */
static inline void leaf_triangles_intersect(struct tracer *tr, int first, int count, float3 o,
					    float3 d, bool any_hit, float *nearest,
					    struct hit *best)
{
	int end = first + (count & RT_LEAF_COUNT_MASK);

	for (int k = first; k < end; k++) {
		if (any_hit && (best->sphere >= 0 || best->triangle >= 0))
			return;
		COUNT_PRIM_TEST(tr);
		leaf_triangle_consider(tr, k, o, d, any_hit, nearest, best);
	}
}

/* Tests a leaf's primitives: spheres [first, first + count) of a leaf of
 * spheres (RT_LEAF_SPHERES, no reference to read), leaf triangles [first,
 * first + count) of a leaf of triangles (RT_LEAF_TRIANGLES), else references
 * [first, first + count); with any_hit, up to the first hit. In a scene
 * without spheres (--accel bvh, not bvh-compact) every leaf is a range of leaf
 * triangles, and the host builds with RTCL_LEAF_TRIANGLES_ONLY: only that
 * loop is compiled, 1.09-1.12x faster on meshes on an H100 (docs/bvh.md,
 * batch 49) for the same image. */
static void leaf_intersect(struct tracer *tr, const struct ray_frame *frame, float3 o, float3 d,
			   int first, int count, bool any_hit, float *nearest, struct hit *best)
{
	COUNT_LEAF_VISIT(tr);
#ifdef RTCL_LEAF_TRIANGLES_ONLY
	(void)frame;
	leaf_triangles_intersect(tr, first, count, o, d, any_hit, nearest, best);
#else
	if (count & RT_LEAF_SPHERES) {
		int end = first + (count & RT_LEAF_COUNT_MASK);
		for (int i = first; i < end; i++) {
			if (any_hit && (best->sphere >= 0 || best->triangle >= 0))
				return;
			float4 s = tr->spheres[i].center;
			float gap = sphere_gap(s, frame);
			COUNT_PRIM_TEST(tr);
			COUNT_FLOPS(tr, FLOPS_SPHERE_GAP);
			sphere_consider(tr, s, gap, o, d, i, any_hit, nearest, best);
		}
		return;
	}
	if (SCENE_HAS_TRIANGLES && (count & RT_LEAF_TRIANGLES)) {
		leaf_triangles_intersect(tr, first, count, o, d, any_hit, nearest, best);
		return;
	}
	for (int k = first; k < first + count; k++) {
		if (any_hit && (best->sphere >= 0 || best->triangle >= 0))
			return;
		uint ref = tr->refs[k];
		int index = (int)(ref & RT_PRIM_INDEX_MASK);

		COUNT_PRIM_TEST(tr);
		if (SCENE_HAS_TRIANGLES && ref >> RT_PRIM_KIND_SHIFT == RT_PRIM_TRIANGLE) {
			triangle_consider(tr, index, o, d, any_hit, nearest, best);
			continue;
		}
		float4 s = tr->spheres[index].center;
		float gap = sphere_gap(s, frame);
		COUNT_FLOPS(tr, FLOPS_SPHERE_GAP);
		sphere_consider(tr, s, gap, o, d, index, any_hit, nearest, best);
	}
#endif
}

/* A child waiting on the traversal stack: a node (count 0) or a leaf. */
struct bvh_entry {
	int index, count;
};

#ifdef RTCL_BVH4
#ifndef RTCL_CPU
#error "four-wide nodes are a CPU device's (host/render/block.c)"
#endif
/* The traversal stack of the four-wide tree: a visit leaves at most three
 * children waiting, and the tree is no deeper than the binary one. */
#define BVH4_STACK (3 * RT_BVH_MAX_DEPTH + 1)

/* bvh_intersect over four-wide nodes (RTCL_BVH4: a CPU device outside the
 * counting build; struct rt_bvh4_node, docs/bvh.md "A four-wide tree on
 * CPUs"): a visit tests the four children's boxes in the lanes of float4s,
 * box_hit's slabs with a comparison and a select for the minima and maxima
 * (the operands are never NaN, box_ray), and the children it meets wait on
 * the stack farthest first, so that the nearest is taken next; a lone one is
 * taken at once. The same primitives meet the same tests, and the closest
 * hit does not depend on the order (bvh_intersect), so the image is the
 * binary tree's. */
static void bvh_intersect(struct tracer *tr, const struct ray_frame *frame, float3 o, float3 d,
			  bool any_hit, float *nearest, struct hit *best)
{
	struct bvh_entry stack[BVH4_STACK];
	struct bvh_entry at = {0, 0}; /* the root */
	struct box_ray ray = box_ray(tr, o, d);
	int waiting = 0;

	for (;;) {
		if (at.count > 0) {
			leaf_intersect(tr, frame, o, d, at.index, at.count, any_hit, nearest, best);
			if (any_hit && (best->sphere >= 0 || best->triangle >= 0))
				return;
		} else {
			RTCL_SCENE_SPACE const struct rt_bvh4_node *node = &tr->nodes[at.index];
			float4 ax = fma(node->lo_x, ray.inv_d.x, -ray.o_inv_d.x);
			float4 bx = fma(node->hi_x, ray.inv_d.x, -ray.o_inv_d.x);
			float4 ay = fma(node->lo_y, ray.inv_d.y, -ray.o_inv_d.y);
			float4 by = fma(node->hi_y, ray.inv_d.y, -ray.o_inv_d.y);
			float4 az = fma(node->lo_z, ray.inv_d.z, -ray.o_inv_d.z);
			float4 bz = fma(node->hi_z, ray.inv_d.z, -ray.o_inv_d.z);
			float4 enter = BOX_MAX(BOX_MAX(BOX_MIN(ax, bx), BOX_MIN(ay, by)),
					       BOX_MAX(BOX_MIN(az, bz), (float4)(0.0f)));
			float4 leave = BOX_MIN(BOX_MIN(BOX_MAX(ax, bx), BOX_MAX(ay, by)),
					       BOX_MIN(BOX_MAX(az, bz), (float4)(*nearest)));
			int4 count = vload4(0, node->count);
			int4 index = vload4(0, node->index);
			int4 hit = enter <= leave & count != RT_BVH4_EMPTY;
			float t[4] = {enter.x, enter.y, enter.z, enter.w};
			int ci[4] = {index.x, index.y, index.z, index.w};
			int cc[4] = {count.x, count.y, count.z, count.w};
			int met[4] = {hit.x, hit.y, hit.z, hit.w};
			int order[4], n = 0;

			/* The children met, nearest first (insertion by entry). */
			for (int k = 0; k < 4; k++) {
				if (!met[k])
					continue;
				int j = n++;
				while (j > 0 && t[order[j - 1]] > t[k]) {
					order[j] = order[j - 1];
					j--;
				}
				order[j] = k;
			}
			if (n > 0) {
				for (int j = n - 1; j > 0; j--)
					stack[waiting++] = (struct bvh_entry){ci[order[j]], cc[order[j]]};
				at = (struct bvh_entry){ci[order[0]], cc[order[0]]};
				continue;
			}
		}
		if (waiting == 0)
			return;
		at = stack[--waiting];
	}
}
#else

/* Depth first from the root, nearer child first (by where the ray enters the
 * two boxes), the farther one waiting on a stack in private memory; boxes
 * beyond the nearest hit found so far are skipped. With any_hit, stops at
 * the first hit. The closest hit is that of brute force: the same sphere and
 * triangle tests, ties decided as brute force's order decides them
 * (sphere_consider, triangle_consider), and boxes padded so that every
 * sphere or triangle a test hits is inside (host/layout/bvh.c, BVH_SPHERE_PAD).
 * Leaves wait on the stack like nodes, so that each iteration is one kind of
 * step for the whole SIMD group: testing leaves inside the node step measured
 * 4-7 % slower on an H100 (docs/bvh.md). */
static void bvh_intersect(struct tracer *tr, const struct ray_frame *frame, float3 o, float3 d,
			  bool any_hit, float *nearest, struct hit *best)
{
	struct bvh_entry stack[RT_BVH_MAX_DEPTH];
	struct bvh_entry at = {0, 0}; /* the root */
	struct box_ray ray = box_ray(tr, o, d);
	int waiting = 0;

	for (;;) {
		SIMD_STEP(tr, RT_SIMD_TRAVERSAL);
		if (at.count > 0) {
			leaf_intersect(tr, frame, o, d, at.index, at.count, any_hit, nearest, best);
			if (any_hit && (best->sphere >= 0 || best->triangle >= 0))
				return;
		} else {
			RTCL_SCENE_SPACE const struct rt_bvh_node *node = &tr->nodes[at.index];
			float4 lo0 = node->child[0].lo, hi0 = node->child[0].hi;
			float4 lo1 = node->child[1].lo, hi1 = node->child[1].hi;
			float t0, t1;
#ifdef RTCL_CPU
			int2 hits = box_pair_hit(lo0, hi0, lo1, hi1, &ray, *nearest, &t0, &t1);
			bool hit0 = hits.x, hit1 = hits.y;
#else
			bool hit0 = box_hit(lo0, hi0, &ray, *nearest, &t0);
			bool hit1 = box_hit(lo1, hi1, &ray, *nearest, &t1);
#endif

			COUNT_NODE_VISIT(tr);
			COUNT_FLOPS(tr, 2 * FLOPS_BOX_TEST);
			struct bvh_entry c0 = {bvh_child_index(lo0), bvh_child_count(hi0)};
			struct bvh_entry c1 = {bvh_child_index(lo1), bvh_child_count(hi1)};
			if (hit0 && hit1) {
				bool first0 = t0 <= t1;
				stack[waiting++] = first0 ? c1 : c0;
				at = first0 ? c0 : c1;
				continue;
			}
			if (hit0 || hit1) {
				at = hit0 ? c0 : c1;
				continue;
			}
		}
		if (waiting == 0)
			return;
		at = stack[--waiting];
	}
}
#endif /* RTCL_BVH4 */

#endif
