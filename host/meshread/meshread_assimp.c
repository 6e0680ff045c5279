/* Mesh files through the Open Asset Import Library's C API, in the helper
 * program rtcl-meshread (see mesh.h). */
#define _POSIX_C_SOURCE 200809L
#include "scene/mesh.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <assimp/cfileio.h>
#include <assimp/material.h>
#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/version.h>
#include <jansson.h>

#include "meshread/gltf_read.h"
#include "meshread/mtl_read.h"
#include "meshread/ply_check.h"
#include "meshread/texture_read.h"

/* Polygons become triangles; SortByPType splits points and lines off into meshes of
 * their own, which are skipped; PreTransformVertices applies the node
 * hierarchy (glTF nodes, OBJ groups) to the vertices and normals, so every
 * mesh is in the file's world space before rtcl's placement. */
#define IMPORT_FLAGS                                                                               \
	(aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_PreTransformVertices)

/* ---- Assimp's file access: only regular files inside the model's folder,
 * opened without blocking ----
 * Assimp opens the files a mesh file names (an OBJ's mtllib, a glTF's
 * buffers[].uri) itself; one that is a FIFO hung the import for good (issue
 * 24 finding 4), and one outside the model's folder let a model read any
 * file into an image (issue 39 finding 3). Every file it opens goes through
 * these procedures, which refuse anything but a regular file inside the
 * folder (texture_read.h's rule), remember the first refused, and remember
 * every file opened: rtcl counts them among the run's inputs (finding 1). */

static char refused_file[PATH_MAX];
static int refused_outside;   /* refused_file lies outside the folder */
static const char *mesh_file; /* the mesh file, as rtcl names it */
/* The length of the mesh file's folder's part of its path (the slash
 * included): Assimp opens the files it names there. Where the mesh file is
 * glTF (named .gltf or .glb), it names them by URI as the file writes it,
 * which is decoded here (glTF 2.0, "URIs"). */
static size_t named_at;
static int gltf_names_uris;

/* The files read besides the mesh file, each once. */
static struct mesh_file *opened;
static size_t opened_count;
static int opened_failed; /* out of memory for the list */

static void remember_opened(const char *path, uint32_t kind)
{
	struct mesh_file *grown;

	if (strcmp(path, mesh_file) == 0)
		return;
	for (size_t i = 0; i < opened_count; i++)
		if (strcmp(opened[i].path, path) == 0)
			return;
	grown = realloc(opened, (opened_count + 1) * sizeof(*grown));
	if (grown)
		opened = grown;
	if (!grown || !(opened[opened_count].path = strdup(path))) {
		opened_failed = 1;
		return;
	}
	opened[opened_count++].kind = kind;
}

static int has_extension(const char *path, const char *extension)
{
	size_t n = strlen(path), e = strlen(extension);

	return n > e && strcasecmp(path + n - e, extension) == 0;
}

static void forget_opened(void)
{
	for (size_t i = 0; i < opened_count; i++)
		free(opened[i].path);
	free(opened);
	opened = NULL;
	opened_count = 0;
	opened_failed = 0;
}

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
	static char name[PATH_MAX]; /* a glTF URI decoded */
	struct aiFile *file;
	struct stat st;
	FILE *stream;
	int fd;

	(void)io;
	if (mode[0] != 'r')
		return NULL;
	/* The mesh file itself as the scene names it, maybe a link to
	 * elsewhere; any other file by where it leads. */
	if (strcmp(path, mesh_file) == 0) {
		fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	} else {
		char resolved[PATH_MAX], why[80];
		int uri = gltf_names_uris && strncmp(path, mesh_file, named_at) == 0;
		char *decoded = uri ? model_decode_uri(path, named_at, why, sizeof(why)) : NULL;
		int where;

		if (uri && !decoded)
			return NULL; /* an escaped NUL: no such file */
		if (decoded) {
			snprintf(name, sizeof(name), "%s", decoded);
			free(decoded);
			path = name;
		}
		where = model_folder_resolve(path, resolved);
		/* A name whose ".." climb out of the folder is outside, there
		 * or not. (Assimp also tries the folder joined to a whole path,
		 * "m//abs/m/x.mtl", which no file answers to: not a name that
		 * leaves.) */
		if (where == MODEL_MISSING && strncmp(path, mesh_file, named_at) == 0 &&
		    model_name_leaves(path + named_at + strspn(path + named_at, "/")))
			where = MODEL_OUTSIDE;
		if (where == MODEL_MISSING)
			return NULL; /* Assimp tries other spellings of the name */
		if (where == MODEL_OUTSIDE) {
			if (!refused_file[0]) {
				snprintf(refused_file, sizeof(refused_file), "%s", path);
				refused_outside = 1;
			}
			return NULL;
		}
		fd = open(resolved, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOFOLLOW);
	}
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
	remember_opened(path, MESH_FILE_OTHER);
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

/* ---- Materials (docs/SCENE.md, "Materials from mesh files") ----
 * Read from Assimp's property list directly, key by key, so that every
 * property is either used or named in not_understood. */

/* The property key of semantic 0 (not a texture's), or NULL. */
static const struct aiMaterialProperty *property(const struct aiMaterial *mat, const char *key)
{
	for (unsigned p = 0; p < mat->mNumProperties; p++) {
		const struct aiMaterialProperty *prop = mat->mProperties[p];
		if (prop->mSemantic == 0 && strcmp(prop->mKey.data, key) == 0)
			return prop;
	}
	return NULL;
}

