/* The bounding volume hierarchy (docs/bvh.md): a binned surface-area-heuristic
 * builder over a generic list of primitive boxes, flattened into the
 * two-wide device layout of cl/rtcl_shared.h (struct rt_bvh_node). A scene's
 * spheres and triangles enter through bvh_build_scene; any other bounded
 * primitive needs only its box, centroid and reference (RT_PRIM_*). */
#ifndef RTCL_BVH_H
#define RTCL_BVH_H

#include <stdint.h>

#include "rtcl_shared.h"
#include "scene/scene.h"

/* One primitive as the builder sees it: its box (already padded, see
 * bvh_sphere_prim), its centroid and its reference (kind and index). */
struct bvh_prim {
	float lo[3], hi[3];
	float centroid[3];
	uint32_t ref;
};

struct bvh {
	struct rt_bvh_node *nodes; /* node 0 the root; none for no primitive */
	int node_count;
	uint32_t *refs; /* each primitive's reference, exactly once, leaf by leaf */
	/* Packing (host/layout/scene_block.c): the triangles also in leaf order
	 * with their vertex positions inline, 48 bytes each (bvh_build sets it;
	 * --accel bvh-compact clears it). */
	int leaf_triangles;
	int ref_count;
	int depth;	 /* of the deepest leaf, the root's children at 1 */
	int max_leaf;	 /* most references in one leaf */
	double sah_cost; /* bvh_sah_cost of the tree */
	/* bvh_widen: the tree as four-wide nodes, node 0 the root; NULL until. */
	struct rt_bvh4_node *wide;
	int wide_count;
};

/* Leaves hold at most this many primitives. With BVH_NODE_COST 3 (a node
 * visit, two box tests and a stack step, against one sphere test) the
 * default scene ran 7 % faster on the H100 than with cost 1 and leaves of
 * 4, 2,000 balls the same, 20,000 balls 2 % slower (docs/bvh.md). */
#ifndef BVH_MAX_LEAF
#define BVH_MAX_LEAF 8
#endif
/* SAH bins per axis. */
#define BVH_BINS 16

/* Builds the BVH of prims[0..count) into *out (count may be 0: no node).
 * prims is reordered. Returns 0, or -1 when out of memory. */
int bvh_build(struct bvh_prim *prims, int count, struct bvh *out);

/* bvh_build with a triangle test costing triangle_cost sphere tests in the
 * SAH (BVH_TRIANGLE_COST for bvh_build) and subtrees built on threads of
 * their own down to `levels` levels (bvh.c: BVH_PARALLEL_LEVELS for
 * bvh_build; 0: one thread). The tree is the same whatever levels; the tests
 * compare. */
int bvh_build_threaded(struct bvh_prim *prims, int count, double triangle_cost, int levels,
		       struct bvh *out);

/* The BVH of the scene's spheres and triangles, in one hierarchy, in the
 * device's coordinates: relative to the camera's eye (scene_from_eye), a
 * triangle test costing triangle_cost sphere tests (BVH_TRIANGLE_COST; 1 for
 * --accel bvh-compact). Returns 0, or -1 when out of memory. */
int bvh_build_scene(const struct scene *scene, double triangle_cost, struct bvh *out);

/* Sphere i of the scene as a primitive, its box padded outward (bvh.c says
 * by how much and why), in the sphere's own coordinates (an eye at the
 * origin). */
void bvh_sphere_prim(const struct scene_sphere *sphere, int i, struct bvh_prim *out);

/* Triangle i of the scene as a primitive, its box padded outward too. */
void bvh_triangle_prim(const struct scene_triangle *tri, int i, struct bvh_prim *out);

/* The tree's SAH cost, in units of one sphere test, with a node visit
 * (two box tests) costing BVH_NODE_COST and a triangle test
 * BVH_TRIANGLE_COST: what a ray through the root's box expects to spend. */
double bvh_sah_cost(const struct bvh *bvh, double triangle_cost);
#ifndef BVH_NODE_COST
#define BVH_NODE_COST 3.0
#endif
/* A triangle test against a sphere test's 1: as dear as a node visit, so
 * that a range of triangles is split as a node cost of 1 would split it.
 * On the H100 (docs/bvh.md, batch 40) that tested 2.3 times fewer triangles
 * per ray on the SPD mount meshes and the lake than BVH_NODE_COST 3 did, and
 * ran 1.15-1.27 times faster; spheres keep BVH_NODE_COST 3, which a node
 * cost of 1 made 8 % slower on the default scene. */
#ifndef BVH_TRIANGLE_COST
#define BVH_TRIANGLE_COST 3.0
#endif

/* A CPU device takes the four-wide tree (bvh_widen) when the binary tree
 * has at least this many nodes; a smaller tree has few visits to save, and a
 * four-wide visit's sorting costs more than it saves (PoCL on the 2-core VM,
 * docs/results/pocl-cpu-bvh4: the default scene's 16 nodes 7 % slower, 400
 * balls' 106 1-2 % slower, scenes/glass_mesh.json's 173 9 % faster, SPD
 * tetra 8's 1.31x). */
#define BVH_WIDE_MIN_NODES 128

/* Collapses the binary tree into four-wide nodes (struct rt_bvh4_node, for
 * CPU devices: docs/bvh.md, "A four-wide tree on CPUs") in bvh->wide: each
 * node takes its binary node's two children and replaces an inner one by
 * its two, the one of largest surface area first, until it has four or only
 * leaves; the leaves and their references are the binary tree's. Returns 0
 * (also for a tree without nodes, which stays without), or -1 when out of
 * memory. */
int bvh_widen(struct bvh *bvh);

void bvh_free(struct bvh *bvh);

#endif
