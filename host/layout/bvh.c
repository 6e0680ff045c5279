/* The binned SAH builder (docs/bvh.md). Top down: each range of primitives
 * is binned by centroid along each axis into BVH_BINS bins, the split with
 * the least SAH cost is taken, and the range becomes a leaf when it is small
 * enough (BVH_MAX_LEAF) and no split is cheaper. Nodes are numbered in the
 * order they are made, depth first, so that a node's first child follows it
 * in memory. The top levels' second subtrees are built on threads of their
 * own (build_parallel), into node arrays of their own that are then appended
 * in that order: the same tree, node for node, as one thread builds. */
#include "layout/bvh.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* Subtrees built on threads of their own: at most 2^BVH_PARALLEL_LEVELS
 * threads, and only ranges of at least BVH_PARALLEL_MIN primitives (below,
 * a thread costs more than it saves). */
#define BVH_PARALLEL_LEVELS 3
#define BVH_PARALLEL_MIN 65536

/* Below this depth, ranges split by SAH; from it on, at the middle of the
 * range, which ends any tree within RT_BVH_MAX_DEPTH levels: 2^31 primitives
 * need at most 31 halvings. */
#define BVH_SAH_DEPTH (RT_BVH_MAX_DEPTH - 32)

struct box {
	float lo[3], hi[3];
};

static void box_empty(struct box *b)
{
	for (int k = 0; k < 3; k++) {
		b->lo[k] = FLT_MAX;
		b->hi[k] = -FLT_MAX;
	}
}

/* Comparisons rather than fminf/fmaxf, which are calls into libm here (they
 * must handle NaN, which no box holds): the builder's hot loop. */
static void box_grow(struct box *b, const float lo[3], const float hi[3])
{
	for (int k = 0; k < 3; k++) {
		b->lo[k] = lo[k] < b->lo[k] ? lo[k] : b->lo[k];
		b->hi[k] = hi[k] > b->hi[k] ? hi[k] : b->hi[k];
	}
}

/* Half the surface area; 0 for an empty box. Only ratios are used. */
static double box_area(const struct box *b)
{
	double e[3];

	for (int k = 0; k < 3; k++)
		e[k] = b->hi[k] >= b->lo[k] ? (double)b->hi[k] - b->lo[k] : 0.0;
	return e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
}

/* A child as its parent stores it: a node (count 0) or a leaf. */
struct child {
	struct box box;
	int index; /* the node, or the leaf's first reference */
	int count; /* the leaf's references; 0 for a node */
};

struct builder {
	struct bvh_prim *prims;
	struct rt_bvh_node *nodes;
	int node_count;
	int depth, max_leaf;
	double triangle_cost; /* ref_cost's */
};

/* What testing a primitive costs the SAH, in sphere tests. */
static double ref_cost(uint32_t ref, double triangle_cost)
{
	return ref >> RT_PRIM_KIND_SHIFT == RT_PRIM_TRIANGLE ? triangle_cost : 1.0;
}

struct split {
	int axis, bin; /* primitives whose centroid bins below bin go left */
	double cost;
	float origin, scale; /* centroid to bin: (c - origin) * scale */
};

static int centroid_bin(const struct bvh_prim *p, const struct split *s)
{
	int bin = (int)((p->centroid[s->axis] - s->origin) * s->scale);

	return bin < 0 ? 0 : bin >= BVH_BINS ? BVH_BINS - 1 : bin;
}

/* Primitives binned along one axis: per bin, how many, what testing them
 * costs (ref_cost) and their box. */
struct axis_bins {
	struct split s;
	int counts[BVH_BINS];
	double costs[BVH_BINS];
	struct box boxes[BVH_BINS];
};

/* The best split of the binned axis into *best, if cheaper than *best: a
 * sweep from the right for the right sides' costs, then from the left. */
