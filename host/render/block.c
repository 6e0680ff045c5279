#include "render/block.h"

#include <stdio.h>
#include <stdlib.h>

#include "layout/scene_block.h"
#include "base/quote.h"
#include "base/test_hooks.h"
#include "base/timing.h"

int block_check_scene_fits(const struct device *dev, const struct scene *scene,
			   const struct mesh_block *mesh, const struct bvh *bvh, char *err,
			   size_t err_size)
{
	size_t bytes = scene_block_bytes(scene, mesh, bvh);
	/* One buffer holds the whole block, whose offsets are 32-bit. */
	unsigned long long limit = dev->max_alloc_size < DEVSCENE_MAX_BYTES
					   ? (unsigned long long)dev->max_alloc_size
					   : (unsigned long long)DEVSCENE_MAX_BYTES;

	char textures[80] = "";

	if (bytes <= limit)
		return 0;
	if (scene->texture_count)
		snprintf(textures, sizeof(textures), ", %d texture%s of %zu bytes",
			 scene->texture_count, scene->texture_count == 1 ? "" : "s",
			 scene_texture_bytes(scene));
	snprintf(err, err_size,
		 "%s: the scene (%d triangles%s) needs %zu bytes of device "
		 "memory, more than the limit of %llu bytes in one buffer on %s (%s)",
		 quote_text(scene->source), scene->triangle_count, textures, bytes, limit, dev->name,
		 limit == dev->max_alloc_size ? "CL_DEVICE_MAX_MEM_ALLOC_SIZE"
					      : "rtcl's 32-bit scene offsets");
	return -1;
}

/* Builds the BVH of the scene's spheres and triangles for --accel (s) into
 * *bvh, with its figures in res. */
static int build_bvh(const struct scene *scene, const struct render_settings *s,
		     struct render_result *res, struct bvh *bvh, char *err, size_t err_size)
{
	double lap = timing_now();

	/* bvh-compact: triangles priced like spheres, as many per leaf as the
	 * builder's sphere leaves (docs/bvh.md, "Node cost per kind"). */
	double triangle_cost = s->accel == ACCEL_BVH_COMPACT ? 1.0 : BVH_TRIANGLE_COST;

	if (bvh_build_scene(scene, triangle_cost, bvh)) {
		snprintf(err, err_size,
			 "out of host memory for the BVH of %d spheres and %d triangles",
			 scene->sphere_count, scene->triangle_count);
		return -1;
	}
	res->bvh_build_ms = timing_lap_ms(&lap);
	bvh->leaf_triangles = s->accel != ACCEL_BVH_COMPACT;
	res->bvh_nodes = bvh->node_count;
	res->bvh_depth = bvh->depth;
	res->bvh_sah_cost = bvh->sah_cost;
	res->bvh_bytes = (size_t)bvh->node_count * sizeof(*bvh->nodes) +
			 (size_t)bvh->ref_count * sizeof(*bvh->refs);
	if (bvh->leaf_triangles) /* the triangles again, in leaf order */
		res->bvh_bytes += (size_t)scene->triangle_count * sizeof(struct rt_leaf_triangle);
	return 0;
}

/* Device bytes per triangle (issue 11's budget: 64, which --accel
 * bvh-compact keeps): the whole scene block over the triangles, and the
 * shares of the triangles, their vertices and the BVH (with its leaf
 * triangles). */
static void print_triangle_bytes(const struct scene *scene, const struct render_result *res)
{
	double n = scene->triangle_count;
	size_t vertex_bytes = sizeof(struct rt_vertex) + sizeof(struct rt_vertex_normal);

	fprintf(stderr,
		"rtcl: device scene block %zu bytes for %d triangles: %.1f bytes per triangle "
		"(%zu triangle, %.1f vertices (%d), %.1f BVH)\n",
		res->scene_bytes, scene->triangle_count, res->scene_bytes / n,
		sizeof(struct rt_triangle), res->vertex_count * vertex_bytes / n, res->vertex_count,
		res->bvh_bytes / n);
}

/* The scene's triangles indexed (the mesh block) and its BVH (with use_bvh), checked
 * to fit on dev and packed into *block. */
