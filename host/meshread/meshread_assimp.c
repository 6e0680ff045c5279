/* Mesh files through the Open Asset Import Library's C API, in the helper
 * program rtcl-meshread (see mesh.h). */
#define _POSIX_C_SOURCE 200809L
#include "scene/mesh.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "meshread/ply_check.h"

/* Polygons become triangles; SortByPType splits points and lines off into meshes of
 * their own, which are skipped; PreTransformVertices applies the node
 * hierarchy (glTF nodes, OBJ groups) to the vertices and normals, so every
 * mesh is in the file's world space before rtcl's placement. */
#define IMPORT_FLAGS                                                                               \
	(aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_PreTransformVertices)

/* ---- Assimp's file access: only regular files, opened without blocking ----
 * Assimp opens the files a mesh file names (an OBJ's mtllib, a glTF's
 * buffers[].uri) itself; one that is a FIFO hung the import for good (issue
 * 24 finding 4). Every file it opens goes through these procedures, which
 * refuse anything but a regular file and remember the first refused. */

static char refused_file[512];

static size_t file_read(struct aiFile *file, char *buffer, size_t size, size_t count)
{
	return fread(buffer, size, count, (FILE *)file->UserData);
}

static size_t file_write(struct aiFile *file, const char *buffer, size_t size, size_t count)
{
	(void)file, (void)buffer, (void)size, (void)count;
	return 0; /* an import writes nothing */
}

static size_t file_tell(struct aiFile *file)
{
	off_t at = ftello((FILE *)file->UserData);

	return at < 0 ? 0 : (size_t)at;
}

static size_t file_size(struct aiFile *file)
{
	struct stat st;

	return fstat(fileno((FILE *)file->UserData), &st) == 0 ? (size_t)st.st_size : 0;
}

static enum aiReturn file_seek(struct aiFile *file, size_t offset, enum aiOrigin origin)
{
	int whence = origin == aiOrigin_SET   ? SEEK_SET
		     : origin == aiOrigin_CUR ? SEEK_CUR
					      : SEEK_END;

	return fseeko((FILE *)file->UserData, (off_t)offset, whence) == 0 ? aiReturn_SUCCESS
									  : aiReturn_FAILURE;
}

static void file_flush(struct aiFile *file)
{
	(void)file;
}

static struct aiFile *file_open(struct aiFileIO *io, const char *path, const char *mode)
{
	struct aiFile *file;
	struct stat st;
	FILE *stream;
	int fd;

	(void)io;
	if (mode[0] != 'r')
		return NULL;
	fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	if (fd < 0)
		return NULL;
	if (fstat(fd, &st) != 0) {
		close(fd);
		return NULL;
	}
	if (!S_ISREG(st.st_mode)) {
		if (!refused_file[0] && !S_ISDIR(st.st_mode))
			snprintf(refused_file, sizeof(refused_file), "%s", path);
		close(fd);
		return NULL;
	}
	file = calloc(1, sizeof(*file));
	stream = file ? fdopen(fd, "rb") : NULL;
	if (!stream) {
		free(file);
		close(fd);
		return NULL;
	}
	file->ReadProc = file_read;
	file->WriteProc = file_write;
	file->TellProc = file_tell;
	file->FileSizeProc = file_size;
	file->SeekProc = file_seek;
	file->FlushProc = file_flush;
	file->UserData = (aiUserData)stream;
	return file;
}

static void file_close(struct aiFileIO *io, struct aiFile *file)
{
	(void)io;
	if (!file)
		return;
	fclose((FILE *)file->UserData);
	free(file);
}

/* The largest polygon of an OBJ file: Assimp's triangulation takes time
 * that grows with the square of a polygon's vertices (10,000 took 1 s, one
 * of 100,000 minutes: issue 24 finding 4). PLY's faces are checked by
 * ply_check; other formats rely on the time limit (mesh.h). */
static int obj_polygon_too_large(const char *path, char *reason, size_t reason_size)
{
	size_t n = strlen(path), line_number = 0, capacity = 0;
	char *line = NULL;
	int too_large = 0;
	FILE *f;

	if (n < 4 || strcasecmp(path + n - 4, ".obj") != 0 || !(f = fopen(path, "rb")))
		return 0;
	while (!too_large && getline(&line, &capacity, f) >= 0) {
		unsigned long vertices = 0;
		char *p = line + strspn(line, " \t");

		line_number++;
		if (p[0] != 'f' || (p[1] != ' ' && p[1] != '\t'))
			continue;
		/* One pass over the line, character by character: strspn and
		 * strcspn from each word made it quadratic under ASan's
		 * strict_string_checks, which measures the rest of the string at
		 * every call (20 s for one face of 100,000 vertices). */
		for (int in_word = 0; *++p;) {
			int blank = *p == ' ' || *p == '\t' || *p == '\r' || *p == '\n';
			vertices += !blank && !in_word;
			in_word = !blank;
		}
		if (vertices > MESH_MAX_POLYGON_VERTICES) {
			snprintf(reason, reason_size,
				 "line %zu: a face of %lu vertices, more than the %d a polygon may "
				 "have",
				 line_number, vertices, MESH_MAX_POLYGON_VERTICES);
			too_large = 1;
		}
	}
	free(line);
	fclose(f);
	return too_large;
}

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
	struct aiFileIO io = {file_open, file_close, NULL};
	const struct aiScene *sc;
	size_t vertices, triangles;
	int has_normals, ret = -1;

	memset(out, 0, sizeof(*out));
	refused_file[0] = '\0';
	if (ply_check(path, reason, reason_size) ||
	    obj_polygon_too_large(path, reason, reason_size))
		return -1;
	sc = aiImportFileEx(path, IMPORT_FLAGS, &io);
	if (refused_file[0]) {
		snprintf(reason, reason_size, "it names \"%s\", which is not a regular file",
			 refused_file);
		goto out_release_scene;
	}
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
	if (sc)
		aiReleaseImport(sc);
	return ret;
}
