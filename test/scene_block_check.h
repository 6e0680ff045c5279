/* The property the scene fuzzer checks on every accepted scene, shared by
 * test/fuzz_scene.c and test/test_fuzz_regressions.c: the device layout
 * from scene_block_pack holds only numbers the tracer can use. inf or NaN there,
 * or a radius, epsilon, ior or checker size that rounded to 0 in float,
 * would render a silently wrong picture. */
#ifndef RTCL_TEST_DEVSCENE_CHECK_H
#define RTCL_TEST_DEVSCENE_CHECK_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rtcl_shared.h"

static int vec4_finite(rt_vec4 v)
{
	return isfinite(v.s[0]) && isfinite(v.s[1]) && isfinite(v.s[2]) && isfinite(v.s[3]);
}

static int float_positive(float x)
{
	return isfinite(x) && x > 0;
}

/* The triangles: vertices and normals finite, each index within the vertex
 * array (between vertex_offset and normal_offset) and each material one
 * the scene has. */
static const char *triangles_problem(const void *packed)
{
	const unsigned char *block = packed;
	const struct rt_scene *h = packed;
	const struct rt_triangle *t = (const void *)(block + h->triangle_offset);
	const struct rt_vertex *v = (const void *)(block + h->vertex_offset);
	const struct rt_vertex_normal *n = (const void *)(block + h->normal_offset);
	rt_uint vertices = (h->normal_offset - h->vertex_offset) / sizeof(*v);

	for (rt_uint i = 0; i < vertices; i++)
		if (!vec4_finite(v[i].position) || !vec4_finite(n[i].normal))
			return "vertex or normal not finite";
	for (int i = 0; i < h->triangle_count; i++) {
		for (int k = 0; k < 3; k++)
			if (t[i].index.s[k] >= vertices)
				return "triangle vertex index out of range";
		if ((int)(t[i].index.s[3] & ~RT_TRIANGLE_SMOOTH) >= h->material_count)
			return "triangle material out of range";
	}
	return NULL;
}

/* A leaf's references name primitives the scene has. */
static const char *refs_problem(const struct rt_scene *h, const rt_uint *refs, int first, int count)
{
	for (int r = first; r < first + count; r++) {
		int index = (int)(refs[r] & RT_PRIM_INDEX_MASK);
		if (refs[r] >> RT_PRIM_KIND_SHIFT == RT_PRIM_SPHERE ? index >= h->sphere_count
								     : index >= h->triangle_count)
			return "BVH reference out of range";
	}
	return NULL;
}

/* A range of leaf triangles (RT_LEAF_TRIANGLES) within their array, each
 * naming a triangle the scene has, its vertices finite. */
static const char *leaf_triangles_problem(const struct rt_scene *h, int index, int count)
{
	const unsigned char *block = (const void *)h;
	const struct rt_leaf_triangle *t = (const void *)(block + h->bvh_triangle_offset);
	size_t slots = (h->uv_offset - h->bvh_triangle_offset) / sizeof(*t);

	if ((size_t)index + (size_t)count > slots)
		return "BVH triangle leaf out of range";
	for (int k = index; k < index + count; k++) {
		int i;
		memcpy(&i, &t[k].v0.s[3], sizeof(i));
		if (i < 0 || i >= h->triangle_count)
			return "leaf triangle naming no triangle";
		for (int c = 0; c < 3; c++)
			if (!isfinite(t[k].v0.s[c]) || !isfinite(t[k].v1.s[c]) ||
			    !isfinite(t[k].v2.s[c]))
				return "leaf triangle vertex not finite";
	}
	return NULL;
}

/* One child of BVH node n (width 2 or 4): a later node, a range of spheres
 * (RT_LEAF_SPHERES), of leaf triangles (RT_LEAF_TRIANGLES) or of references
 * within their arrays, naming primitives the scene has. */