/* Up to n numbers of the property key into out; returns how many (0: none). */
static unsigned numbers(const struct aiMaterial *mat, const char *key, double *out, unsigned n)
{
	const struct aiMaterialProperty *prop = property(mat, key);
	unsigned got = 0;

	if (!prop)
		return 0;
	for (; got < n; got++) {
		if (prop->mType == aiPTI_Float && (got + 1) * sizeof(float) <= prop->mDataLength) {
			float f;
			memcpy(&f, prop->mData + got * sizeof(float), sizeof(f));
			out[got] = f;
		} else if (prop->mType == aiPTI_Double &&
			   (got + 1) * sizeof(double) <= prop->mDataLength) {
			memcpy(&out[got], prop->mData + got * sizeof(double), sizeof(double));
		} else if (prop->mType == aiPTI_Integer &&
			   (got + 1) * sizeof(int32_t) <= prop->mDataLength) {
			int32_t i;
			memcpy(&i, prop->mData + got * sizeof(i), sizeof(i));
			out[got] = i;
		} else {
			break;
		}
	}
	return got;
}

/* The string property key (an aiString: a 32-bit length, then the bytes), or "". */
static void string_of(const struct aiMaterial *mat, const char *key, char *out, size_t size)
{
	const struct aiMaterialProperty *prop = property(mat, key);
	uint32_t length;

	out[0] = '\0';
	if (!prop || prop->mType != aiPTI_String || prop->mDataLength < sizeof(length))
		return;
	memcpy(&length, prop->mData, sizeof(length));
	if (length > prop->mDataLength - sizeof(length))
		length = prop->mDataLength - (uint32_t)sizeof(length);
	if (length >= size)
		length = (uint32_t)size - 1;
	memcpy(out, prop->mData + sizeof(length), length);
	out[length] = '\0'; /* control bytes kept: messages escape them (base/quote.h) */
}

/* Adds what (once) to the comma-separated notes. */
static void note(struct mesh_material *m, const char *what)
{
	char *notes = m->not_understood;
	size_t n = strlen(notes), w = strlen(what);

	for (const char *at = notes; (at = strstr(at, what)); at += w)
		if ((at == notes || at[-1] == ' ') && (at[w] == ',' || at[w] == '\0'))
			return;
	if (n + w + 3 < MESH_NOTES_MAX)
		snprintf(notes + n, MESH_NOTES_MAX - n, "%s%s", n ? ", " : "", what);
}

/* The properties rtcl reads or may leave aside without loss. */
static int understood(const char *key, int metallic_roughness)
{
	static const char *const always[] = {
		"?mat.name",	 "$mat.shadingm", "$mat.twosided",	   "$clr.transparent",
		"$mat.refracti", "$clr.emissive", "$mat.anisotropyFactor", "$mat.emissiveIntensity",
		NULL};
	static const char *const phong[] = {"$clr.diffuse",
					    "$clr.specular",
					    "$clr.ambient",
					    "$mat.shininess",
					    "$mat.opacity",
					    "$mat.illum",
					    NULL};
	/* Assimp's glTF reader repeats the base colour as $clr.diffuse and
	 * the alpha as $mat.opacity, and derives $mat.shininess. */
	static const char *const pbr[] = {"$clr.base",
					  "$mat.metallicFactor",
					  "$mat.roughnessFactor",
					  "$mat.gltf.alphaMode",
					  "$mat.gltf.alphaCutoff",
					  "$mat.transmission.factor",
					  "$clr.diffuse",
					  "$mat.opacity",
					  "$mat.shininess",
					  NULL};
	const char *const *lists[] = {always, metallic_roughness ? pbr : phong};

	for (int l = 0; l < 2; l++)
		for (const char *const *k = lists[l]; *k; k++)
			if (strcmp(key, *k) == 0)
				return 1;
	return 0;
}

/* The texture kinds rtcl reads: base colour, (cut-out) opacity, and for the
 * path integrator glTF's metallic-roughness (Assimp 5.2's "unknown" type)
 * and the emissive texture. */
static int texture_read(unsigned semantic)
{
	return semantic == aiTextureType_DIFFUSE || semantic == aiTextureType_BASE_COLOR ||
	       semantic == aiTextureType_OPACITY || semantic == aiTextureType_UNKNOWN ||
	       semantic == aiTextureType_METALNESS || semantic == aiTextureType_DIFFUSE_ROUGHNESS ||
	       semantic == aiTextureType_EMISSIVE || semantic == aiTextureType_NORMALS;
}

/* Counts the textures rtcl reads and notes the properties it does not
 * understand. */
static void survey(const struct aiMaterial *mat, struct mesh_material *m)
{
	int metallic_roughness = m->kind == MESH_MATERIAL_METALLIC_ROUGHNESS;
	double emissive[3] = {0, 0, 0}, anisotropy = 0;
	char what[160];

	for (unsigned p = 0; p < mat->mNumProperties; p++) {
		const struct aiMaterialProperty *prop = mat->mProperties[p];
		const char *key = prop->mKey.data;

		if (strncmp(key, "$tex.", 5) == 0) {
			if (strcmp(key, "$tex.file") != 0)
				continue; /* the file's mapping, wrap modes ... */
			/* glTF's base colour texture comes as diffuse and base colour */
			if (texture_read(prop->mSemantic))
				m->textures +=
					!(prop->mSemantic == aiTextureType_BASE_COLOR &&
					  aiGetMaterialTextureCount(mat, aiTextureType_DIFFUSE));
			else {
				snprintf(
					what, sizeof(what), "%s texture",
					aiTextureTypeToString((enum aiTextureType)prop->mSemantic));
				note(m, what);
			}
			continue;
		}
		if (prop->mSemantic != 0 || !understood(key, metallic_roughness)) {
			snprintf(what, sizeof(what), "%.120s", key);
			note(m, what);
		}
	}
	/* Emission is rendered by the path integrator only (SCENE.md,
	 * "Emission"): read, and under Whitted not drawn, as -v said before. */
	if (numbers(mat, "$clr.emissive", emissive, 3) &&
	    (emissive[0] != 0 || emissive[1] != 0 || emissive[2] != 0)) {
		double strength = 1;
		numbers(mat, "$mat.emissiveIntensity", &strength, 1);
		for (int i = 0; i < 3; i++)
			m->emissive[i] = emissive[i] * strength;
		note(m, "emissive");
	}
	if (numbers(mat, "$mat.anisotropyFactor", &anisotropy, 1) && anisotropy != 0)
		note(m, "anisotropy");
}

