/* Mesh files through the Open Asset Import Library's C API, in the helper
 * program rtcl-meshread (see mesh.h). */
#define _POSIX_C_SOURCE 200809L
#include "scene/mesh.h"

#include <errno.h>
#include <fcntl.h>
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

#include "meshread/ply_check.h"
#include "meshread/texture_read.h"

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
	out[length] = '\0';
	for (char *c = out; *c; c++) /* names go into messages on one line */
		if ((unsigned char)*c < 0x20 || *c == 0x7f)
			*c = '?';
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

/* Appends t's texels to out->texels at a 16-byte boundary. Returns 0, or
 * -1 when out of memory (reason in t). */
static int append_texels(struct mesh_data *out, struct mesh_texture *t, unsigned char *texels)
{
	size_t at = (out->texel_bytes + 15) / 16 * 16;
	unsigned char *grown = realloc(out->texels, at + (size_t)t->bytes);

	if (!grown) {
		snprintf(t->reason, sizeof(t->reason), "out of memory for its %llu bytes",
			 (unsigned long long)t->bytes);
		return -1;
	}
	memset(grown + out->texel_bytes, 0, at - out->texel_bytes);
	memcpy(grown + at, texels, (size_t)t->bytes);
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

/* Reads texture t (its name and role set): embedded ("*N") or a file beside
 * the mesh. Its reason says why when it could not be read. */
static void read_texture(const struct aiScene *sc, const char *path, struct mesh_data *out,
			 struct mesh_texture *t)
{
	unsigned char *bytes = NULL, *texels = NULL;
	size_t size = 0;

	if (t->name[0] == '*') {
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
	} else if (!texture_file_bytes(path, t->name, &bytes, &size, t->reason,
				       sizeof(t->reason))) {
		texture_decode(bytes, size, t, &texels);
	}
	free(bytes);
	if (texels && !t->reason[0])
		append_texels(out, t, texels);
	free(texels);
}

/* The index in out->textures of texture `type` of mat, read in `role`
 * (each name and role once), or -1 where mat has none. */
static int32_t texture_of(const struct aiScene *sc, const char *path,
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
	for (size_t i = 0; i < out->texture_count; i++)
		if (out->textures[i].role == role && out->textures[i].wrap_s == wrap_of(modes[0]) &&
		    out->textures[i].wrap_t == wrap_of(modes[1]) &&
		    strncmp(out->textures[i].name, name.data, MESH_TEXTURE_NAME_MAX - 1) == 0)
			return (int32_t)i;
	grown = realloc(out->textures, (out->texture_count + 1) * sizeof(*grown));
	if (!grown)
		return -1;
	out->textures = grown;
	t = &out->textures[out->texture_count];
	memset(t, 0, sizeof(*t));
	snprintf(t->name, sizeof(t->name), "%.*s", (int)sizeof(t->name) - 1, name.data);
	for (char *c = t->name; *c; c++) /* names go into messages on one line */
		if ((unsigned char)*c < 0x20 || *c == 0x7f)
			*c = '?';
	t->role = role;
	t->wrap_s = wrap_of(modes[0]);
	t->wrap_t = wrap_of(modes[1]);
	read_texture(sc, path, out, t);
	return (int32_t)out->texture_count++;
}

/* The textures of the materials some triangle has (the others are not
 * read), and then the vertices' texture coordinates. Returns 0, or -1 when
 * out of memory. */
static int read_textures(const struct aiScene *sc, const char *path, struct mesh_data *out)
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
		/* glTF's base colour texture comes as base colour and diffuse */
		m->base_texture = texture_of(sc, path, mat,
					     aiGetMaterialTextureCount(mat, aiTextureType_BASE_COLOR)
						     ? aiTextureType_BASE_COLOR
						     : aiTextureType_DIFFUSE,
					     MESH_TEXTURE_COLOR, out);
		if (m->kind == MESH_MATERIAL_PHONG)
			m->opacity_texture = texture_of(sc, path, mat, aiTextureType_OPACITY,
							MESH_TEXTURE_OPACITY, out);
		/* glTF's metallicRoughnessTexture: Assimp 5.2 gives it as the
		 * "unknown" type, later versions also as metalness */
		if (m->kind == MESH_MATERIAL_METALLIC_ROUGHNESS)
			m->metallic_roughness_texture = texture_of(
				sc, path, mat,
				aiGetMaterialTextureCount(mat, aiTextureType_UNKNOWN)
					? aiTextureType_UNKNOWN
					: aiTextureType_METALNESS,
				MESH_TEXTURE_DATA, out);
		m->emissive_texture =
			texture_of(sc, path, mat, aiTextureType_EMISSIVE, MESH_TEXTURE_COLOR, out);
		if (m->kind == MESH_MATERIAL_METALLIC_ROUGHNESS)
			m->normal_texture = texture_of(sc, path, mat, aiTextureType_NORMALS,
						       MESH_TEXTURE_DATA, out);
		textured |= m->base_texture >= 0 || m->opacity_texture >= 0 ||
			    m->metallic_roughness_texture >= 0 || m->emissive_texture >= 0 ||
			    m->normal_texture >= 0;
	}
	free(used);
	if (!textured)
		return 0;
	out->uvs = calloc(out->vertex_count ? out->vertex_count : 1, 2 * sizeof(double));
	if (!out->uvs)
		return -1;
	size_t base = 0;
	for (unsigned m = 0; m < sc->mNumMeshes; m++) {
		const struct aiMesh *mesh = sc->mMeshes[m];

		if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
			continue;
		for (unsigned v = 0; mesh->mTextureCoords[0] && v < mesh->mNumVertices; v++) {
			out->uvs[2 * (base + v)] = mesh->mTextureCoords[0][v].x;
			out->uvs[2 * (base + v) + 1] = mesh->mTextureCoords[0][v].y;
		}
		base += mesh->mNumVertices;
	}
	return 0;
}