static const char *bvh_child_problem(const struct rt_scene *h, const rt_uint *refs, int ref_slots,
				     int n, int index, int count)
{
	int leaf_count = count & RT_LEAF_COUNT_MASK;

	if (count == 0 && index == 0 && n == 0)
		return NULL; /* an empty leaf beside a single primitive */
	if (count == 0 && (index <= n || index >= h->bvh_node_count))
		return "BVH child node out of range";
	if (count < 0 || index < 0)
		return "BVH child negative";
	if ((count & RT_LEAF_SPHERES) && index + leaf_count > h->sphere_count)
		return "BVH sphere leaf out of range";
	if (count & RT_LEAF_TRIANGLES)
		return leaf_triangles_problem(h, index, leaf_count);
	if (count > 0 && !(count & RT_LEAF_SPHERES)) {
		if (index + count > ref_slots)
			return "BVH leaf references out of range";
		return refs_problem(h, refs, index, count);
	}
	return NULL;
}

/* The BVH: its nodes binary (struct rt_bvh_node) or, on a CPU,
 * four-wide (struct rt_bvh4_node, empty slots RT_BVH4_EMPTY), filling their
 * array; every child as bvh_child_problem wants; the spheres' scene indices
 * (leaf order, host/layout/scene_block.c) each scene index once. */
static const char *bvh_problem(const void *packed)
{
	const unsigned char *block = packed;
	const struct rt_scene *h = packed;
	const struct rt_bvh_node *nodes = (const void *)(block + h->bvh_node_offset);
	const struct rt_bvh4_node *wide = (const void *)(block + h->bvh_node_offset);
	const struct rt_sphere *s = (const void *)(block + h->sphere_offset);
	const rt_uint *refs = (const void *)(block + h->bvh_ref_offset);
	int ref_slots = (int)((h->bvh_triangle_offset - h->bvh_ref_offset) / sizeof(rt_uint));
	int seen_all = 1;
	char *seen = calloc((size_t)h->sphere_count + 1, 1);
	size_t node_bytes = h->bvh_width == 4 ? sizeof(*wide) : sizeof(*nodes);

	if (h->bvh_node_count > 0 ? h->bvh_width != 2 && h->bvh_width != 4 : h->bvh_width != 0)
		return "BVH width neither 2 nor 4";
	if (h->bvh_ref_offset - h->bvh_node_offset != (size_t)h->bvh_node_count * node_bytes)
		return "BVH nodes do not fill their array";
	for (int i = 0; seen && i < h->sphere_count; i++) {
		int k = s[i].scene_index;
		if (k < 0 || k >= h->sphere_count || seen[k])
			seen_all = 0;
		else
			seen[k] = 1;
	}
	free(seen);
	if (!seen_all)
		return "sphere scene indices not a permutation";
	for (int n = 0; n < h->bvh_node_count; n++)
		for (int c = 0; c < h->bvh_width; c++) {
			int index, count;
			if (h->bvh_width == 4) {
				index = wide[n].index[c];
				count = wide[n].count[c];
				if (count == RT_BVH4_EMPTY)
					continue;
			} else {
				memcpy(&index, &nodes[n].child[c].lo.s[3], sizeof(index));
				memcpy(&count, &nodes[n].child[c].hi.s[3], sizeof(count));
			}
			const char *problem = bvh_child_problem(h, refs, ref_slots, n, index, count);
			if (problem)
				return problem;
		}
	return NULL;
}

/* The textures' arrays (RENDERING.md, "Textures"): in order after the
 * leaf triangles, empty or a coordinate pair per vertex, a map per material
 * naming textures the block has, each texture's texels inside the block and
 * after the decode table, whose entries lie in 0 ... 1. */
