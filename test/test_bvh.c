/* The BVH builder (host/bvh.c): every primitive in exactly one leaf, every box
 * holding what lies below it, a tree shallow enough for the tracer's stack,
 * an SAH cost well under brute force's on random spheres, and the
 * degenerate inputs. */
#include <criterion/criterion.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bvh.h"

static int child_index(const struct rt_bvh_box *b)
{
	int32_t i;
	memcpy(&i, &b->lo.s[3], sizeof(i));
	return i;
}

static int child_count(const struct rt_bvh_box *b)
{
	int32_t n;
	memcpy(&n, &b->hi.s[3], sizeof(n));
	return n;
}

static int box_contains(const struct rt_bvh_box *outer, const float lo[3], const float hi[3])
{
	for (int k = 0; k < 3; k++)
		if (lo[k] < outer->lo.s[k] || hi[k] > outer->hi.s[k])
			return 0;
	return 1;
}

struct walk_state {
	const struct bvh *bvh;
	const struct bvh_prim *by_ref; /* the primitives, indexed by their reference */
	int *seen;		       /* leaf appearances per primitive */
	int *node_seen;
};

/* Checks that every primitive below box b (child of some node, at depth) lies
 * in it; counts what the leaves hold. */
static void walk(struct walk_state *w, const struct rt_bvh_box *b, int depth)
{
	int index = child_index(b), count = child_count(b);

	cr_assert_leq(depth, RT_BVH_MAX_DEPTH, "a child at depth %d", depth);
	if (count == 0) {
		cr_assert(index > 0 && index < w->bvh->node_count, "child node %d of %d", index,
			  w->bvh->node_count);
		cr_assert_eq(w->node_seen[index]++, 0, "node %d reached twice", index);
		for (int k = 0; k < 2; k++) {
			const struct rt_bvh_box *c = &w->bvh->nodes[index].child[k];
			for (int a = 0; a < 3; a++)
				cr_assert(c->lo.s[a] >= b->lo.s[a] && c->hi.s[a] <= b->hi.s[a],
					  "node %d's child %d sticks out of its box", index, k);
			walk(w, c, depth + 1);
		}
		return;
	}
	cr_assert(count > 0 && count <= BVH_MAX_LEAF, "a leaf of %d", count);
	cr_assert(index >= 0 && index + count <= w->bvh->ref_count);
	for (int i = index; i < index + count; i++) {
		uint32_t ref = w->bvh->refs[i];
		const struct bvh_prim *p = &w->by_ref[ref & RT_PRIM_INDEX_MASK];
		cr_assert_eq(ref >> RT_PRIM_KIND_SHIFT, RT_PRIM_SPHERE);
		cr_assert(box_contains(b, p->lo, p->hi), "primitive %u outside its leaf's box",
			  ref & RT_PRIM_INDEX_MASK);
		w->seen[ref & RT_PRIM_INDEX_MASK]++;
	}
}

/* Builds over prims (copied: the builder reorders) and checks the tree. */
static struct bvh check_tree(const struct bvh_prim *prims, int n)
{
	struct bvh bvh;
	struct bvh_prim *work = malloc((size_t)(n ? n : 1) * sizeof(*work));
	int *seen = calloc((size_t)(n ? n : 1), sizeof(int));
	int *node_seen = calloc((size_t)(n ? n : 1), sizeof(int));

	cr_assert(work && seen && node_seen);
	memcpy(work, prims, (size_t)n * sizeof(*work));
	cr_assert_eq(bvh_build(work, n, &bvh), 0);
	cr_assert_eq(bvh.ref_count, n);
	if (n == 0) {
		cr_assert_eq(bvh.node_count, 0);
	} else {
		struct walk_state w = {&bvh, prims, seen, node_seen};
		cr_assert_leq(bvh.node_count, n > 1 ? n - 1 : 1);
		node_seen[0] = 1;
		for (int k = 0; k < 2; k++)
			walk(&w, &bvh.nodes[0].child[k], 1);
		for (int i = 0; i < bvh.node_count; i++)
			cr_assert_eq(node_seen[i], 1, "node %d unreached", i);
		/* Once, but for one primitive, which both root children hold. */
		for (int i = 0; i < n; i++)
			cr_assert_eq(seen[i], n == 1 ? 2 : 1, "primitive %d in %d leaves", i,
				     seen[i]);
	}
	free(work);
	free(seen);
	free(node_seen);
	return bvh;
}