static void sweep_axis(const struct axis_bins *a, double parent_area, struct split *best)
{
	struct split s = a->s;
	struct box left, right;
	double right_cost[BVH_BINS];
	double cost = 0.0;

	box_empty(&right);
	for (int b = BVH_BINS - 1, n = 0; b > 0; b--) {
		n += a->counts[b];
		cost += a->costs[b];
		box_grow(&right, a->boxes[b].lo, a->boxes[b].hi);
		right_cost[b] = n ? box_area(&right) * cost : -1.0;
	}
	box_empty(&left);
	cost = 0.0;
	for (int b = 1, n = 0; b < BVH_BINS; b++) {
		n += a->counts[b - 1];
		cost += a->costs[b - 1];
		box_grow(&left, a->boxes[b - 1].lo, a->boxes[b - 1].hi);
		if (n == 0 || right_cost[b] < 0.0)
			continue;
		s.bin = b;
		s.cost = BVH_NODE_COST + (box_area(&left) * cost + right_cost[b]) / parent_area;
		if (s.cost < best->cost)
			*best = s;
	}
}

/* Bins the range along every axis whose centroids spread, in one pass over
 * the primitives, and keeps the cheapest split in *best. Returns the cost
 * of testing every primitive of the range. */
static double find_split(const struct bvh_prim *prims, int begin, int end,
			 const struct box *centroids, double parent_area, double triangle_cost,
			 struct split *best)
{
	struct axis_bins bins[3];
	int axis_count = 0;
	double range_cost = 0.0;

	for (int axis = 0; axis < 3; axis++) {
		double extent = (double)centroids->hi[axis] - centroids->lo[axis];
		if (!(extent > 0.0))
			continue;
		struct axis_bins *a = &bins[axis_count];
		a->s = (struct split){axis, 0, 0.0, centroids->lo[axis],
				      (float)(BVH_BINS / extent)};
		memset(a->counts, 0, sizeof(a->counts));
		memset(a->costs, 0, sizeof(a->costs));
		for (int b = 0; b < BVH_BINS; b++)
			box_empty(&a->boxes[b]);
		axis_count++;
	}
	for (int i = begin; i < end; i++) {
		double cost = ref_cost(prims[i].ref, triangle_cost);

		range_cost += cost;
		for (int k = 0; k < axis_count; k++) {
			int b = centroid_bin(&prims[i], &bins[k].s);
			bins[k].counts[b]++;
			bins[k].costs[b] += cost;
			box_grow(&bins[k].boxes[b], prims[i].lo, prims[i].hi);
		}
	}
	for (int k = 0; k < axis_count; k++)
		sweep_axis(&bins[k], parent_area, best);
	return range_cost;
}

/* Moves the primitives that go left to the front; returns the first that
 * goes right. */
static int partition(struct bvh_prim *prims, int begin, int end, const struct split *s)
{
	int mid = begin;

	for (int i = begin; i < end; i++) {
		if (centroid_bin(&prims[i], s) < s->bin) {
			struct bvh_prim t = prims[i];
			prims[i] = prims[mid];
			prims[mid++] = t;
		}
	}
	return mid;
}

/* Returns where range [begin, end) splits, or begin when it stays a leaf.
 * bounds: the range's box, centroids: its centroids' box. must_split: the
 * root, which is always a node. */
static int choose_split(struct builder *b, int begin, int end, const struct box *bounds,
			const struct box *centroids, int depth, int must_split)
{
	int n = end - begin;
	struct split best = {0, 0, DBL_MAX, 0.0f, 0.0f};

	if (n == 1)
		return begin;
	if (depth >= BVH_SAH_DEPTH)
		return n > BVH_MAX_LEAF || must_split ? begin + n / 2 : begin;
	double area = box_area(bounds);
	double leaf_cost = find_split(b->prims, begin, end, centroids, area > 0.0 ? area : 1.0,
				      b->triangle_cost, &best);
	if (best.cost == DBL_MAX) /* every centroid in one bin: no SAH split */
		return n > BVH_MAX_LEAF || must_split ? begin + n / 2 : begin;
	if (n <= BVH_MAX_LEAF && !must_split && best.cost >= leaf_cost)
		return begin;
	return partition(b->prims, begin, end, &best);
}