static const char *textures_problem(const struct rt_scene *h)
{
	const unsigned char *block = (const void *)h;
	size_t vertices = (h->normal_offset - h->vertex_offset) / sizeof(struct rt_vertex);

	/* The path integrator's arrays follow the textures' (path_problem), but
	 * for the texels, which come last. */
	size_t end = h->path_offset ? h->path_offset : h->total_bytes;

	if (h->uv_offset < h->bvh_triangle_offset || h->material_map_offset < h->uv_offset ||
	    h->texture_offset < h->material_map_offset ||
	    h->texture_table_offset < h->texture_offset || end < h->texture_table_offset)
		return "texture arrays out of order";
	if (h->material_map_offset == h->uv_offset) /* no textures */
		return end - h->uv_offset < 16 && (h->path_offset || end == h->uv_offset) &&
				       h->texture_count == 0
			       ? NULL
			       : "texture arrays without their maps";
	const struct rt_vertex_uv *uv = (const void *)(block + h->uv_offset);
	const struct rt_material_map *map = (const void *)(block + h->material_map_offset);
	const struct rt_texture *t = (const void *)(block + h->texture_offset);
	const float *table = (const void *)(block + h->texture_table_offset);
	size_t texels = h->texture_table_offset + RT_TEXTURE_TABLE * sizeof(float);

	if (h->material_map_offset - h->uv_offset < vertices * sizeof(*uv) ||
	    h->texture_offset - h->material_map_offset !=
		    (size_t)h->material_count * sizeof(*map) ||
	    h->texture_table_offset - h->texture_offset != (size_t)h->texture_count * sizeof(*t) ||
	    end < texels)
		return "texture arrays of the wrong size";
	for (size_t i = 0; i < vertices; i++)
		if (!isfinite(uv[i].u) || !isfinite(uv[i].v))
			return "texture coordinates not finite";
	for (int i = 0; i < h->material_count; i++)
		if (map[i].texture < -1 || map[i].texture >= h->texture_count ||
		    map[i].alpha_texture < -1 || map[i].alpha_texture >= h->texture_count ||
		    !(map[i].alpha_cutoff >= 0) || !isfinite(map[i].alpha_cutoff) ||
		    !(map[i].alpha_scale >= 0 && map[i].alpha_scale <= 1))
			return "material map out of range";
	for (int i = 0; i < RT_TEXTURE_TABLE; i++)
		if (!(table[i] >= 0 && table[i] <= 1))
			return "texture decode table out of 0 ... 1";
	for (int i = 0; i < h->texture_count; i++) {
		size_t size = t[i].flags & RT_TEXTURE_FLOAT ? 16 : 4;
		if (t[i].width < 1 || t[i].height < 1 || t[i].width > 16384 ||
		    t[i].height > 16384 || (t[i].flags & RT_WRAP_MASK) > RT_WRAP_MIRROR ||
		    ((t[i].flags >> RT_WRAP_T_SHIFT) & RT_WRAP_MASK) > RT_WRAP_MIRROR)
			return "texture size or wrap mode out of range";
		/* The texels last, after the path integrator's arrays too. */
		if (t[i].offset % 16 || t[i].offset < texels ||
		    (h->path_offset && t[i].offset < h->path_offset) ||
		    t[i].offset + (size_t)t[i].width * t[i].height * size > h->total_bytes)
			return "texture texels outside the block";
	}
	return NULL;
}

/* The path integrator's arrays (cl/rtcl_shared.h, struct rt_path), where
 * the block has them: inside the block, a BSDF per material of finite
 * numbers and texture indices the block has, the emitters' primitives the
 * scene has and their cdf rising to 1, the environment map's cdfs within
 * 0 ... 1 and ending at 1, its texels finite. */