/* ---- Cameras (docs/SCENE.md, "The camera from a mesh file") ---- */

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

/* A glTF camera's yfov in degrees from what Assimp's glTF 2.0 importer
 * keeps: up to Assimp 5.2, mHorizontalFOV = yfov * aspectRatio; from 5.3
 * (assimp pull request 4886), 2 atan(tan(yfov / 2) aspectRatio); yfov
 * itself where the file gives no aspectRatio (mAspect 0). Not the half
 * angle that aiCamera's documentation names. */
static double gltf_yfov_degrees(const struct aiCamera *cam)
{
	double h = cam->mHorizontalFOV, aspect = cam->mAspect, yfov = h;

	if (aspect > 0)
		yfov = aiGetVersionMajor() < 5 || (aiGetVersionMajor() == 5 && aiGetVersionMinor() <= 2)
			       ? h / aspect
			       : 2 * atan(tan(h / 2) / aspect);
	return yfov * (180.0 / 3.14159265358979323846);
}

/* The cameras that a node places, in the file's world space. A glTF camera
 * sits at its node's origin looking down its -z, +y up (glTF 2.0, "Cameras"):
 * Assimp 5.2 also copies the node's translation into mPosition, which the
 * node's transform applies again, so mPosition is not used. Cameras of
 * other formats are listed, not read. Returns -1 when out of memory. */
static int read_cameras(const struct aiScene *sc, struct mesh_data *out)
{
	int gltf = from_gltf2(sc);

	out->cameras = calloc(sc->mNumCameras ? sc->mNumCameras : 1, sizeof(*out->cameras));
	if (!out->cameras)
		return -1;
	for (unsigned i = 0; i < sc->mNumCameras; i++) {
		const struct aiCamera *cam = sc->mCameras[i];
		const struct aiNode *node =
			cam && cam->mName.length && sc->mRootNode ? find_node(sc->mRootNode, &cam->mName)
								  : NULL;
		struct mesh_camera *c = &out->cameras[out->camera_count];
		double m[3][4];

		if (!node)
			continue; /* no node places it */
		snprintf(c->name, sizeof(c->name), "%.*s", (int)sizeof(c->name) - 1,
			 cam->mName.data);
		for (char *ch = c->name; *ch; ch++) /* names go into messages on one line */
			if ((unsigned char)*ch < 0x20 || *ch == 0x7f)
				*ch = '?';
		out->camera_count++;
		if (!gltf) {
			c->kind = MESH_CAMERA_NOT_GLTF;
			continue;
		}
		c->kind = cam->mHorizontalFOV == 0 ? MESH_CAMERA_ORTHOGRAPHIC
						   : MESH_CAMERA_PERSPECTIVE;
		global_transform(node, m);
		for (int k = 0; k < 3; k++) {
			c->position[k] = m[k][3];
			c->direction[k] = -m[k][2];
			c->up[k] = m[k][1];
		}
		c->fov = gltf_yfov_degrees(cam);
		c->aspect = cam->mAspect;
	}
	return 0;
}

/* The cameras of a file that has some, from a second import without
 * post-processing: PreTransformVertices renames every camera "cam_N" and
 * flattens the node hierarchy, and applying the steps to a scene already
 * imported (aiApplyPostProcessing) frees it twice in Assimp 5.2 when a step
 * fails (found by test/fuzz_mesh.c). Only files with cameras are read twice.
 * Returns -1 when out of memory; a second import that fails leaves the file
 * without cameras. */
static int import_cameras(const char *path, struct aiFileIO *io, struct mesh_data *out)
{
	const struct aiScene *sc = aiImportFileEx(path, 0, io);
	int ret = sc ? read_cameras(sc, out) : 0;

	if (sc)
		aiReleaseImport(sc);
	return ret;
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
	out->triangle_materials = malloc((triangles ? triangles : 1) * sizeof(uint32_t));
	out->materials = calloc(sc->mNumMaterials ? sc->mNumMaterials : 1, sizeof(*out->materials));
	if (!out->positions || (has_normals && !out->normals) || !out->indices ||
	    !out->triangle_materials || !out->materials) {
		snprintf(reason, reason_size, "out of memory for %zu triangles", triangles);
		mesh_data_free(out);
		goto out_release_scene;
	}
	if (gather(sc, out, reason, reason_size)) {
		mesh_data_free(out);
		goto out_release_scene;
	}
	for (unsigned m = 0; m < sc->mNumMaterials; m++)
		read_material(sc->mMaterials[m], m, &out->materials[m]);
	out->material_count = sc->mNumMaterials;
	if (read_textures(sc, path, out)) {
		snprintf(reason, reason_size, "out of memory for its textures");
		mesh_data_free(out);
		goto out_release_scene;
	}
	if (sc->mNumCameras) {
		aiReleaseImport(sc);
		sc = NULL;
		if (import_cameras(path, &io, out)) {
			snprintf(reason, reason_size, "out of memory for its cameras");
			goto out_release_scene;
		}
	}
	ret = 0;
out_release_scene:
	if (ret)
		mesh_data_free(out);
	if (sc)
		aiReleaseImport(sc);
	return ret;
}