static void read_phong(const struct aiMaterial *mat, struct mesh_material *m)
{
	double illum = 2;

	m->kind = MESH_MATERIAL_PHONG;
	m->opacity = 1;
	m->ior = 1;
	numbers(mat, "$clr.diffuse", m->diffuse, 3);
	numbers(mat, "$clr.specular", m->specular, 3);
	numbers(mat, "$clr.ambient", m->ambient, 3);
	numbers(mat, "$mat.shininess", &m->shininess, 1);
	numbers(mat, "$mat.opacity", &m->opacity, 1);
	numbers(mat, "$mat.refracti", &m->ior, 1);
	numbers(mat, "$mat.illum", &illum, 1);
	m->illum = illum >= 0 && illum <= 10 ? (uint32_t)illum : 2;
}

static void read_metallic_roughness(const struct aiMaterial *mat, struct mesh_material *m)
{
	char mode[16];

	m->kind = MESH_MATERIAL_METALLIC_ROUGHNESS;
	m->base[0] = m->base[1] = m->base[2] = m->base[3] = 1;
	m->metallic = m->roughness = 1;
	m->alpha_cutoff = 0.5;
	numbers(mat, "$clr.base", m->base, 4);
	numbers(mat, "$mat.metallicFactor", &m->metallic, 1);
	numbers(mat, "$mat.roughnessFactor", &m->roughness, 1);
	numbers(mat, "$mat.transmission.factor", &m->transmission, 1);
	numbers(mat, "$mat.gltf.alphaCutoff", &m->alpha_cutoff, 1);
	m->has_ior = numbers(mat, "$mat.refracti", &m->ior, 1) == 1;
	string_of(mat, "$mat.gltf.alphaMode", mode, sizeof(mode));
	m->alpha_mode = strcmp(mode, "BLEND") == 0  ? MESH_ALPHA_BLEND
			: strcmp(mode, "MASK") == 0 ? MESH_ALPHA_MASK
						    : MESH_ALPHA_OPAQUE;
}

/* Whether m is what Assimp puts where the file has no material: one named
 * AI_DEFAULT_MATERIAL_NAME, an unnamed one with only its format's defaults
 * (PLY's white, glTF's white metallic 1 roughness 1, opaque), or an OBJ
 * material its MTL library does not define (SCENE.md says which). */
static int missing(const struct mesh_material *m, int named)
{
	if (strcmp(m->name, AI_DEFAULT_MATERIAL_NAME) == 0)
		return 1;
	if (m->textures)
		return 0;
	if (m->kind == MESH_MATERIAL_METALLIC_ROUGHNESS)
		return !named && m->base[0] == 1 && m->base[1] == 1 && m->base[2] == 1 &&
		       m->base[3] == 1 && m->metallic == 1 && m->roughness == 1 &&
		       m->transmission == 0 && !m->has_ior && m->alpha_mode == MESH_ALPHA_OPAQUE;
	/* Assimp's OBJ reader fills a material its MTL library does not define
	 * (or a library that is missing) with these. */
	if (!named)
		return m->diffuse[0] == 1 && m->diffuse[1] == 1 && m->diffuse[2] == 1;
	for (int i = 0; i < 3; i++)
		if (m->diffuse[i] != 0.6f || m->specular[i] != 0 || m->ambient[i] != 0)
			return 0;
	return m->kind == MESH_MATERIAL_PHONG && m->shininess == 0 && m->opacity == 1 &&
	       m->ior == 1 && m->illum == 1 && !m->not_understood[0];
}

static void read_material(const struct aiMaterial *mat, unsigned index, struct mesh_material *m)
{
	double metallic;

	memset(m, 0, sizeof(*m));
	m->base_texture = m->opacity_texture = -1;
	m->metallic_roughness_texture = m->emissive_texture = m->normal_texture = -1;
	string_of(mat, "?mat.name", m->name, sizeof(m->name));
	int named = m->name[0] != '\0';
	if (!named)
		snprintf(m->name, sizeof(m->name), "#%u", index);
	if (numbers(mat, "$mat.metallicFactor", &metallic, 1))
		read_metallic_roughness(mat, m);
	else
		read_phong(mat, m);
	survey(mat, m);
	if (missing(m, named)) {
		m->kind = MESH_MATERIAL_MISSING;
		m->not_understood[0] = '\0';
	}
}

/* KHR_materials_emissive_strength, which Assimp 5.2 does not read (later
 * versions give it as $mat.emissiveIntensity, which survey applies): the
 * glTF's material i is Assimp's material i (Assimp appends its default
 * material after them). */
static void gltf_emissive_strengths(const struct aiScene *sc, const json_t *doc,
				    struct mesh_data *out)
{
	json_t *materials = doc ? json_object_get(doc, "materials") : NULL;
	double given;

	for (size_t i = 0; json_is_array(materials) && i < json_array_size(materials) &&
			   i < out->material_count;
	     i++) {
		json_t *strength = json_object_get(
			json_object_get(json_object_get(json_array_get(materials, i), "extensions"),
					"KHR_materials_emissive_strength"),
			"emissiveStrength");
		double x = json_is_number(strength) ? json_number_value(strength) : 1;
		if (x == 1 || numbers(sc->mMaterials[i], "$mat.emissiveIntensity", &given, 1))
			continue;
		for (int c = 0; c < 3; c++)
			out->materials[i].emissive[c] *= x;
	}
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

/* Appends the triangle meshes of sc to out, which has room for them, each
 * triangle with its mesh's material.
 * Returns -1, with why in reason, for a face that names a vertex its mesh
 * does not have (Assimp does not check: found by test/fuzz_mesh.c). */
static int gather(const struct aiScene *sc, struct mesh_data *out, char *reason, size_t reason_size)
{
	for (unsigned m = 0; m < sc->mNumMeshes; m++) {
		const struct aiMesh *mesh = sc->mMeshes[m];
		size_t base = out->vertex_count;
		uint32_t material = mesh->mMaterialIndex < sc->mNumMaterials ? mesh->mMaterialIndex
									     : MESH_NO_MATERIAL;

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
			out->triangle_materials[out->triangle_count] = material;
			out->triangle_count++;
		}
	}
	return 0;
}

