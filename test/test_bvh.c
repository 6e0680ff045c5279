/* The BVH builder (host/layout/bvh.c): every primitive in exactly one leaf, every box
 * holding what lies below it, a tree shallow enough for the tracer's stack,
 * an SAH cost well under brute force's on random spheres, and the
 * degenerate inputs. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "layout/bvh.h"

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
	const struct bvh_prim *by_ref; /* the primitives: the spheres by index, then the
					  triangles by index */
	int spheres;		       /* how many of them are spheres */
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
		int slot = (int)(ref & RT_PRIM_INDEX_MASK);
		if (ref >> RT_PRIM_KIND_SHIFT == RT_PRIM_TRIANGLE)
			slot += w->spheres;
		else
			cr_assert_eq(ref >> RT_PRIM_KIND_SHIFT, RT_PRIM_SPHERE);
		const struct bvh_prim *p = &w->by_ref[slot];
		cr_assert_eq(p->ref, ref, "reference %#x for primitive %d", ref, slot);
		cr_assert(box_contains(b, p->lo, p->hi), "primitive %d outside its leaf's box",
			  slot);
		w->seen[slot]++;
	}
}

/* Builds over prims (copied: the builder reorders), spheres first then
 * triangles, each kind by index, and checks the tree. */
static struct bvh check_mixed_tree(const struct bvh_prim *prims, int n, int spheres)
{
	struct bvh bvh;
	struct bvh_prim *work = malloc((size_t)(n ? n : 1) * sizeof(*work));
	int *seen = calloc((size_t)(n ? n : 1), sizeof(int));
	int *node_seen = calloc((size_t)(n ? n : 1), sizeof(int));