static void store_child(struct rt_bvh_box *out, const struct child *c)
{
	int32_t index = c->index, count = c->count;

	for (int k = 0; k < 3; k++) {
		out->lo.s[k] = c->box.lo[k];
		out->hi.s[k] = c->box.hi[k];
	}
	/* int bits in the w lanes: bvh_child_index, bvh_child_count */
	memcpy(&out->lo.s[3], &index, sizeof(index));
	memcpy(&out->hi.s[3], &count, sizeof(count));
}

static void build_parallel(struct builder *b, int begin, int end, int depth, int levels,
			   struct child *out);

/* A subtree built on a thread of its own, into nodes of its own numbered
 * from 0. */
struct subtree {
	struct builder b;
	int begin, end, depth, levels;
	struct child out;
};

static void *build_subtree(void *arg)
{
	struct subtree *t = arg;

	build_parallel(&t->b, t->begin, t->end, t->depth, t->levels, &t->out);
	return NULL;
}

/* Appends subtree t's nodes to b's, renumbered (its node k becomes b's
 * node_count + k), and renumbers its root child *c the same way. */
static void append_subtree(struct builder *b, const struct subtree *t, struct child *c)
{
	int offset = b->node_count;

	for (int n = 0; n < t->b.node_count; n++) {
		struct rt_bvh_node *node = &b->nodes[offset + n];
		*node = t->b.nodes[n];
		for (int k = 0; k < 2; k++) {
			int32_t index, count;
			memcpy(&index, &node->child[k].lo.s[3], sizeof(index));
			memcpy(&count, &node->child[k].hi.s[3], sizeof(count));
			if (count == 0) {
				index += offset;
				memcpy(&node->child[k].lo.s[3], &index, sizeof(index));
			}
		}
	}
	if (c->count == 0)
		c->index += offset;
	b->node_count += t->b.node_count;
	b->depth = t->b.depth > b->depth ? t->b.depth : b->depth;
	b->max_leaf = t->b.max_leaf > b->max_leaf ? t->b.max_leaf : b->max_leaf;
}

/* Builds the children [begin, mid) into *left, on this thread, and [mid,
 * end) into *right on a thread of its own, both at depth with `levels`
 * levels of threads below. Returns 0, or -1 having built nothing when the
 * thread or its nodes cannot be had. */
static int build_children_threaded(struct builder *b, int begin, int mid, int end, int depth,
				   int levels, struct child *left, struct child *right)
{
	struct subtree t = {.b = *b, .begin = mid, .end = end, .depth = depth, .levels = levels};
	pthread_t thread;

	t.b.node_count = 0;
	t.b.nodes = malloc((size_t)(end - mid) * sizeof(*t.b.nodes));
	if (!t.b.nodes || pthread_create(&thread, NULL, build_subtree, &t) != 0) {
		free(t.b.nodes);
		return -1;
	}
	build_parallel(b, begin, mid, depth, levels, left);
	pthread_join(thread, NULL);
	*right = t.out;
	append_subtree(b, &t, right);
	free(t.b.nodes);
	return 0;
}

/* Builds range [begin, end) at depth into *out: a leaf, or a node made here
 * with its subtrees; the second subtree of each of the top `levels` levels
 * on a thread of its own when large enough (BVH_PARALLEL_MIN), and where a
 * thread or its nodes cannot be had, on this thread. */
static void build_parallel(struct builder *b, int begin, int end, int depth, int levels,
			   struct child *out)
{
	struct box centroids;

	/* One pass for both boxes: at a million triangles each pass over a
	 * range is a tenth of the build. */
	box_empty(&out->box);
	box_empty(&centroids);
	for (int i = begin; i < end; i++) {
		box_grow(&out->box, b->prims[i].lo, b->prims[i].hi);
		box_grow(&centroids, b->prims[i].centroid, b->prims[i].centroid);
	}
	int mid = choose_split(b, begin, end, &out->box, &centroids, depth, depth == 0);
	if (mid == begin) {
		out->index = begin;
		out->count = end - begin;
		b->depth = depth > b->depth ? depth : b->depth;
		b->max_leaf = out->count > b->max_leaf ? out->count : b->max_leaf;
		return;
	}
	int node = b->node_count++;
	struct child left, right;