/* ---- Textures (docs/SCENE.md, "Textures") ---- */

/* Assimp's wrap mode as the mesh protocol's (Assimp's "decal", no texture
 * outside 0 ... 1, is clamped). */
static uint32_t wrap_of(enum aiTextureMapMode mode)
{
	return mode == aiTextureMapMode_Mirror	? MESH_WRAP_MIRROR
	       : mode == aiTextureMapMode_Clamp || mode == aiTextureMapMode_Decal ? MESH_WRAP_CLAMP
										   : MESH_WRAP_REPEAT;
}

/* Appends t's texels (malloc'd; taken, freed here) to out->texels at a
 * 16-byte boundary; the first texture's buffer becomes out->texels as it is,
 * not copied (a 16384² texture is 1 GiB). Returns 0, or -1 when out of
 * memory (reason in t). */
static int append_texels(struct mesh_data *out, struct mesh_texture *t, unsigned char *texels)
{
	size_t at = (out->texel_bytes + 15) / 16 * 16;
	unsigned char *grown;

	if (!out->texels) {
		out->texels = texels;
		t->offset = 0;
		out->texel_bytes = (size_t)t->bytes;
		return 0;
	}
	grown = realloc(out->texels, at + (size_t)t->bytes);
	if (!grown) {
		snprintf(t->reason, sizeof(t->reason), "out of memory for its %llu bytes",
			 (unsigned long long)t->bytes);
		free(texels);
		return -1;
	}
	memset(grown + out->texel_bytes, 0, at - out->texel_bytes);
	memcpy(grown + at, texels, (size_t)t->bytes);
	free(texels);
	out->texels = grown;
	t->offset = at;
	out->texel_bytes = at + (size_t)t->bytes;
	return 0;
}

/* An embedded texture that Assimp holds uncompressed (mHeight > 0): its
 * aiTexel are BGRA, 8 bits each, rows top first. */
static unsigned char *raw_texels(const struct aiTexture *tex, struct mesh_texture *t)
{
	size_t count = (size_t)tex->mWidth * tex->mHeight;
	unsigned char *texels;

	if (tex->mWidth > MESH_TEXTURE_MAX_SIDE || tex->mHeight > MESH_TEXTURE_MAX_SIDE) {
		snprintf(t->reason, sizeof(t->reason),
			 "it is %ux%u texels, more than the %d a side rtcl reads", tex->mWidth,
			 tex->mHeight, MESH_TEXTURE_MAX_SIDE);
		return NULL;
	}
	texels = malloc(count * 4);
	if (!texels) {
		snprintf(t->reason, sizeof(t->reason), "out of memory");
		return NULL;
	}
	for (size_t i = 0; i < count; i++) {
		const struct aiTexel *x = &tex->pcData[i];
		texels[4 * i] = x->r, texels[4 * i + 1] = x->g, texels[4 * i + 2] = x->b;
		texels[4 * i + 3] = t->role == MESH_TEXTURE_OPACITY ? x->r : x->a;
	}
	t->format = MESH_TEXELS_8;
	t->width = tex->mWidth;
	t->height = tex->mHeight;
	t->bytes = (uint64_t)count * 4;
	return texels;
}

/* Whether the file was read by Assimp's glTF 2.0 importer (its metadata
 * "SourceAsset_Format" says "glTF2 Importer"). */
static int from_gltf2(const struct aiScene *sc)
{
	const struct aiMetadata *meta = sc->mMetaData;

	for (unsigned i = 0; meta && i < meta->mNumProperties; i++)
		if (strcmp(meta->mKeys[i].data, "SourceAsset_Format") == 0 &&
		    meta->mValues[i].mType == AI_AISTRING && meta->mValues[i].mData)
			return strncmp(((const struct aiString *)meta->mValues[i].mData)->data,
				       "glTF2", 5) == 0;
	return 0;
}

/* Reads texture t (its name and role set): embedded ("*N") or a file beside
 * the mesh (doc: a glTF file's JSON, or NULL). Its reason says why when it
 * could not be read. */
static void read_texture(const struct aiScene *sc, const char *path, const json_t *doc,
			 struct mesh_data *out, struct mesh_texture *t)
{
	unsigned char *bytes = NULL, *texels = NULL;
	char *file = NULL;
	size_t size = 0;
	long plain;

	if (!t->name[0] && doc && (plain = gltf_plain_data_image(doc)) >= 0) {
		/* Assimp keeps neither bytes nor a name for it (issue 39: "it is
		 * not a regular file" was said of the model's folder). */
		snprintf(t->reason, sizeof(t->reason),
			 "images[%ld] is a data: URI that is not base64; rtcl reads only base64 "
			 "data: URIs",
			 plain);
	} else if (!t->name[0]) {
		snprintf(t->reason, sizeof(t->reason), "the file gives no image for it");
	} else if (t->name[0] == '*') {
		char *end;
		unsigned long i = strtoul(t->name + 1, &end, 10);
		const struct aiTexture *tex;

		if (*end || i >= sc->mNumTextures || !sc->mTextures[i]) {
			snprintf(t->reason, sizeof(t->reason), "the file has no embedded texture %.40s",
				 t->name);
			return;
		}
		tex = sc->mTextures[i];
		if (tex->mHeight > 0) {
			texels = raw_texels(tex, t);
		} else if (!texture_decode((const unsigned char *)tex->pcData, tex->mWidth, t,
					   &texels)) {
			/* decoded */
		}
	} else {
		/* glTF names its images by URI (glTF 2.0, "URIs"); other formats
		 * by file name */
		int ok = !texture_file_bytes(path, t->name, from_gltf2(sc), &bytes, &size, &file,
					     t->reason, sizeof(t->reason));
		if (file)
			remember_opened(file, MESH_FILE_TEXTURE);
		free(file);
		if (ok)
			texture_decode(bytes, size, t, &texels);
	}
	free(bytes);
	if (texels && !t->reason[0])
		append_texels(out, t, texels);
	else
		free(texels);
}