static const char *path_problem(const struct rt_scene *h)
{
	const unsigned char *block = (const void *)h;
	const struct rt_path *path = (const void *)(block + h->path_offset);

	if (!h->path_offset)
		return NULL;
	if (h->path_offset % 16 || h->path_offset + sizeof(*path) > h->total_bytes ||
	    path->bsdf_offset + (size_t)h->material_count * sizeof(struct rt_bsdf) > h->total_bytes ||
	    path->emitter_offset + (size_t)path->emitter_count * sizeof(struct rt_emitter) >
		    h->total_bytes)
		return "path arrays outside the block";
	const struct rt_bsdf *b = (const void *)(block + path->bsdf_offset);
	for (int i = 0; i < h->material_count; i++)
		if (!vec4_finite(b[i].color) || !vec4_finite(b[i].emission) ||
		    !(b[i].type >= RT_BSDF_MAPPED && b[i].type <= RT_BSDF_PRINCIPLED) ||
		    !(b[i].emission.s[3] > 0) || !(b[i].color.s[3] >= 0) ||
		    b[i].metallic_roughness_texture >= h->texture_count ||
		    b[i].emissive_texture >= h->texture_count ||
		    b[i].normal_texture >= h->texture_count)
			return "BSDF out of range";
	const struct rt_emitter *e = (const void *)(block + path->emitter_offset);
	float before = 0;
	for (int i = 0; i < path->emitter_count; i++) {
		int index = (int)(e[i].prim & RT_PRIM_INDEX_MASK);
		if (e[i].prim >> RT_PRIM_KIND_SHIFT == RT_PRIM_SPHERE ? index >= h->sphere_count
									: index >= h->triangle_count)
			return "emitter naming no primitive";
		if (!(e[i].cdf >= before && e[i].cdf <= 1))
			return "emitter cdf not rising within 0 ... 1";
		before = e[i].cdf;
	}
	if (path->emitter_count && (e[path->emitter_count - 1].cdf != 1 ||
				    !float_positive(path->inv_emitter_weight)))
		return "emitter cdf not ending at 1";
	if (path->group_count < 0 || path->group_count > h->light_count + 2)
		return "light groups out of range";
	if (path->environment != RT_ENVIRONMENT_MAP)
		return NULL;
	size_t texels = (size_t)path->env_width * path->env_height;
	if (path->env_width < 1 || path->env_height < 1 ||
	    path->env_texel_offset + texels * sizeof(rt_vec4) > h->total_bytes ||
	    path->env_row_cdf_offset + (size_t)path->env_height * 4 > h->total_bytes ||
	    path->env_column_cdf_offset + texels * 4 > h->total_bytes)
		return "environment map outside the block";
	const rt_vec4 *t = (const void *)(block + path->env_texel_offset);
	const float *rows = (const void *)(block + path->env_row_cdf_offset);
	const float *columns = (const void *)(block + path->env_column_cdf_offset);
	for (size_t i = 0; i < texels; i++)
		if (!vec4_finite(t[i]) || !(columns[i] >= 0 && columns[i] <= 1))
			return "environment texel or cdf out of range";
	for (int k = 0; k < path->env_height; k++)
		if (!(rows[k] >= 0 && rows[k] <= 1) || columns[(size_t)k * path->env_width +
							       path->env_width - 1] != 1)
			return "environment cdf out of range";
	return rows[path->env_height - 1] == 1 ? NULL : "environment cdf not ending at 1";
}

/* Returns NULL when the packed scene is usable, else what is wrong. */
static const char *scene_block_problem(const void *packed)
{
	const unsigned char *block = packed;
	const struct rt_scene *h = packed;
	const struct rt_material *m = (const void *)(block + h->material_offset);
	const struct rt_sphere *s = (const void *)(block + h->sphere_offset);
	const struct rt_plane *p = (const void *)(block + h->plane_offset);
	const struct rt_light *l = (const void *)(block + h->light_offset);

	if (!vec4_finite(h->eye) || !vec4_finite(h->forward) || !vec4_finite(h->right) ||
	    !vec4_finite(h->up))
		return "camera not finite";
	/* The scalars in w lanes (cl/rtcl_shared.h): the half-extents, epsilon. */
	if (!float_positive(h->forward.s[3]) || !float_positive(h->eye.s[3]))
		return "image half-extent not positive";
	if (!float_positive(h->right.s[3]))
		return "epsilon not positive in float";
	if (!vec4_finite(h->background) || !vec4_finite(h->ambient))
		return "background or ambient not finite";
	for (int i = 0; i < h->material_count; i++) {
		if (!vec4_finite(m[i].color) || !isfinite(m[i].diffuse) ||
		    !isfinite(m[i].specular) || !isfinite(m[i].shininess) ||
		    !isfinite(m[i].reflect) || !isfinite(m[i].transmit))
			return "material not finite";
		if (!float_positive(m[i].ior) || !float_positive(m[i].inv_ior))
			return "ior or 1/ior not positive in float";
	}
	for (int i = 0; i < h->sphere_count; i++) {
		if (!vec4_finite(s[i].center))
			return "sphere not finite";
		if (!float_positive(s[i].radius) || !float_positive(s[i].center.s[3]) ||
		    !float_positive(s[i].inv_radius))
			return "radius, radius² or 1/radius not positive in float";
	}
	for (int i = 0; i < h->plane_count; i++) {
		if (!vec4_finite(p[i].normal) || !vec4_finite(p[i].checker_color))
			return "plane not finite";
		if (p[i].has_checker && !float_positive(p[i].checker_color.s[3]))
			return "checker size not positive in float";
	}
	for (int i = 0; i < h->light_count; i++)
		if (!vec4_finite(l[i].position) || !vec4_finite(l[i].color))
			return "light not finite";
	const char *problem = triangles_problem(packed);
	if (!problem)
		problem = textures_problem(h);
	if (!problem)
		problem = path_problem(h);
	return problem ? problem : bvh_problem(packed);
}

#endif
