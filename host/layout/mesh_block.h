/* The scene's triangles as the device stores them (cl/rtcl_shared.h, docs/bvh.md
 * "Triangle storage"): each distinct vertex once, its position and its
 * shading normal in two arrays, and per triangle the indices of its three
 * vertices and its material. */
#ifndef RTCL_MESH_BLOCK_H
#define RTCL_MESH_BLOCK_H

#include "rtcl_shared.h"
#include "scene/scene.h"

struct mesh_block {
	struct rt_triangle *triangles;	  /* scene->triangle_count of them */
	struct rt_vertex *vertices;	  /* vertex_count of them */
	struct rt_vertex_normal *normals; /* vertex i's is normals[i] */
	struct rt_vertex_uv *uvs;	  /* vertex i's is uvs[i]; NULL without
					     textures (scene_has_textures) */
	int vertex_count;
};

/* Fills *mesh from the scene's triangles: vertices relative to the eye
 * (scene_from_eye), normals and, in a scene with textures, texture
 * coordinates, rounded to float, those equal in position, (on smooth
 * triangles) normal and texture coordinates merged. Returns 0, or -1 when out of memory (then *mesh holds nothing to free). */
int mesh_block_build(const struct scene *scene, struct mesh_block *mesh);

void mesh_block_free(struct mesh_block *mesh);

#endif