/* texture_of's answer when out of memory. */
#define TEXTURE_NO_MEMORY (-2)

/* The index in out->textures of texture `type` of mat, read in `role`
 * (each name and role once), -1 where mat has none, or TEXTURE_NO_MEMORY. */
static int32_t texture_of(const struct aiScene *sc, const char *path, const json_t *doc,
			  const struct aiMaterial *mat, enum aiTextureType type, uint32_t role,
			  struct mesh_data *out)
{
	enum aiTextureMapMode modes[3] = {aiTextureMapMode_Wrap, aiTextureMapMode_Wrap,
					  aiTextureMapMode_Wrap};
	struct aiString name;
	struct mesh_texture *t, *grown;

	if (aiGetMaterialTextureCount(mat, type) == 0 ||
	    aiGetMaterialTexture(mat, type, 0, &name, NULL, NULL, NULL, NULL, modes, NULL) !=
		    aiReturn_SUCCESS)
		return -1;
	/* The whole name: messages quote its control bytes (base/quote.h). */
	for (size_t i = 0; i < out->texture_count; i++)
		if (out->textures[i].role == role && out->textures[i].wrap_s == wrap_of(modes[0]) &&
		    out->textures[i].wrap_t == wrap_of(modes[1]) &&
		    strcmp(out->textures[i].name, name.data) == 0)
			return (int32_t)i;
	grown = realloc(out->textures, (out->texture_count + 1) * sizeof(*grown));
	if (!grown)
		return TEXTURE_NO_MEMORY;
	out->textures = grown;
	t = &out->textures[out->texture_count];
	memset(t, 0, sizeof(*t));
	t->name = strdup(name.data);
	if (!t->name)
		return TEXTURE_NO_MEMORY;
	t->role = role;
	t->wrap_s = wrap_of(modes[0]);
	t->wrap_t = wrap_of(modes[1]);
	read_texture(sc, path, doc, out, t);
	return (int32_t)out->texture_count++;
}

/* Where mat's base colour texture is: glTF's comes as base colour and
 * diffuse, MTL's map_Kd as diffuse. */
static enum aiTextureType base_type(const struct aiMaterial *mat)
{
	return aiGetMaterialTextureCount(mat, aiTextureType_BASE_COLOR) ? aiTextureType_BASE_COLOR
									: aiTextureType_DIFFUSE;
}

/* A texture's binding: the set of texture coordinates it reads and the
 * transform from the file's coordinates to the texture's: [u' v'] = m [u v
 * 1], v down (glTF's convention, v_down) or up (the MTL's). */
struct uv_binding {
	unsigned set;
	int v_down;
	double m[2][3];
};

/* A glTF material's base colour binding (AI_MATKEY_UVWSRC: glTF's texCoord;
 * KHR_texture_transform's texCoord from the JSON, doc; its offset, rotation
 * and scale from Assimp's aiUVTransform). Returns 1 where it is not set 0
 * untransformed. */
static int gltf_binding(const struct aiMaterial *mat, enum aiTextureType type, const json_t *doc,
			const char *name, struct uv_binding *b)
{
	struct aiUVTransform uv;
	unsigned int max = sizeof(uv) / sizeof(float);
	int set = 0, texcoord = gltf_transform_texcoord(doc, name);

	aiGetMaterialIntegerArray(mat, _AI_MATKEY_UVWSRC_BASE, type, 0, &set, NULL);
	if (texcoord >= 0)
		set = texcoord;
	b->set = set > 0 && set < AI_MAX_NUMBER_OF_TEXTURECOORDS ? (unsigned)set : 0;
	b->v_down = 1;
	if (aiGetMaterialFloatArray(mat, _AI_MATKEY_UVTRANSFORM_BASE, type, 0, (ai_real *)&uv,
				    &max) != aiReturn_SUCCESS ||
	    max != sizeof(uv) / sizeof(float))
		return b->set != 0;
	/* Assimp 5.2's glTF reader keeps KHR_texture_transform as scaling
	 * s, rotation -r and a translation worked out for rotation about the
	 * centre and v up (glTF2Importer.cpp); back to glTF's offset o: */
	double sx = uv.mScaling.x, sy = uv.mScaling.y, r = -uv.mRotation;
	double c = cos(r), s = sin(r);
	double ox = uv.mTranslation.x - 0.5 * sx * (-c + s + 1);
	double oy = 0.5 * sy * (s + c - 1) + 1 - sy - uv.mTranslation.y;
	/* KHR_texture_transform: translation · rotation · scale, the
	 * rotation [cos sin; -sin cos]. */
	b->m[0][0] = c * sx;
	b->m[0][1] = s * sy;
	b->m[0][2] = ox;
	b->m[1][0] = -s * sx;
	b->m[1][1] = c * sy;
	b->m[1][2] = oy;
	return 1;
}

/* The -s and -o of material m's map_Kd or map_d (role) among the file's
 * MTL transforms, or NULL. */
static const struct mtl_transform *mtl_transform_of(const struct mesh_material *m, unsigned role,
						     const struct mtl_transform *list, size_t count)
{
	for (size_t i = 0; i < count; i++)
		if (list[i].role == role && strcmp(list[i].material, m->name) == 0)
			return &list[i];
	return NULL;
}

/* Material i's binding into b: glTF's (doc), or an MTL's map_Kd -s/-o (its
 * map_d's where it has no map_Kd). One set of coordinates serves both of a
 * material's textures: a map_d transformed unlike its map_Kd is noted as not
 * understood. Returns 1 where it is not set 0 untransformed. */
