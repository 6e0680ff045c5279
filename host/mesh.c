/* Mesh files through the Open Asset Import Library's C API, in the helper
 * program rtcl-meshread (see mesh.h). */
#include "mesh.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

/* Polygons become triangles; SortByPType splits points and lines off into
 * meshes of their own, which are skipped; PreTransformVertices applies the
 * node hierarchy (glTF nodes, OBJ groups) to the vertices and normals, so
 * every mesh is in the file's world space before rtcl's placement. */
#define IMPORT_FLAGS                                                                               \
	(aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_PreTransformVertices)

/* The vertices and triangles to expect, counting only triangle meshes. */
static void count(const struct aiScene *sc, size_t *vertices, size_t *triangles, int *has_normals)
{
	*vertices = *triangles = 0;
	*has_normals = 1;
	for (unsigned m = 0; m < sc->mNumMeshes; m++) {
		const struct aiMesh *mesh = sc->mMeshes[m];

		if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
			continue;
		*vertices += mesh->mNumVertices;
		*triangles += mesh->mNumFaces;
		if (!mesh->mNormals)
			*has_normals = 0;
	}
}

/* Appends the triangle meshes of sc to out, which has room for them.
 * Returns -1, with why in reason, for a face that names a vertex its mesh
 * does not have (Assimp does not check: found by test/fuzz_mesh.c). */
static int gather(const struct aiScene *sc, struct mesh_data *out, char *reason, size_t reason_size)
{
	for (unsigned m = 0; m < sc->mNumMeshes; m++) {
		const struct aiMesh *mesh = sc->mMeshes[m];
		size_t base = out->vertex_count;

		if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
			continue;
		for (unsigned v = 0; v < mesh->mNumVertices; v++) {
			double *p = out->positions + 3 * (base + v);

			p[0] = mesh->mVertices[v].x, p[1] = mesh->mVertices[v].y;
			p[2] = mesh->mVertices[v].z;
			if (out->normals) {
				double *n = out->normals + 3 * (base + v);

				n[0] = mesh->mNormals[v].x, n[1] = mesh->mNormals[v].y;
				n[2] = mesh->mNormals[v].z;
			}
		}
		out->vertex_count += mesh->mNumVertices;
		for (unsigned f = 0; f < mesh->mNumFaces; f++) {
			const struct aiFace *face = &mesh->mFaces[f];

			if (face->mNumIndices != 3)
				continue; /* cannot happen after Triangulate; never trust it */
			for (int k = 0; k < 3; k++) {
				if (face->mIndices[k] >= mesh->mNumVertices) {
					snprintf(reason, reason_size,
						 "face %u names vertex %u, but its mesh has %u", f,
						 face->mIndices[k], mesh->mNumVertices);
					return -1;
				}
				out->indices[3 * out->triangle_count + k] =
					base + face->mIndices[k];
			}
			out->triangle_count++;
		}
	}
	return 0;
}

int mesh_import_here(const char *path, struct mesh_data *out, char *reason, size_t reason_size)
{
	const struct aiScene *sc;
	size_t vertices, triangles;
	int has_normals, ret = -1;

	memset(out, 0, sizeof(*out));
	sc = aiImportFile(path, IMPORT_FLAGS);
	if (!sc) {
		snprintf(reason, reason_size, "%s", aiGetErrorString());
		return -1;
	}
	count(sc, &vertices, &triangles, &has_normals);
	out->positions = malloc((vertices ? vertices : 1) * 3 * sizeof(double));
	out->normals = has_normals ? malloc((vertices ? vertices : 1) * 3 * sizeof(double)) : NULL;
	out->indices = malloc((triangles ? triangles : 1) * 3 * sizeof(size_t));
	if (!out->positions || (has_normals && !out->normals) || !out->indices) {
		snprintf(reason, reason_size, "out of memory for %zu triangles", triangles);
		mesh_data_free(out);
		goto out_release_scene;
	}
	if (gather(sc, out, reason, reason_size)) {
		mesh_data_free(out);
		goto out_release_scene;
	}
	ret = 0;
out_release_scene:
	aiReleaseImport(sc);
	return ret;
}