static void random_spheres(struct bvh_prim *prims, int n, unsigned seed, double radius)
{
	srand(seed);
	for (int i = 0; i < n; i++) {
		struct scene_sphere s = {{0}, radius, 0};
		for (int k = 0; k < 3; k++)
			s.center[k] = 100.0 * rand() / RAND_MAX - 50.0;
		bvh_sphere_prim(&s, i, &prims[i]);
	}
}

Test(bvh, random_spheres_tree_and_cost)
{
	static const int sizes[] = {2, 3, 5, 17, 60, 400, 2000};
	static struct bvh_prim prims[2000];

	for (size_t z = 0; z < sizeof(sizes) / sizeof(sizes[0]); z++) {
		int n = sizes[z];
		random_spheres(prims, n, 2009 + (unsigned)n, 0.5);
		struct bvh bvh = check_tree(prims, n);
		/* Brute force costs n sphere tests a ray; the tree's expected
		 * cost grows about logarithmically (with BVH_NODE_COST 3 and
		 * leaves of 8, measured 41 for 400 and 81 for 2000), a small
		 * tree's at most a root visit more than brute force. */
		double bound = n >= 2000 ? n / 20.0 : n >= 400 ? n / 8.0 : n + BVH_NODE_COST;
		fprintf(stderr, "%d spheres: SAH cost %.2f\n", n, bvh.sah_cost);
		cr_expect_leq(bvh.sah_cost, bound, "%d spheres: SAH cost %.1f above %.1f", n,
			      bvh.sah_cost, bound);
		bvh_free(&bvh);
	}
}

Test(bvh, no_primitive)
{
	struct bvh bvh = check_tree(NULL, 0);

	cr_expect_null(bvh.nodes);
	cr_expect_eq(bvh.sah_cost, 0.0);
	bvh_free(&bvh);
}

Test(bvh, one_primitive)
{
	struct bvh_prim prim;
	struct scene_sphere s = {{1, 2, 3}, 0.5, 0};

	bvh_sphere_prim(&s, 0, &prim);
	struct bvh bvh = check_tree(&prim, 1);
	cr_expect_eq(bvh.node_count, 1);
	bvh_free(&bvh);
}

/* Identical spheres give SAH nothing to split on: the builder halves the
 * range instead, and the tree stays within the stack's depth. */
Test(bvh, identical_centroids)
{
	static struct bvh_prim prims[5000];
	struct scene_sphere s = {{1, 2, 3}, 0.5, 0};

	for (int i = 0; i < 5000; i++)
		bvh_sphere_prim(&s, i, &prims[i]);
	struct bvh bvh = check_tree(prims, 5000);
	cr_expect_leq(bvh.depth, 14, "depth %d for 5000 identical spheres", bvh.depth);
	bvh_free(&bvh);
}

/* A sphere's box holds the sphere with room to spare for rounding. */
Test(bvh, sphere_box_is_padded)
{
	struct bvh_prim p;
	struct scene_sphere s = {{10, -20, 30}, 2, 0};

	bvh_sphere_prim(&s, 7, &p);
	cr_expect_eq(p.ref, 7u);
	for (int k = 0; k < 3; k++) {
		cr_expect_lt(p.lo[k], s.center[k] - 2.0);
		cr_expect_gt(p.hi[k], s.center[k] + 2.0);
		cr_expect_lt(p.hi[k] - p.lo[k], 4.01, "padding stays small");
		cr_expect_eq(p.centroid[k], (float)s.center[k]);
	}
}