static int material_binding(const struct aiScene *sc, unsigned i, const json_t *doc,
			    const struct mtl_transform *list, size_t count,
			    struct mesh_material *m, struct uv_binding *b)
{
	const struct mtl_transform *kd, *d, *t;

	memset(b, 0, sizeof(*b));
	b->m[0][0] = b->m[1][1] = 1;
	if (doc)
		return m->base_texture >= 0 &&
		       gltf_binding(sc->mMaterials[i], base_type(sc->mMaterials[i]), doc, m->name, b);
	kd = m->base_texture >= 0 ? mtl_transform_of(m, MESH_TEXTURE_COLOR, list, count) : NULL;
	d = m->opacity_texture >= 0 ? mtl_transform_of(m, MESH_TEXTURE_OPACITY, list, count) : NULL;
	if (m->base_texture >= 0 && m->opacity_texture >= 0 &&
	    (kd || d) && (!kd || !d || memcmp(kd->scale, d->scale, sizeof(kd->scale)) ||
			  memcmp(kd->offset, d->offset, sizeof(kd->offset))))
		note(m, "map_d -s/-o unlike map_Kd's");
	t = m->base_texture >= 0 ? kd : d;
	if (!t)
		return 0;
	b->m[0][0] = t->scale[0];
	b->m[0][2] = t->offset[0];
	b->m[1][1] = t->scale[1];
	b->m[1][2] = t->offset[1];
	return 1;
}

/* Mesh's texture coordinates into uvs (2 per vertex), for its material's
 * textures: the set that binding b reads, through its transform (glTF's in
 * its v-down convention: Assimp's glTF reader turns v up, v' = 1 - v).
 * Without a binding, the first set. */
static void mesh_uvs(const struct aiMesh *mesh, const struct uv_binding *b, double *uvs)
{
	const struct aiVector3D *set = mesh->mTextureCoords[b ? b->set : 0];

	for (unsigned v = 0; set && v < mesh->mNumVertices; v++) {
		double u = set[v].x, w = set[v].y;

		if (b) {
			double y = b->v_down ? 1 - w : w;
			u = b->m[0][0] * set[v].x + b->m[0][1] * y + b->m[0][2];
			y = b->m[1][0] * set[v].x + b->m[1][1] * y + b->m[1][2];
			w = b->v_down ? 1 - y : y;
		}
		uvs[2 * v] = u;
		uvs[2 * v + 1] = w;
	}
}

/* The textures of the materials some triangle has (the others are not
 * read), and then the vertices' texture coordinates (glTF: as the base
 * colour texture's binding says, doc). Returns 0, or -1 when out of
 * memory. */
static int read_textures(const struct aiScene *sc, const char *path, const json_t *doc,
			 struct mesh_data *out)
{
	char *used = calloc(out->material_count ? out->material_count : 1, 1);
	int textured = 0;

	if (!used)
		return -1;
	for (size_t t = 0; t < out->triangle_count; t++)
		if (out->triangle_materials[t] != MESH_NO_MATERIAL)
			used[out->triangle_materials[t]] = 1;
	for (size_t i = 0; i < out->material_count; i++) {
		struct mesh_material *m = &out->materials[i];
		const struct aiMaterial *mat = sc->mMaterials[i];

		if (!used[i] || m->kind == MESH_MATERIAL_MISSING)
			continue;
		m->base_texture = texture_of(sc, path, doc, mat, base_type(mat), MESH_TEXTURE_COLOR, out);
		if (m->kind == MESH_MATERIAL_PHONG)
			m->opacity_texture = texture_of(sc, path, doc, mat, aiTextureType_OPACITY,
							MESH_TEXTURE_OPACITY, out);
		/* glTF's metallicRoughnessTexture: Assimp 5.2 gives it as the
		 * "unknown" type, later versions also as metalness */
		if (m->kind == MESH_MATERIAL_METALLIC_ROUGHNESS)
			m->metallic_roughness_texture = texture_of(
				sc, path, doc, mat,
				aiGetMaterialTextureCount(mat, aiTextureType_UNKNOWN)
					? aiTextureType_UNKNOWN
					: aiTextureType_METALNESS,
				MESH_TEXTURE_DATA, out);
		m->emissive_texture =
			texture_of(sc, path, doc, mat, aiTextureType_EMISSIVE, MESH_TEXTURE_COLOR, out);
		if (m->kind == MESH_MATERIAL_METALLIC_ROUGHNESS)
			m->normal_texture = texture_of(sc, path, doc, mat, aiTextureType_NORMALS,
						       MESH_TEXTURE_DATA, out);
		textured |= m->base_texture >= 0 || m->opacity_texture >= 0 ||
			    m->metallic_roughness_texture >= 0 || m->emissive_texture >= 0 ||
			    m->normal_texture >= 0;
		if (m->base_texture == TEXTURE_NO_MEMORY || m->opacity_texture == TEXTURE_NO_MEMORY ||
		    m->metallic_roughness_texture == TEXTURE_NO_MEMORY ||
		    m->emissive_texture == TEXTURE_NO_MEMORY || m->normal_texture == TEXTURE_NO_MEMORY) {
			free(used);
			return -1;
		}
	}
	free(used);
	if (!textured)
		return 0;
	out->uvs = calloc(out->vertex_count ? out->vertex_count : 1, 2 * sizeof(double));
	if (!out->uvs)
		return -1;
	/* An OBJ's material libraries: the other files the importer opened
	 * (the textures, remembered since, aside). */
	struct mtl_transform *transforms = NULL;
	size_t transform_count = 0, n = strlen(path);
	int obj = n >= 4 && strcasecmp(path + n - 4, ".obj") == 0;
	for (size_t f = 0; obj && f < opened_count; f++)
		if (opened[f].kind != MESH_FILE_TEXTURE &&
		    mtl_read_transforms(opened[f].path, &transforms, &transform_count)) {
			free(transforms);
			return -1;
		}
	size_t base = 0;
	for (unsigned m = 0; m < sc->mNumMeshes; m++) {
		const struct aiMesh *mesh = sc->mMeshes[m];
		unsigned i = mesh->mMaterialIndex;
		struct uv_binding binding;
		int bound = i < out->material_count &&
			    material_binding(sc, i, doc, transforms, transform_count,
					     &out->materials[i], &binding);

		if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
			continue;
		mesh_uvs(mesh, bound ? &binding : NULL, out->uvs + 2 * base);
		base += mesh->mNumVertices;
	}
	free(transforms);
	return 0;
}