	if (levels < 1 || end - mid < BVH_PARALLEL_MIN ||
	    build_children_threaded(b, begin, mid, end, depth + 1, levels - 1, &left, &right)) {
		build_parallel(b, begin, mid, depth + 1, levels - 1, &left);
		build_parallel(b, mid, end, depth + 1, levels - 1, &right);
	}
	store_child(&b->nodes[node].child[0], &left);
	store_child(&b->nodes[node].child[1], &right);
	out->index = node;
	out->count = 0;
}

int bvh_build(struct bvh_prim *prims, int count, struct bvh *out)
{
	return bvh_build_threaded(prims, count, BVH_TRIANGLE_COST, BVH_PARALLEL_LEVELS, out);
}

int bvh_build_threaded(struct bvh_prim *prims, int count, double triangle_cost, int levels,
		       struct bvh *out)
{
	struct builder b = {prims, NULL, 0, 0, 0, triangle_cost};
	struct child root;

	memset(out, 0, sizeof(*out));
	if (count == 0)
		return 0;
	/* A binary tree of count leaves has count - 1 nodes; one primitive
	 * still gets a root. */
	b.nodes = calloc((size_t)(count > 1 ? count - 1 : 1), sizeof(*b.nodes));
	out->refs = malloc((size_t)count * sizeof(*out->refs));
	if (!b.nodes || !out->refs) {
		free(b.nodes);
		free(out->refs);
		out->refs = NULL;
		return -1;
	}
	if (count == 1) {
		/* The root's two children are the one leaf: both tests give the
		 * same hit, and the traversal needs no empty child. */
		struct child leaf = {.index = 0, .count = 1};
		memcpy(leaf.box.lo, prims[0].lo, sizeof(leaf.box.lo));
		memcpy(leaf.box.hi, prims[0].hi, sizeof(leaf.box.hi));
		store_child(&b.nodes[0].child[0], &leaf);
		store_child(&b.nodes[0].child[1], &leaf);
		b.node_count = 1;
		b.depth = b.max_leaf = 1;
	} else {
		build_parallel(&b, 0, count, 0, levels, &root);
	}
	for (int i = 0; i < count; i++)
		out->refs[i] = prims[i].ref;
	out->nodes = b.nodes;
	out->node_count = b.node_count;
	out->ref_count = count;
	out->depth = b.depth;
	out->max_leaf = b.max_leaf;
	out->sah_cost = bvh_sah_cost(out, triangle_cost);
	out->leaf_triangles = 1;
	return 0;
}

/* How far a sphere's box is grown beyond the sphere: the tracer's box test
 * and sphere test round differently (fma slabs against the distance from
 * the centre in the ray's frame, docs/bvh.md), each off by a few float ulps
 * of the coordinates involved, 1e-7 relative. A margin 100 times that, of
 * the sphere's largest coordinate and radius, keeps every ray the sphere
 * test takes inside the box, and so the image equal to brute force's. */
#define BVH_SPHERE_PAD 1e-5

/* The box of a sphere whose centre is c in the device's coordinates. */
static void sphere_prim_at(const struct scene_sphere *sphere, const double c[3], int i,
			   struct bvh_prim *out)
{
	double r = sphere->radius;
	double scale = fmax(fmax(fabs(c[0]), fabs(c[1])), fabs(c[2])) + r;
	double reach = r + BVH_SPHERE_PAD * scale;

	for (int k = 0; k < 3; k++) {
		out->lo[k] = nextafterf((float)(c[k] - reach), -FLT_MAX);
		out->hi[k] = nextafterf((float)(c[k] + reach), FLT_MAX);
		out->centroid[k] = (float)c[k];
	}
	out->ref = RT_PRIM_SPHERE << RT_PRIM_KIND_SHIFT | (uint32_t)i;
}