static int pack_scene(struct device *dev, const struct scene *scene,
		      const struct render_settings *s, int use_bvh, struct render_result *res,
		      void **block, char *err, size_t err_size)
{
	struct bvh bvh = {0};
	struct mesh_block mesh;
	int ret = -1;

	if (mesh_block_build(scene, &mesh)) {
		snprintf(err, err_size, "out of host memory for the %d triangles' vertices",
			 scene->triangle_count);
		return -1;
	}
	res->vertex_count = mesh.vertex_count;
	if (use_bvh && build_bvh(scene, s, res, &bvh, err, err_size))
		goto free_mesh;
	/* A CPU device traverses a four-wide tree (docs/bvh.md, "A four-wide
	 * tree on CPUs") of a tree large enough; GPUs and the counting build,
	 * whose node visits and box tests are the binary tree's on every
	 * device, the binary one. */
	if (use_bvh && !dev->is_gpu && !s->count_flops && bvh.node_count >= BVH_WIDE_MIN_NODES &&
	    !hook_binary_bvh()) {
		if (bvh_widen(&bvh)) {
			snprintf(err, err_size, "out of host memory for the four-wide BVH");
			goto free_bvh;
		}
		res->bvh_bytes += (size_t)bvh.wide_count * sizeof(*bvh.wide) -
				  (size_t)bvh.node_count * sizeof(*bvh.nodes);
	}
	res->bvh_width = !use_bvh || bvh.node_count == 0 ? 0 : bvh.wide ? 4 : 2;
	res->bvh_device_nodes = bvh.wide ? bvh.wide_count : bvh.node_count;
	if (block_check_scene_fits(dev, scene, &mesh, use_bvh ? &bvh : NULL, err, err_size))
		goto free_bvh;
	/* Without its texels: buffers_create writes them from the scene. */
	*block = scene_block_pack_head(scene, &mesh, use_bvh ? &bvh : NULL, s->width, s->height,
				       s->max_depth, &res->scene_bytes);
	if (!*block)
		snprintf(err, err_size, "out of host memory for the scene's %zu bytes",
			 scene_block_bytes(scene, &mesh, use_bvh ? &bvh : NULL));
	else
		ret = 0;
free_bvh:
	bvh_free(&bvh);
free_mesh:
	mesh_block_free(&mesh);
	return ret;
}

int block_prepare_scene(struct device *dev, const struct scene *scene,
			const struct render_settings *s, struct render_result *res, void **block,
			char *err, size_t err_size)
{
	int use_bvh =
		s->accel != ACCEL_NONE && (scene->sphere_count > 0 || scene->triangle_count > 0);

	*block = NULL;
	if (scene_block_check_resolution(scene, err, err_size) ||
	    pack_scene(dev, scene, s, use_bvh, res, block, err, err_size))
		return -1;
	res->rgb = malloc(image_float_bytes(s->width, s->height));
	if (!res->rgb) {
		snprintf(err, err_size, "out of host memory for a %dx%d image", s->width,
			 s->height);
		return -1;
	}
	/* A third at most: every work-group holds its own copy, and a larger
	 * one leaves too few groups per compute unit. On the H100 (48 KiB) a
	 * 41 KiB block in __local memory ran 1.5 times slower than from
	 * __global (400 balls with their BVH), a 9 KiB one 6 % faster
	 * (docs/bvh.md). */
	res->scene_in_local =
		!s->force_global_scene &&
		(res->scene_bytes + LOCAL_MEM_RESERVE) * LOCAL_MEM_SHARE <= dev->local_mem_size;
	if (s->verbose && (scene->triangle_count || scene->skipped_triangles))
		fprintf(stderr,
			"rtcl: %d triangles; %ld of area 0 (after placement) skipped from mesh "
			"files\n",
			scene->triangle_count, scene->skipped_triangles);
	if (s->verbose && use_bvh)
		fprintf(stderr,
			"rtcl: BVH of %d sphere%s and %d triangle%s: %d nodes, depth %d, SAH cost "
			"%.2f, built in %.3f ms\n",
			scene->sphere_count, scene->sphere_count == 1 ? "" : "s",
			scene->triangle_count, scene->triangle_count == 1 ? "" : "s",
			res->bvh_nodes, res->bvh_depth, res->bvh_sah_cost, res->bvh_build_ms);
	if (s->verbose && scene->triangle_count)
		print_triangle_bytes(scene, res);
	if (s->verbose)
		fprintf(stderr, "rtcl: scene is %zu bytes; %s\n", res->scene_bytes,
			res->scene_in_local
				? "copied into __local memory by each work-group"
				: "read from __global memory (it would take more than a third of "
				  "__local memory)");
	return 0;
}