/* ---- Nodes: where a light sits ---- */

/* The node called name, depth first (Assimp's FindNode), or NULL. */
static const struct aiNode *find_node(const struct aiNode *node, const struct aiString *name)
{
	if (node->mName.length == name->length &&
	    memcmp(node->mName.data, name->data, name->length) == 0)
		return node;
	for (unsigned i = 0; i < node->mNumChildren; i++) {
		const struct aiNode *found = find_node(node->mChildren[i], name);
		if (found)
			return found;
	}
	return NULL;
}

/* The node's global transform, its parents' applied, in double (rows of
 * a 3x4 matrix: p' = M [p 1]). */
static void global_transform(const struct aiNode *node, double m[3][4])
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 4; j++)
			m[i][j] = i == j;
	for (; node; node = node->mParent) {
		const struct aiMatrix4x4 *t = &node->mTransformation;
		const double p[3][4] = {{t->a1, t->a2, t->a3, t->a4},
					{t->b1, t->b2, t->b3, t->b4},
					{t->c1, t->c2, t->c3, t->c4}};
		double r[3][4];

		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 4; j++)
				r[i][j] = p[i][0] * m[0][j] + p[i][1] * m[1][j] + p[i][2] * m[2][j] +
					  (j == 3 ? p[i][3] : 0);
		memcpy(m, r, sizeof(r));
	}
}

/* ---- Cameras (docs/SCENE.md, "The camera from a mesh file") ---- */

/* The cameras of a file of another format than glTF 2.0 (whose cameras
 * gltf_read_cameras reads): listed by their names, so that the scene's
 * "camera" can say why it cannot take one, not read. Returns -1 when out of
 * memory. */
static int read_cameras(const struct aiScene *sc, struct mesh_data *out)
{
	out->cameras = calloc(sc->mNumCameras ? sc->mNumCameras : 1, sizeof(*out->cameras));
	if (!out->cameras)
		return -1;
	for (unsigned i = 0; i < sc->mNumCameras; i++) {
		const struct aiCamera *cam = sc->mCameras[i];
		struct mesh_camera *c = &out->cameras[out->camera_count];

		if (!cam || !cam->mName.length)
			continue;
		/* Control bytes kept: messages escape them (base/quote.h). */
		snprintf(c->name, sizeof(c->name), "%.*s", (int)sizeof(c->name) - 1,
			 cam->mName.data);
		c->kind = MESH_CAMERA_NOT_GLTF;
		out->camera_count++;
	}
	return 0;
}

/* The lights that a node places, in the file's world space, with their
 * colour times their intensity (Assimp's mColorDiffuse). A glTF light sits
 * at its node's origin shining down its -z (KHR_lights_punctual), whatever
 * Assimp copies into mPosition (as for cameras, read_cameras); another
 * format's at mPosition along mDirection, in its node's space. Returns -1
 * when out of memory. */
static int read_lights(const struct aiScene *sc, struct mesh_data *out)
{
	int gltf = from_gltf2(sc);

	out->lights = calloc(sc->mNumLights ? sc->mNumLights : 1, sizeof(*out->lights));
	if (!out->lights)
		return -1;
	for (unsigned i = 0; i < sc->mNumLights; i++) {
		const struct aiLight *light = sc->mLights[i];
		const struct aiNode *node = light && light->mName.length && sc->mRootNode
						    ? find_node(sc->mRootNode, &light->mName)
						    : NULL;
		struct mesh_light *l = &out->lights[out->light_count];
		double m[3][4], local[3] = {0, 0, -1}, at[3] = {0, 0, 0};

		if (!node)
			continue; /* no node places it */
		if (!gltf) {
			local[0] = light->mDirection.x, local[1] = light->mDirection.y;
			local[2] = light->mDirection.z;
			at[0] = light->mPosition.x, at[1] = light->mPosition.y;
			at[2] = light->mPosition.z;
		}
		snprintf(l->name, sizeof(l->name), "%.*s", (int)sizeof(l->name) - 1,
			 light->mName.data);
		for (char *ch = l->name; *ch; ch++) /* names go into messages on one line */
			if ((unsigned char)*ch < 0x20 || *ch == 0x7f)
				*ch = '?';
		out->light_count++;
		l->kind = light->mType == aiLightSource_POINT	      ? MESH_LIGHT_POINT
			  : light->mType == aiLightSource_DIRECTIONAL ? MESH_LIGHT_DIRECTIONAL
			  : light->mType == aiLightSource_SPOT	      ? MESH_LIGHT_SPOT
								      : MESH_LIGHT_OTHER;
		global_transform(node, m);
		for (int k = 0; k < 3; k++) {
			l->position[k] =
				m[k][0] * at[0] + m[k][1] * at[1] + m[k][2] * at[2] + m[k][3];
			l->direction[k] =
				m[k][0] * local[0] + m[k][1] * local[1] + m[k][2] * local[2];
		}
		l->color[0] = light->mColorDiffuse.r;
		l->color[1] = light->mColorDiffuse.g;
		l->color[2] = light->mColorDiffuse.b;
	}
	return 0;
}