void bvh_sphere_prim(const struct scene_sphere *sphere, int i, struct bvh_prim *out)
{
	sphere_prim_at(sphere, sphere->center, i, out);
}

/* A triangle's box is padded like a sphere's, by BVH_SPHERE_PAD of its
 * largest vertex coordinate: the Moller-Trumbore test and the box test round
 * differently, and the pad keeps every ray the triangle test takes inside the
 * box. It also gives an axis-aligned (flat) triangle a box of some thickness,
 * so that the slab test never meets a zero-width slab. The vertices are the
 * device's, rounded to float (host/layout/mesh_block.c); the triangle test takes the
 * edges between them in float, which the pad also covers. */
static void triangle_prim_at(const double corner[3][3], int i, struct bvh_prim *out)
{
	double v[3][3], scale = 0.0;

	for (int k = 0; k < 3; k++) {
		for (int j = 0; j < 3; j++) {
			v[j][k] = (float)corner[j][k];
			scale = fmax(scale, fabs(v[j][k]));
		}
	}
	double pad = BVH_SPHERE_PAD * scale;
	for (int k = 0; k < 3; k++) {
		double lo = fmin(fmin(v[0][k], v[1][k]), v[2][k]);
		double hi = fmax(fmax(v[0][k], v[1][k]), v[2][k]);
		out->lo[k] = nextafterf((float)(lo - pad), -FLT_MAX);
		out->hi[k] = nextafterf((float)(hi + pad), FLT_MAX);
		out->centroid[k] = (float)((v[0][k] + v[1][k] + v[2][k]) / 3.0);
	}
	out->ref = RT_PRIM_TRIANGLE << RT_PRIM_KIND_SHIFT | (uint32_t)i;
}

void bvh_triangle_prim(const struct scene_triangle *tri, int i, struct bvh_prim *out)
{
	triangle_prim_at(tri->v, i, out);
}

int bvh_build_scene(const struct scene *scene, double triangle_cost, struct bvh *out)
{
	int spheres = scene->sphere_count, n = spheres + scene->triangle_count;
	struct bvh_prim *prims = malloc((size_t)(n ? n : 1) * sizeof(*prims));

	if (!prims)
		return -1;
	/* In the device's coordinates, relative to the eye (scene_from_eye). */
	for (int i = 0; i < spheres; i++) {
		double c[3];
		scene_from_eye(scene, scene->spheres[i].center, c);
		sphere_prim_at(&scene->spheres[i], c, i, &prims[i]);
	}
	for (int i = 0; i < scene->triangle_count; i++) {
		double v[3][3];
		for (int j = 0; j < 3; j++)
			scene_from_eye(scene, scene->triangles[i].v[j], v[j]);
		triangle_prim_at((const double(*)[3])v, i, &prims[spheres + i]);
	}
	int ret = bvh_build_threaded(prims, n, triangle_cost, BVH_PARALLEL_LEVELS, out);
	free(prims);
	return ret;
}

static void load_child(const struct rt_bvh_box *in, struct box *box, int *index, int *count)
{
	int32_t i, n;

	for (int k = 0; k < 3; k++) {
		box->lo[k] = in->lo.s[k];
		box->hi[k] = in->hi.s[k];
	}
	memcpy(&i, &in->lo.s[3], sizeof(i));
	memcpy(&n, &in->hi.s[3], sizeof(n));
	*index = i;
	*count = n;
}

/* Sum over nodes of their area times BVH_NODE_COST, and over leaves of
 * their area times their primitives' costs (ref_cost), over the root's
 * area. */
double bvh_sah_cost(const struct bvh *bvh, double triangle_cost)
{
	struct box root, box;
	double sum = 0.0;
	int index, count;

	if (bvh->node_count == 0)
		return 0.0;
	box_empty(&root);
	for (int n = 0; n < bvh->node_count; n++) {
		for (int k = 0; k < 2; k++) {
			load_child(&bvh->nodes[n].child[k], &box, &index, &count);
			if (n == 0)
				box_grow(&root, box.lo, box.hi);
			double cost = count ? 0.0 : BVH_NODE_COST;
			for (int r = 0; r < count; r++)
				cost += ref_cost(bvh->refs[index + r], triangle_cost);
			sum += box_area(&box) * cost;
		}
	}
	double area = box_area(&root);
	return BVH_NODE_COST + (area > 0.0 ? sum / area : 0.0);
}

