/* Build time and SAH cost: rtcl's binned SAH builder (host/bvh.c) against
 * Embree 3's rtcBuildBVH (libembree-dev), two-wide, leaves of up to 4, on the
 * same padded sphere boxes; best of 5 builds, one thread ("threads=1").
 * Built from the repository root after make:
 *   cc -O2 -std=c11 -D_DEFAULT_SOURCE -Ihost -Icl -DCL_TARGET_OPENCL_VERSION=120 -include math.h \
 *      docs/results/bvh/embree_compare.c build/bvh.o build/scene.o build/scene_check.o \
 *      build/scene_literal.o build/files.o build/interrupt.o -lembree3 -ljansson -lm -pthread
 *   ./a.out SCENE.json threads=1
 * Results: embree_compare.txt beside it. */
#include <embree3/rtcore.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "bvh.h"
#include "scene.h"

struct enode { int leaf; int count; struct RTCBounds b[2]; void *child[2]; };
static void *create_node(RTCThreadLocalAllocator a, unsigned n, void *u) {
	(void)n; (void)u; struct enode *x = rtcThreadLocalAlloc(a, sizeof(struct enode), 16); memset(x, 0, sizeof(*x)); return x; }
static void set_children(void *p, void **c, unsigned n, void *u) { (void)u; struct enode *x = p; for (unsigned i = 0; i < n; i++) x->child[i] = c[i]; x->count = n; }
static void set_bounds(void *p, const struct RTCBounds **b, unsigned n, void *u) { (void)u; struct enode *x = p; for (unsigned i = 0; i < n; i++) x->b[i] = *b[i]; }
static void *create_leaf(RTCThreadLocalAllocator a, const struct RTCBuildPrimitive *pr, size_t n, void *u) {
	(void)pr; (void)u; struct enode *x = rtcThreadLocalAlloc(a, sizeof(struct enode), 16); memset(x, 0, sizeof(*x)); x->leaf = 1; x->count = (int)n; return x; }
static double area(const struct RTCBounds *b) { double e0 = b->upper_x - b->lower_x, e1 = b->upper_y - b->lower_y, e2 = b->upper_z - b->lower_z; return e0 * e1 + e1 * e2 + e2 * e0; }
static double sum(const struct enode *x, double a, int *nodes) {
	if (x->leaf) return a * x->count;
	(*nodes)++;
	double s = a; /* the node, then its children */
	for (int i = 0; i < x->count; i++) s += sum(x->child[i], area(&x->b[i]), nodes);
	return s;
}
static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec * 1e3 + t.tv_nsec * 1e-6; }

int main(int argc, char **argv) {
	RTCDevice dev = rtcNewDevice(argc > 2 ? argv[2] : NULL);
	for (int f = 1; f < 2; f++) {
		struct scene s; char err[512];
		if (scene_load_file(&s, argv[f], err, sizeof(err))) { fprintf(stderr, "%s\n", err); return 1; }
		int n = s.sphere_count;
		struct bvh_prim *pr = malloc(n * sizeof(*pr));
		double best = 1e30; struct bvh tree;
		for (int r = 0; r < 5; r++) {
			for (int i = 0; i < n; i++) bvh_sphere_prim(&s.spheres[i], i, &pr[i]);
			double t0 = now(); bvh_build(pr, n, &tree); double t = now() - t0; if (t < best) best = t;
			if (r < 4) bvh_free(&tree);
		}
		printf("%6d balls  rtcl binned SAH: %8.3f ms, SAH cost %.2f, %d nodes\n", n, best, tree.sah_cost, tree.node_count);
		bvh_free(&tree);
		const char *qn[] = {"LOW", "MEDIUM", "HIGH"};
		enum RTCBuildQuality q[] = {RTC_BUILD_QUALITY_LOW, RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_HIGH};
		struct RTCBuildPrimitive *bp = aligned_alloc(32, ((n * 2 * sizeof(*bp)) + 31) / 32 * 32);
		for (int k = 0; k < 3; k++) {
			double eb = 1e30, cost = 0; int nodes = 0;
			for (int r = 0; r < 5; r++) {
				for (int i = 0; i < n; i++) {
					bvh_sphere_prim(&s.spheres[i], i, &pr[i]);
					bp[i] = (struct RTCBuildPrimitive){pr[i].lo[0], pr[i].lo[1], pr[i].lo[2], 0, pr[i].hi[0], pr[i].hi[1], pr[i].hi[2], (unsigned)i};
				}
				RTCBVH bvh = rtcNewBVH(dev);
				struct RTCBuildArguments a = rtcDefaultBuildArguments();
				a.buildQuality = q[k]; a.maxBranchingFactor = 2; a.maxLeafSize = 4; a.maxDepth = 64;
				a.bvh = bvh; a.primitives = bp; a.primitiveCount = n; a.primitiveArrayCapacity = n * 2;
				a.createNode = create_node; a.setNodeChildren = set_children; a.setNodeBounds = set_bounds; a.createLeaf = create_leaf;
				double t0 = now(); struct enode *root = rtcBuildBVH(&a); double t = now() - t0; if (t < eb) eb = t;
				if (r == 4) {
					struct RTCBounds rb = root->b[0];
					rb.lower_x = fminf(rb.lower_x, root->b[1].lower_x); rb.lower_y = fminf(rb.lower_y, root->b[1].lower_y); rb.lower_z = fminf(rb.lower_z, root->b[1].lower_z);
					rb.upper_x = fmaxf(rb.upper_x, root->b[1].upper_x); rb.upper_y = fmaxf(rb.upper_y, root->b[1].upper_y); rb.upper_z = fmaxf(rb.upper_z, root->b[1].upper_z);
					double ra = area(&rb);
					cost = sum(root, ra, &nodes) / ra;
				}
				rtcReleaseBVH(bvh);
			}
			printf("%6d balls  Embree %-6s   : %8.3f ms, SAH cost %.2f, %d nodes\n", n, qn[k], eb, cost, nodes);
		}
		scene_free(&s);
	}
	rtcReleaseDevice(dev);
	return 0;
}
