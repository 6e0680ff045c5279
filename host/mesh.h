/* Reading a mesh file (any format the Open Asset Import Library reads: OBJ,
 * PLY, STL, glTF 2.0, ...) into one flat list of triangles, with the file's
 * own node transforms applied. Placement, normals and the checks of
 * docs/SCENE.md are the scene loader's (host/scene_mesh.c).
 *
 * Assimp runs in a helper program of its own, rtcl-meshread (host/meshread.c),
 * which rtcl starts for each mesh file and which sends the mesh back through a
 * pipe (host/mesh_spawn.c): Assimp 5.2 calls abort() on some malformed files
 * (found by the mesh fuzzer, test/fuzz_mesh.c), and that must end the helper,
 * never rtcl and its user's render. rtcl itself does not link Assimp. */
#ifndef RTCL_MESH_H
#define RTCL_MESH_H

#include <stddef.h>

struct mesh_data {
	double *positions; /* 3 per vertex */
	double *normals;   /* 3 per vertex, or NULL where the file has none */
	size_t *indices;   /* 3 per triangle, into the vertices */
	size_t vertex_count, triangle_count;
};

/* What mesh_import returns besides 0. */
enum {
	MESH_REFUSED = -1,	  /* the file's fault: unreadable, malformed, or the
				     importer died on it */
	MESH_IMPORTER_FAILED = -2 /* rtcl's: the helper is missing, could not start,
				     failed a sanitizer check or answered nonsense */
};

/* Reads `path` through the helper program. Returns 0 (triangle_count may be
 * 0: points and lines are left out), or MESH_REFUSED / MESH_IMPORTER_FAILED
 * with why in reason[reason_size]. */
int mesh_import(const char *path, struct mesh_data *out, char *reason, size_t reason_size);

/* How many mesh_import calls of this process returned MESH_IMPORTER_FAILED:
 * the fuzzers and the regression test check that none did, whatever the
 * message (which quotes the scene's words). */
unsigned long mesh_importer_failures(void);

/* The helper's side: Assimp in this process. Returns 0, or -1 with the
 * importer's words in reason. (host/mesh.c, linked into rtcl-meshread only.) */
int mesh_import_here(const char *path, struct mesh_data *out, char *reason, size_t reason_size);

/* The helper's answer on fd: the mesh (mesh != NULL) or the reason it was
 * refused. Returns 0, or -1 when the pipe broke. */
int mesh_send(int fd, const struct mesh_data *mesh, const char *reason);

void mesh_data_free(struct mesh_data *mesh);

/* The environment variable that names the helper program, overriding where
 * rtcl looks for it (host/libdir.h). */
#define MESH_HELPER_ENV "RTCL_MESHREAD"
#define MESH_HELPER_NAME "rtcl-meshread"

#endif