	cr_assert(work && seen && node_seen);
	if (n > 0) /* memcpy from NULL is undefined even for 0 bytes */
		memcpy(work, prims, (size_t)n * sizeof(*work));
	cr_assert_eq(bvh_build(work, n, &bvh), 0);
	cr_assert_eq(bvh.ref_count, n);
	if (n == 0) {
		cr_assert_eq(bvh.node_count, 0);
	} else {
		struct walk_state w = {&bvh, prims, spheres, seen, node_seen};
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

static struct bvh check_tree(const struct bvh_prim *prims, int n)
{
	return check_mixed_tree(prims, n, n);
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

/* A random triangle of the cube -50..50; every third flat in an axis plane
 * (one coordinate the same for all three vertices, often 0), as meshes of
 * boxes and floors have them. */
static void random_triangle(struct scene_triangle *t, int i)
{
	for (int v = 0; v < 3; v++)
		for (int k = 0; k < 3; k++)
			t->v[v][k] = 100.0 * rand() / RAND_MAX - 50.0;
	if (i % 3 == 0) {
		int axis = i / 3 % 3;
		double at = i % 2 ? 0.0 : t->v[0][axis];
		for (int v = 0; v < 3; v++)
			t->v[v][axis] = at;
	}
}

/* Spheres and triangles in one tree: every primitive in exactly one leaf,
 * under boxes that hold it, references of both kinds. */
Test(bvh, spheres_and_triangles_in_one_tree)
{
	static const int sizes[][2] = {{0, 1}, {0, 2}, {1, 1}, {3, 40}, {60, 335}, {100, 3000}};
	static struct bvh_prim prims[3100];

	for (size_t z = 0; z < sizeof(sizes) / sizeof(sizes[0]); z++) {
		int spheres = sizes[z][0], n = spheres + sizes[z][1];
		random_spheres(prims, spheres, 7 + (unsigned)n, 0.5);
		for (int i = spheres; i < n; i++) {
			struct scene_triangle t;
			random_triangle(&t, i - spheres);
			bvh_triangle_prim(&t, i - spheres, &prims[i]);
			cr_assert_eq(prims[i].ref >> RT_PRIM_KIND_SHIFT, RT_PRIM_TRIANGLE);
		}
		struct bvh bvh = check_mixed_tree(prims, n, spheres);
		bvh_free(&bvh);
	}
}

/* Subtrees built on threads of their own make the same tree, node for node
 * and reference for reference, as one thread: 300,000 triangles, so that the
 * top levels' ranges pass BVH_PARALLEL_MIN. */
Test(bvh, threads_build_the_same_tree)
{
	enum { N = 300000 };
	struct bvh_prim *one = malloc(N * sizeof(*one)), *many = malloc(N * sizeof(*many));
	struct bvh a, b;

	cr_assert(one && many);
	srand(26);
	for (int i = 0; i < N; i++) { /* small triangles scattered over a cube */
		struct scene_triangle t;
		double centre[3];
		for (int k = 0; k < 3; k++)
			centre[k] = 100.0 * rand() / RAND_MAX - 50.0;
		for (int v = 0; v < 3; v++)
			for (int k = 0; k < 3; k++)
				t.v[v][k] = centre[k] + (double)rand() / RAND_MAX - 0.5;
		bvh_triangle_prim(&t, i, &one[i]);
	}
	memcpy(many, one, N * sizeof(*one));
	cr_assert_eq(bvh_build_threaded(one, N, BVH_TRIANGLE_COST, 0, &a), 0);
	cr_assert_eq(bvh_build_threaded(many, N, BVH_TRIANGLE_COST, 3, &b), 0);
	cr_assert_eq(a.node_count, b.node_count);
	cr_assert_gt(a.node_count, 4 * 65536 / 8, "too small a tree to use threads");
	cr_assert_eq(memcmp(a.nodes, b.nodes, (size_t)a.node_count * sizeof(*a.nodes)), 0);
	cr_assert_eq(memcmp(a.refs, b.refs, (size_t)a.ref_count * sizeof(*a.refs)), 0);
	cr_assert_eq(a.depth, b.depth);
	cr_assert_eq(a.max_leaf, b.max_leaf);
	cr_assert_eq(a.sah_cost, b.sah_cost);
	bvh_free(&a);
	bvh_free(&b);
	free(one);
	free(many);
}

/* A triangle's box holds its vertices as the device stores them (v0, v0 + e1,
 * v0 + e2 in float) with room to spare on every axis, the flat one of an
 * axis-aligned triangle too (a slab of zero width would leave the box test
 * to the rounding of a ray in its plane), and stays small: 1e-5 of the
 * largest coordinate on each side. */
Test(bvh, triangle_box_is_padded)
{
	static const struct scene_triangle tris[] = {
		{{{1, 2, 3}, {4, -5, 6}, {-7, 8, 9.5}}, {{0}}, 0, 0},
		{{{-4, 0, 4}, {4, 0, 4}, {0, 0, -5}}, {{0}}, 0, 0},	     /* flat in y = 0 */
		{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0}}, 0, 0},	     /* flat in z = 0 */
		{{{3, -1, 1e4}, {3, 1, 1e4}, {3, 0, 1e4 + 1}}, {{0}}, 0, 0}, /* x = 3, far */
	};

	for (int i = 0; i < (int)(sizeof(tris) / sizeof(tris[0])); i++) {
		struct bvh_prim p;
		double scale = 0; /* the largest coordinate, which sets the padding */
		for (int v = 0; v < 3; v++)
			for (int k = 0; k < 3; k++)
				scale = fmax(scale, fabs(tris[i].v[v][k]));
		bvh_triangle_prim(&tris[i], i, &p);
		cr_expect_eq(p.ref, RT_PRIM_TRIANGLE << RT_PRIM_KIND_SHIFT | (uint32_t)i);
		for (int k = 0; k < 3; k++) {
			float v0 = (float)tris[i].v[0][k];
			double lo = v0, hi = v0, sum = v0;
			for (int v = 1; v < 3; v++) {
				double x = (double)v0 + (float)(tris[i].v[v][k] - tris[i].v[0][k]);
				lo = x < lo ? x : lo;
				hi = x > hi ? x : hi;
				sum += x;
			}
			cr_expect_lt(p.lo[k], lo, "triangle %d axis %d: no room below", i, k);
			cr_expect_gt(p.hi[k], hi, "triangle %d axis %d: no room above", i, k);
			cr_expect_lt(p.hi[k] - p.lo[k], (hi - lo) + 1e-4 * scale,
				     "triangle %d axis %d: padding stays small", i, k);
			cr_expect_float_eq(p.centroid[k], sum / 3, 1e-6 * (fabs(sum) + 1));
		}
	}
}

/* A leaf as a walk finds it: its reference range and its box. */
struct leaf_seen {
	int index, count;
	float lo[3], hi[3];
};

static int by_leaf(const void *a, const void *b)
{
	return memcmp(a, b, sizeof(struct leaf_seen));
}

static void binary_leaves(const struct bvh *bvh, const struct rt_bvh_box *b,
			  struct leaf_seen *out, int *n)
{
	if (child_count(b) == 0 && child_index(b) != 0) {
		for (int k = 0; k < 2; k++)
			binary_leaves(bvh, &bvh->nodes[child_index(b)].child[k], out, n);
		return;
	}
	struct leaf_seen l = {child_index(b), child_count(b), {0}, {0}};
	for (int a = 0; a < 3; a++) {
		l.lo[a] = b->lo.s[a];
		l.hi[a] = b->hi.s[a];
	}
	out[(*n)++] = l;
}

/* Walks four-wide node w, whose box (from its parent) is lo..hi: every
 * child's box inside it, a node with fewer than four children holding only
 * leaves, empty slots last and empty; collects the leaves. */
static void wide_leaves(const struct bvh *bvh, int w, const float lo[3], const float hi[3],
			int *reached, struct leaf_seen *out, int *n)
{
	const struct rt_bvh4_node *node = &bvh->wide[w];
	const float *los[3] = {node->lo_x.s, node->lo_y.s, node->lo_z.s};
	const float *his[3] = {node->hi_x.s, node->hi_y.s, node->hi_z.s};
	int children = 0, leaves = 0;

	cr_assert(w >= 0 && w < bvh->wide_count, "four-wide node %d of %d", w, bvh->wide_count);
	cr_assert_eq(reached[w]++, 0, "four-wide node %d reached twice", w);
	for (int k = 0; k < 4; k++) {
		if (node->count[k] == RT_BVH4_EMPTY) {
			for (int a = 0; a < 3; a++)
				cr_assert(los[a][k] > his[a][k], "an empty slot's box is not empty");
			continue;
		}
		cr_assert_eq(children++, k, "an empty slot before a child");
		float clo[3] = {los[0][k], los[1][k], los[2][k]};
		float chi[3] = {his[0][k], his[1][k], his[2][k]};
		for (int a = 0; a < 3; a++)
			cr_assert(clo[a] >= lo[a] && chi[a] <= hi[a], "node %d's child %d sticks out",
				  w, k);
		if (node->count[k] == 0 && node->index[k] != 0) {
			cr_assert_gt(node->index[k], w, "a child node before its parent");
			wide_leaves(bvh, node->index[k], clo, chi, reached, out, n);
			continue;
		}
		leaves++;
		struct leaf_seen l = {node->index[k], node->count[k], {0}, {0}};
		memcpy(l.lo, clo, sizeof(clo));
		memcpy(l.hi, chi, sizeof(chi));
		out[(*n)++] = l;
	}
	cr_assert_geq(children, 2, "four-wide node %d has %d children", w, children);
	cr_assert(children == 4 || leaves == children,
		  "node %d left an inner child closed with room", w);
}

/* bvh_widen (docs/bvh.md, "A four-wide tree on CPUs"): the binary tree's
 * leaves, each once with its box, under four-wide nodes whose boxes hold
 * what is below them; fewer nodes than the binary tree. */
static void check_widened(struct bvh *bvh)
{
	int cap = 2 * bvh->node_count + 2, nb = 0, nw = 0;
	struct leaf_seen *binary = calloc((size_t)cap, sizeof(*binary));
	struct leaf_seen *wide = calloc((size_t)cap, sizeof(*wide));
	int *reached = calloc((size_t)bvh->node_count + 1, sizeof(int));
	const float big[3] = {INFINITY, INFINITY, INFINITY}, small[3] = {-INFINITY, -INFINITY,
								       -INFINITY};

	cr_assert(binary && wide && reached);
	cr_assert_eq(bvh_widen(bvh), 0);
	if (bvh->node_count == 0) {
		cr_assert_null(bvh->wide);
		cr_assert_eq(bvh->wide_count, 0);
	} else {
		cr_assert(bvh->wide_count >= 1 && bvh->wide_count <= bvh->node_count);
		for (int k = 0; k < 2; k++)
			binary_leaves(bvh, &bvh->nodes[0].child[k], binary, &nb);
		wide_leaves(bvh, 0, small, big, reached, wide, &nw);
		for (int w = 0; w < bvh->wide_count; w++)
			cr_assert_eq(reached[w], 1, "four-wide node %d unreached", w);
		cr_assert_eq(nw, nb, "%d leaves in the four-wide tree, %d in the binary", nw, nb);
		qsort(binary, (size_t)nb, sizeof(*binary), by_leaf);
		qsort(wide, (size_t)nw, sizeof(*wide), by_leaf);
		cr_assert(memcmp(binary, wide, (size_t)nb * sizeof(*binary)) == 0,
			  "the four-wide tree's leaves are not the binary tree's");
	}
	free(binary);
	free(wide);
	free(reached);
}

Test(bvh, widened_trees_hold_the_binary_trees_leaves)
{
	static const int sizes[] = {0, 1, 2, 3, 5, 17, 60, 400, 2000};
	static struct bvh_prim prims[5000];

	for (size_t z = 0; z < sizeof(sizes) / sizeof(sizes[0]); z++) {
		int n = sizes[z];
		random_spheres(prims, n, 26 + (unsigned)n, 0.5);
		struct bvh bvh = check_tree(prims, n);
		check_widened(&bvh);
		if (n == 2000) /* 2000 spheres in leaves of up to 8: about a third */
			cr_expect_lt(bvh.wide_count, bvh.node_count / 2, "%d four-wide nodes of %d",
				     bvh.wide_count, bvh.node_count);
		bvh_free(&bvh);
	}
	struct scene_sphere s = {{1, 2, 3}, 0.5, 0};
	for (int i = 0; i < 5000; i++) /* a deep tree of identical spheres */
		bvh_sphere_prim(&s, i, &prims[i]);
	struct bvh bvh = check_tree(prims, 5000);
	check_widened(&bvh);
	bvh_free(&bvh);
}