/* The cameras and lights of a file that has some, from a second import
 * without post-processing: PreTransformVertices renames every camera
 * "cam_N" and flattens the node hierarchy, and applying the steps to a scene
 * already imported (aiApplyPostProcessing) frees it twice in Assimp 5.2 when a
 * step fails (found by test/fuzz_mesh.c). Only files with cameras or lights
 * are read twice; cameras only where `cameras` is set (a glTF file's come
 * from gltf_read_cameras). Returns -1 when out of memory; a second import
 * that fails leaves the file without cameras and lights. */
static int import_views(const char *path, struct aiFileIO *io, int cameras,
			struct mesh_data *out)
{
	const struct aiScene *sc = aiImportFileEx(path, 0, io);
	int ret = sc ? (cameras && read_cameras(sc, out)) || read_lights(sc, out) : 0;

	if (sc)
		aiReleaseImport(sc);
	return ret;
}

/* ---- Assimp's log: what it drops with a warning only ----
 * Assimp 5.2's glTF reader leaves out a triangle whose index names a vertex
 * its primitive does not have, and says so only in its log (issue 39
 * finding 10); the glTF specification makes such a file invalid. */

static int dropped_faces;

static void on_assimp_log(const char *message, char *user)
{
	(void)user;
	if (strstr(message, "faces had out-of-range indices"))
		dropped_faces = 1;
}

int mesh_import_here(const char *path, struct mesh_data *out, char *reason, size_t reason_size)
{
	struct aiFileIO io = {file_open, file_close, NULL};
	struct aiLogStream log = {on_assimp_log, NULL};
	const struct aiScene *sc = NULL;
	json_t *doc = NULL;
	size_t vertices, triangles;
	int has_normals, ret = -1;

	memset(out, 0, sizeof(*out));
	refused_file[0] = '\0';
	refused_outside = 0;
	dropped_faces = 0;
	mesh_file = path;
	named_at = strrchr(path, '/') ? (size_t)(strrchr(path, '/') - path) + 1 : 0;
	gltf_names_uris = has_extension(path, ".gltf") || has_extension(path, ".glb");
	forget_opened();
	if (ply_check(path, reason, reason_size) ||
	    obj_polygon_too_large(path, reason, reason_size) ||
	    model_folder_set(path, reason, reason_size) ||
	    gltf_read(path, &doc, reason, reason_size))
		return -1;
	if (doc && gltf_check_required(doc, reason, reason_size))
		goto out_release_scene;
	aiAttachLogStream(&log);
	sc = aiImportFileEx(path, IMPORT_FLAGS, &io);
	aiDetachLogStream(&log);
	if (refused_file[0]) {
		const char *slash = strrchr(path, '/');
		if (refused_outside)
			snprintf(reason, reason_size,
				 "it names \"%s\", which lies outside the folder of \"%s\"",
				 refused_file, slash ? slash + 1 : path);
		else
			snprintf(reason, reason_size,
				 "it names \"%s\", which is not a regular file", refused_file);
		goto out_release_scene;
	}
	if (!sc) {
		snprintf(reason, reason_size, "%s", aiGetErrorString());
		goto out_release_scene;
	}
	/* What the files Assimp opened are, for rtcl's messages. */
	for (size_t i = 0; i < opened_count; i++) {
		if (from_gltf2(sc))
			opened[i].kind = MESH_FILE_BUFFER;
		else if (has_extension(opened[i].path, ".mtl"))
			opened[i].kind = MESH_FILE_LIBRARY;
	}
	if (dropped_faces) {
		snprintf(reason, reason_size,
			 "a triangle of it names a vertex its primitive does not have (glTF: "
			 "every index must be less than the POSITION accessor's count)");
		goto out_release_scene;
	}
	count(sc, &vertices, &triangles, &has_normals);
	out->positions = malloc((vertices ? vertices : 1) * 3 * sizeof(double));
	out->normals = has_normals ? malloc((vertices ? vertices : 1) * 3 * sizeof(double)) : NULL;
	out->indices = malloc((triangles ? triangles : 1) * 3 * sizeof(size_t));
	out->triangle_materials = malloc((triangles ? triangles : 1) * sizeof(uint32_t));
	out->materials = calloc(sc->mNumMaterials ? sc->mNumMaterials : 1, sizeof(*out->materials));
	if (!out->positions || (has_normals && !out->normals) || !out->indices ||
	    !out->triangle_materials || !out->materials) {
		snprintf(reason, reason_size, "out of memory for %zu triangles", triangles);
		goto out_release_scene;
	}
	if (gather(sc, out, reason, reason_size))
		goto out_release_scene;
	for (unsigned m = 0; m < sc->mNumMaterials; m++)
		read_material(sc->mMaterials[m], m, &out->materials[m]);
	out->material_count = sc->mNumMaterials;
	gltf_emissive_strengths(sc, doc, out);
	if (read_textures(sc, path, doc, out)) {
		snprintf(reason, reason_size, "out of memory for its textures");
		goto out_release_scene;
	}
	/* Cameras and lights from a second import (import_views); glTF's
	 * cameras from its JSON instead, each placed by the node that holds
	 * it. */
	if (sc->mNumCameras || sc->mNumLights) {
		aiReleaseImport(sc);
		sc = NULL;
		if (import_views(path, &io, !doc, out)) {
			snprintf(reason, reason_size, "out of memory for its cameras and lights");
			goto out_release_scene;
		}
	}
	if (doc && gltf_read_cameras(doc, out)) {
		snprintf(reason, reason_size, "out of memory for its cameras");
		goto out_release_scene;
	}
	if (opened_failed) {
		snprintf(reason, reason_size, "out of memory for the names of the files it read");
		goto out_release_scene;
	}
	out->files = opened;
	out->file_count = opened_count;
	opened = NULL;
	opened_count = 0;
	ret = 0;
out_release_scene:
	forget_opened();
	if (ret)
		mesh_data_free(out);
	if (sc)
		aiReleaseImport(sc);
	json_decref(doc);
	forget_opened();
	return ret;
}
