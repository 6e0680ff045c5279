/* Indexing the scene's triangles for the device (docs/bvh.md, "Triangle
 * storage"). The loader gives every triangle its own three vertices and
 * normals in double; the device gets each distinct vertex once, found with a
 * hash table on the vertex's position and normal as the device stores them. */
#include "layout/mesh_block.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The words a vertex is told apart by, as the device stores it: its
 * position and its normal (0 on flat triangles, whose vertices carry none),
 * rounded to float. */
struct vertex_key {
	rt_vec4 position, normal;
	struct rt_vertex_uv uv; /* 0 without textures */
};

/* uv: the triangle's texture coordinates, or NULL. */
static void vertex_key(const struct scene *scene, const struct scene_triangle *tri,
		       const struct scene_triangle_uv *uv, int k, struct vertex_key *out)
{
	double position[3];

	memset(out, 0, sizeof(*out));
	scene_from_eye(scene, tri->v[k], position);
	for (int i = 0; i < 3; i++) {
		out->position.s[i] = (float)position[i];
		if (tri->smooth)
			out->normal.s[i] = (float)tri->normal[k][i];
	}
	if (uv) {
		out->uv.u = (float)uv->uv[k][0];
		out->uv.v = (float)uv->uv[k][1];
	}
}

static uint32_t vertex_hash(const struct vertex_key *v)
{
	uint32_t words[10], h = 2166136261u;

	memcpy(words, v, sizeof(words));
	for (int i = 0; i < 10; i++) {
		h = (h ^ words[i]) * 0x9e3779b1u;
		h ^= h >> 15;
	}
	return h;
}

struct vertex_table {
	int32_t *slots; /* vertex index, or -1 for an empty slot */
	uint32_t mask;
};

/* Returns the index of the vertex equal to *v in mesh, adding it first when
 * there is none. The table has room for every vertex (mesh_block_build). */
static rt_uint vertex_index(struct vertex_table *table, struct mesh_block *mesh,
			    const struct vertex_key *v)
{
	for (uint32_t s = vertex_hash(v) & table->mask;; s = (s + 1) & table->mask) {
		int32_t at = table->slots[s];
		if (at < 0) {
			table->slots[s] = mesh->vertex_count;
			mesh->vertices[mesh->vertex_count].position = v->position;
			mesh->normals[mesh->vertex_count].normal = v->normal;
			if (mesh->uvs)
				mesh->uvs[mesh->vertex_count] = v->uv;
			return (rt_uint)mesh->vertex_count++;
		}
		if (!memcmp(&mesh->vertices[at].position, &v->position, sizeof(v->position)) &&
		    !memcmp(&mesh->normals[at].normal, &v->normal, sizeof(v->normal)) &&
		    (!mesh->uvs || !memcmp(&mesh->uvs[at], &v->uv, sizeof(v->uv))))
			return (rt_uint)at;
	}
}

static void index_triangle(struct vertex_table *table, struct mesh_block *mesh,
			   const struct scene *scene, const struct scene_triangle *in,
			   const struct scene_triangle_uv *uv, struct rt_triangle *out)
{
	for (int k = 0; k < 3; k++) {
		struct vertex_key v;

		vertex_key(scene, in, uv, k, &v);
		out->index.s[k] = vertex_index(table, mesh, &v);
	}
	out->index.s[3] = (rt_uint)in->material | (in->smooth ? RT_TRIANGLE_SMOOTH : 0u);
}

int mesh_block_build(const struct scene *scene, struct mesh_block *mesh)
{
	size_t corners = 3 * (size_t)scene->triangle_count, slots = 16;
	struct vertex_table table;

	memset(mesh, 0, sizeof(*mesh));
	if (scene->triangle_count == 0)
		return 0;
	while (slots < 2 * corners) /* at most half full */
		slots *= 2;
	table.mask = (uint32_t)(slots - 1);
	table.slots = malloc(slots * sizeof(*table.slots));
	mesh->triangles = malloc((size_t)scene->triangle_count * sizeof(*mesh->triangles));
	mesh->vertices = malloc(corners * sizeof(*mesh->vertices));
	mesh->normals = malloc(corners * sizeof(*mesh->normals));
	int textured = scene_has_textures(scene) && scene->triangle_uvs;
	mesh->uvs = textured ? malloc(corners * sizeof(*mesh->uvs)) : NULL;
	if (!table.slots || !mesh->triangles || !mesh->vertices || !mesh->normals ||
	    (textured && !mesh->uvs))
		goto free_all;
	memset(table.slots, 0xff, slots * sizeof(*table.slots));
	for (int i = 0; i < scene->triangle_count; i++)
		index_triangle(&table, mesh, scene, &scene->triangles[i],
			       textured ? &scene->triangle_uvs[i] : NULL, &mesh->triangles[i]);
	free(table.slots);
	/* Usually about a sixth of the corners: give the rest back. */
	struct rt_vertex *fitted =
		realloc(mesh->vertices, (size_t)mesh->vertex_count * sizeof(*mesh->vertices));
	struct rt_vertex_normal *fitted_normals =
		realloc(mesh->normals, (size_t)mesh->vertex_count * sizeof(*mesh->normals));
	if (fitted)
		mesh->vertices = fitted;
	if (fitted_normals)
		mesh->normals = fitted_normals;
	if (mesh->uvs) {
		struct rt_vertex_uv *fitted_uvs =
			realloc(mesh->uvs, (size_t)mesh->vertex_count * sizeof(*mesh->uvs));
		if (fitted_uvs)
			mesh->uvs = fitted_uvs;
	}
	return 0;

free_all:
	free(table.slots);
	mesh_block_free(mesh);
	return -1;
}

void mesh_block_free(struct mesh_block *mesh)
{
	free(mesh->triangles);
	free(mesh->vertices);
	free(mesh->normals);
	free(mesh->uvs);
	memset(mesh, 0, sizeof(*mesh));
}