/* Child c of binary node n. */
static const struct rt_bvh_box *binary_child(const struct bvh *bvh, int n, int c)
{
	return &bvh->nodes[n].child[c];
}

static int box_index(const struct rt_bvh_box *b)
{
	int32_t i;

	memcpy(&i, &b->lo.s[3], sizeof(i));
	return i;
}

static int box_count(const struct rt_bvh_box *b)
{
	int32_t c;

	memcpy(&c, &b->hi.s[3], sizeof(c));
	return c;
}

/* An inner child: count 0 and a node index (an empty leaf, only beside a
 * root's single primitive, has index 0, the root, which no node has as a
 * child). */
static int is_inner(const struct rt_bvh_box *b)
{
	return box_count(b) == 0 && box_index(b) != 0;
}

static double half_area(const struct rt_bvh_box *b)
{
	double dx = b->hi.s[0] - b->lo.s[0], dy = b->hi.s[1] - b->lo.s[1],
	       dz = b->hi.s[2] - b->lo.s[2];

	return dx * dy + dy * dz + dz * dx;
}

/* Four-wide node w from binary node n: its children, inner ones opened,
 * largest first, while there is room; an inner child left gets the next
 * four-wide node (*next), filled the same way, depth first. */
static void widen_node(struct bvh *bvh, int n, int w, int *next)
{
	struct rt_bvh_box kids[4] = {*binary_child(bvh, n, 0), *binary_child(bvh, n, 1)};
	int count = 2;
	struct rt_bvh4_node *node = &bvh->wide[w];

	while (count < 4) {
		int open = -1;
		for (int k = 0; k < count; k++)
			if (is_inner(&kids[k]) &&
			    (open < 0 || half_area(&kids[k]) > half_area(&kids[open])))
				open = k;
		if (open < 0)
			break;
		int inner = box_index(&kids[open]);
		kids[open] = *binary_child(bvh, inner, 0);
		kids[count++] = *binary_child(bvh, inner, 1);
	}
	for (int k = 0; k < 4; k++) {
		const struct rt_bvh_box *b = &kids[k];
		float *lo[3] = {&node->lo_x.s[k], &node->lo_y.s[k], &node->lo_z.s[k]};
		float *hi[3] = {&node->hi_x.s[k], &node->hi_y.s[k], &node->hi_z.s[k]};
		for (int a = 0; a < 3; a++) {
			*lo[a] = k < count ? b->lo.s[a] : FLT_MAX;
			*hi[a] = k < count ? b->hi.s[a] : -FLT_MAX;
		}
		node->index[k] = k < count ? box_index(b) : 0;
		node->count[k] = k < count ? box_count(b) : RT_BVH4_EMPTY;
	}
	for (int k = 0; k < count; k++) {
		if (!is_inner(&kids[k]))
			continue;
		int child = (*next)++;
		node->index[k] = child;
		widen_node(bvh, box_index(&kids[k]), child, next);
	}
}

int bvh_widen(struct bvh *bvh)
{
	int next = 1;

	free(bvh->wide);
	bvh->wide = NULL;
	bvh->wide_count = 0;
	if (bvh->node_count == 0)
		return 0;
	/* Each four-wide node opens at least one binary node: never more. */
	bvh->wide = malloc((size_t)bvh->node_count * sizeof(*bvh->wide));
	if (!bvh->wide)
		return -1;
	widen_node(bvh, 0, 0, &next);
	bvh->wide_count = next;
	return 0;
}

void bvh_free(struct bvh *bvh)
{
	free(bvh->wide);
	free(bvh->nodes);
	free(bvh->refs);
	memset(bvh, 0, sizeof(*bvh));
}
