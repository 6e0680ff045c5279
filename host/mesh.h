/* Reading a mesh file (any format the Open Asset Import Library reads: OBJ,
 * PLY, STL, glTF 2.0, ...) into one flat list of triangles, with the file's
 * own node transforms applied. Placement, normals and the checks of
 * docs/SCENE.md are the scene loader's (host/scene_mesh.c). */
#ifndef RTCL_MESH_H
#define RTCL_MESH_H

#include <stddef.h>

struct mesh_data {
	double *positions; /* 3 per vertex */
	double *normals;   /* 3 per vertex, or NULL where the file has none */
	size_t *indices;   /* 3 per triangle, into the vertices */
	size_t vertex_count, triangle_count;
};

/* Reads `path`. Returns 0 (triangle_count may be 0: points and lines are
 * left out), or -1 with why in reason[reason_size] (the importer's words,
 * or the system's for a file that cannot be opened). */
int mesh_import(const char *path, struct mesh_data *out, char *reason, size_t reason_size);

void mesh_data_free(struct mesh_data *mesh);

#endif
