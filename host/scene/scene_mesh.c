/* The scene loader's version 2 (docs/SCENE.md, "Version 2: triangle meshes"):
 * "meshes", files placed with scale, rotate and translate, and the inline
 * "triangles". mesh_import (host/scene/mesh.h) reads the files, host/scene/mesh_place.c computes the
 * placement and the normals; this file reads the fields, puts the triangles
 * in the scene and checks what SCENE.md asks. */
#define _POSIX_C_SOURCE 200809L

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "base/quote.h"
#include "base/suggest.h"
#include "scene/mesh.h"
#include "scene/mesh_place.h"
#include "scene/scene_loader.h"

/* Triangle indices are ints on the device; far below INT_MAX so that the
 * counts and byte offsets computed from them cannot overflow either. */
#define SCENE_MAX_TRIANGLES (INT_MAX / 4)

/* Where a file's name or the importer's reason goes into a message: control
 * bytes escaped as base/quote.h escapes them (\x1b, \n), so that the message
 * stays one line and drives no terminal; a text longer than the buffer ends
 * in "...". */
#define MESSAGE_TEXT_MAX 1200

static const char *one_line(const char *text, char buf[MESSAGE_TEXT_MAX])
{
	size_t n = strlen(text);

	/* The importer ends some reasons with a newline or a space. */
	while (n > 0 && ((unsigned char)text[n - 1] <= ' ' || text[n - 1] == 0x7f))
		n--;
	return quote_bytes(text, n, buf, MESSAGE_TEXT_MAX - 4);
}

/* Makes room for `more` triangles in scene->triangles. */
static int reserve(struct loader *ld, const struct path *p, size_t more)
{
	struct scene *s = ld->scene;
	size_t need = (size_t)s->triangle_count + more, capacity = ld->triangle_capacity;
	struct scene_triangle *grown;

	if (more > SCENE_MAX_TRIANGLES || need > SCENE_MAX_TRIANGLES)
		return loader_fail(ld, p,
				   "the scene would have %zu triangles, more than the limit of %d",
				   need, SCENE_MAX_TRIANGLES);
	if (need <= capacity)
		return 0;
	capacity = capacity * 2 > need ? capacity * 2 : need;
	grown = realloc(s->triangles, capacity * sizeof(*grown));
	if (!grown) {
		loader_write_err(ld, "%s: out of memory for %zu triangles", ld->source, need);
		return -1;
	}
	s->triangles = grown;
	if (s->triangle_uvs) {
		struct scene_triangle_uv *uvs =
			realloc(s->triangle_uvs, capacity * sizeof(*s->triangle_uvs));
		if (!uvs) {
			loader_write_err(ld, "%s: out of memory for %zu triangles", ld->source,
					 need);
			return -1;
		}
		s->triangle_uvs = uvs;
	}
	ld->triangle_capacity = capacity;
	return 0;
}

/* Gives the scene texture coordinates for every triangle (0 for those so
 * far), once a mesh brings a texture. */
static int start_triangle_uvs(struct loader *ld)
{
	struct scene *s = ld->scene;

	if (s->triangle_uvs)
		return 0;
	s->triangle_uvs = calloc(ld->triangle_capacity ? ld->triangle_capacity : 1,
				 sizeof(*s->triangle_uvs));
	if (!s->triangle_uvs) {
		loader_write_err(ld, "%s: out of memory for texture coordinates", ld->source);
		return -1;
	}
	return 0;
}

/* Places every vertex; refuses a non-finite one (from the file) and one that
 * placement puts beyond what float holds. */
static int place_vertices(struct loader *ld, const struct path *p, const char *name,
			  const struct mesh_data *mesh, const struct placement *pl, double *placed)
{
	char buf[100], text[MESSAGE_TEXT_MAX];

	for (size_t v = 0; v < mesh->vertex_count; v++) {
		const double *in = mesh->positions + 3 * v;
		double *out = placed + 3 * v;

		if (!isfinite(in[0]) || !isfinite(in[1]) || !isfinite(in[2]))
			return loader_fail(ld, p, "\"%s\": vertex %zu is not finite, got %s",
					   one_line(name, text), v, loader_fmt_vec3(in, buf));
		if (mesh->uvs && (!isfinite(mesh->uvs[2 * v]) || !isfinite(mesh->uvs[2 * v + 1]))) {
			char u[32], w[32];
			return loader_fail(ld, p,
					   "\"%s\": vertex %zu's texture coordinates are not finite, "
					   "got [%s, %s]",
					   one_line(name, text), v, loader_fmt_num(mesh->uvs[2 * v], u),
					   loader_fmt_num(mesh->uvs[2 * v + 1], w));
		}
		place_point(pl, in, out);
		for (int i = 0; i < 3; i++) {
			if (!(fabs(out[i]) <= SCENE_MAX_MAGNITUDE))
				return loader_fail(
					ld, p,
					"\"%s\": vertex %zu is at %s after placement, beyond %g in "
					"magnitude (rtcl computes in float)",
					one_line(name, text), v, loader_fmt_vec3(out, buf),
					SCENE_MAX_MAGNITUDE);
		}
	}
	return 0;
}

/* Appends the mesh's triangles with area (after placement), in the vertex
 * order that keeps their normals outward under a mirroring scale; counts
 * the others in scene->skipped_triangles. vn: the vertex normals, or NULL.
 * Each triangle gets materials[its file material] (-1: the default
 * material), or material where materials is NULL. */
static void append_triangles(struct scene *s, const struct mesh_data *mesh, const double *placed,
			     const double *vn, const struct placement *pl, int material,
			     const int *materials)
{
	static const int straight[3] = {0, 1, 2}, mirrored[3] = {0, 2, 1};
	const int *order = pl->mirrored ? mirrored : straight;

	for (size_t t = 0; t < mesh->triangle_count; t++) {
		struct scene_triangle *tri = &s->triangles[s->triangle_count];
		double n[3];

		for (int k = 0; k < 3; k++)
			memcpy(tri->v[k], placed + 3 * mesh->indices[3 * t + order[k]],
			       sizeof(tri->v[k]));
		if (!place_triangle_normal(tri->v, n)) {
			s->skipped_triangles++;
			continue;
		}
		for (int k = 0; k < 3; k++) {
			const double *from = vn ? vn + 3 * mesh->indices[3 * t + order[k]] : n;

			/* A vertex without a usable normal takes the triangle's. */
			memcpy(tri->normal[k], from[0] || from[1] || from[2] ? from : n,
			       sizeof(tri->normal[k]));
		}
		tri->material = material;
		if (materials)
			tri->material = mesh->triangle_materials[t] == MESH_NO_MATERIAL
						? -1
						: materials[mesh->triangle_materials[t]];
		tri->smooth = vn != NULL;
		if (s->triangle_uvs) {
			struct scene_triangle_uv *uv = &s->triangle_uvs[s->triangle_count];
			for (int k = 0; k < 3; k++)
				for (int c = 0; c < 2; c++) {
					double x = mesh->uvs ? mesh->uvs[2 * mesh->indices
										 [3 * t + order[k]] +
									 c]
							     : 0.0;
					/* beyond 1e18: 1e18 (the device's float keeps
					   any product of it finite) */
					uv->uv[k][c] = x > SCENE_MAX_MAGNITUDE	  ? SCENE_MAX_MAGNITUDE
						       : x < -SCENE_MAX_MAGNITUDE ? -SCENE_MAX_MAGNITUDE
										  : x;
				}
		}
		s->triangle_count++;
	}
}

/* "scale": a number or a vec3, no part 0. */
static int read_scale(struct loader *ld, const struct path *item, json_t *obj, double scale[3])
{
	struct path field = child_key(item, "scale");
	json_t *v = json_object_get(obj, "scale");

	scale[0] = scale[1] = scale[2] = 1;
	if (!v)
		return 0;
	if (json_is_number(v)) {
		if (loader_check_number(ld, &field, v, ANY, &scale[0]))
			return -1;
		if (scale[0] == 0)
			return loader_fail(ld, &field, "must not be 0");
		scale[1] = scale[2] = scale[0];
		return 0;
	}
	if (!json_is_array(v))
		return loader_fail(ld, &field, "must be a number or an array of 3 numbers, got %s",
				   loader_type_name(v));
	if (loader_check_vec3(ld, &field, v, ANY, scale))
		return -1;
	for (size_t i = 0; i < 3; i++) {
		struct path part = child_index(&field, i);

		if (scale[i] == 0)
			return loader_fail(ld, &part, "must not be 0");
	}
	return 0;
}

static int read_placement(struct loader *ld, const struct path *item, json_t *obj,
			  struct placement *pl)
{
	struct path smooth = child_key(item, "smooth");
	double degrees[3] = {0, 0, 0};
	json_t *v;

	memset(pl, 0, sizeof(*pl));
	if (read_scale(ld, item, obj, pl->scale) ||
	    loader_read_vec3(ld, item, obj, "rotate", OPTIONAL, ANY, degrees) ||
	    loader_read_vec3(ld, item, obj, "translate", OPTIONAL, ANY, pl->translate) ||
	    loader_get_field(ld, item, obj, "smooth", OPTIONAL, &v))
		return -1;
	if (v && !json_is_boolean(v))
		return loader_fail(ld, &smooth, "must be true or false, got %s",
				   loader_type_name(v));
	pl->smooth = !v || json_is_true(v);
	place_set_rotation(pl, degrees);
	return 0;
}

/* The file's path: relative to the scene file's folder unless absolute. */
static char *mesh_path(const struct loader *ld, const char *name)
{
	const char *dir = name[0] == '/' || !ld->base_dir ? "" : ld->base_dir;
	size_t size = strlen(dir) + strlen(name) + 1;
	char *path = malloc(size);

	if (path)
		snprintf(path, size, "%s%s", dir, name);
	return path;
}

/* Places the imported mesh and appends its triangles, with material or,
 * where materials is not NULL, their file materials' (append_triangles). */
static int place_mesh(struct loader *ld, const struct path *file, const char *name,
		      const struct mesh_data *mesh, const struct placement *pl, int material,
		      const int *materials)
{
	size_t values = 3 * (mesh->vertex_count ? mesh->vertex_count : 1);
	double *placed = malloc(values * sizeof(double));
	double *vn = pl->smooth ? calloc(values, sizeof(double)) : NULL;
	int ret = -1;

	if (!placed || (pl->smooth && !vn)) {
		loader_write_err(ld, "%s: out of memory for %zu vertices", ld->source,
				 mesh->vertex_count);
		goto out_free;
	}
	if (place_vertices(ld, file, name, mesh, pl, placed) ||
	    reserve(ld, file, mesh->triangle_count) ||
	    (mesh->uvs && materials && start_triangle_uvs(ld)))
		goto out_free;
	if (vn && mesh->normals)
		place_file_normals(mesh, pl, vn);
	else if (vn && place_area_weighted_normals(mesh, placed, pl->mirrored, vn)) {
		loader_write_err(ld, "%s: out of memory for %zu vertices", ld->source,
				 mesh->vertex_count);
		goto out_free;
	}
	int before = ld->scene->triangle_count;
	append_triangles(ld->scene, mesh, placed, vn, pl, material, materials);
	for (int t = before; t < ld->scene->triangle_count; t++)
		if (ld->scene->triangles[t].material < 0)
			ld->default_used = 1;
	/* Nothing to see, and most likely not a mesh at all (random bytes that
	 * an importer read as one): issue 24 finding 10. */
	if (ld->scene->triangle_count == before) {
		char text[MESSAGE_TEXT_MAX];
		ret = mesh->triangle_count == 1
			      ? loader_fail(ld, file,
					    "\"%s\": its one triangle has area 0 (after placement)",
					    one_line(name, text))
			      : loader_fail(ld, file,
					    "\"%s\": all of its %zu triangles have area 0 (after "
					    "placement)",
					    one_line(name, text), mesh->triangle_count);
		goto out_free;
	}
	ret = 0;
out_free:
	free(placed);
	free(vn);
	return ret;
}

/* ---- The file's materials (SCENE.md, "Materials from mesh files") ---- */

/* Appends a copy of line to *lines. Returns 0, or -1 with one message. */
static int add_line(struct loader *ld, char ***lines, int *count, const char *line)
{
	char **grown = realloc(*lines, (size_t)(*count + 1) * sizeof(*grown));

	if (!grown || !(grown[*count] = strdup(line))) {
		if (grown)
			*lines = grown;
		loader_write_err(ld, "%s: out of memory", ld->source);
		return -1;
	}
	*lines = grown;
	(*count)++;
	return 0;
}

/* Appends what -v says of the mesh at item (file name) to scene->mesh_reports:
 * the materials and textures it brought, what rtcl did not understand. */
static int report_mesh(struct loader *ld, const struct path *item, const char *name,
		       const struct mesh_data *mesh, int forced)
{
	struct scene *s = ld->scene;
	char line[2 * MESSAGE_TEXT_MAX + 300], notes[700] = "", where[200], text[MESSAGE_TEXT_MAX],
		said[MESSAGE_TEXT_MAX];
	size_t materials = 0, used = 0, textures = 0;
	char *has = calloc(mesh->material_count ? mesh->material_count : 1, 1);

	if (!has) {
		loader_write_err(ld, "%s: out of memory", ld->source);
		return -1;
	}
	for (size_t t = 0; t < mesh->triangle_count; t++)
		if (mesh->triangle_materials[t] != MESH_NO_MATERIAL)
			has[mesh->triangle_materials[t]] = 1;

	for (size_t i = 0; i < mesh->material_count; i++) {
		const struct mesh_material *m = &mesh->materials[i];
		const char *n = m->not_understood;

		if (m->kind == MESH_MATERIAL_MISSING)
			continue;
		materials++;
		used += has[i];
		textures += m->textures;
		/* each note once over the materials */
		for (const char *end; *n; n = *end ? end + 2 : end) {
			char one[MESH_NOTES_MAX];
			size_t len, have = strlen(notes);
			end = strstr(n, ", ");
			end = end ? end : n + strlen(n);
			len = (size_t)(end - n);
			snprintf(one, sizeof(one), "%.*s", (int)len, n);
			int seen = 0;
			for (const char *at = notes; !seen && (at = strstr(at, one)); at += len)
				seen = (at == notes || at[-1] == ' ') &&
				       (at[len] == ',' || at[len] == '\0');
			if (!seen && have + len + 3 < sizeof(notes))
				snprintf(notes + have, sizeof(notes) - have, "%s%s",
					 have ? ", " : "", one);
		}
	}
	free(has);
	loader_format_path(item, where, sizeof(where));
	snprintf(line, sizeof(line), "%s \"%s\": %zu material%s (%zu used), %zu texture%s%s%s%s",
		 where, one_line(name, text), materials, materials == 1 ? "" : "s", used, textures,
		 textures == 1 ? "" : "s",
		 forced ? "; replaced by its \"material\"" : "",
		 notes[0] && !forced ? "; not understood: " : "",
		 forced ? "" : one_line(notes, said));
	return add_line(ld, &s->mesh_reports, &s->mesh_report_count, line);
}

/* A material's name in a message: cut after 64 bytes ("abc..."), as the
 * scene's own names are (scene_check.c). */
static const char *short_name(const char *name, char buf[MESSAGE_TEXT_MAX])
{
	one_line(name, buf);
	if (strlen(buf) > 64)
		snprintf(buf + 64, MESSAGE_TEXT_MAX - 64, "...");
	return buf;
}

/* Whether the file's material i is one of its own: not the importer's
 * stand-in for none (DefaultMaterial, glTF's unnamed default "#N") unless a
 * triangle has it (an OBJ's usemtl of an undefined name). */
static int file_has(const struct mesh_data *mesh, size_t i, const char *used)
{
	return mesh->materials[i].kind != MESH_MATERIAL_MISSING || used[i];
}

/* "FILE has no material "KEY"; its materials are ...", at field, with the
 * nearest of them suggested (issue 39: "#1" and "DefaultMaterial", the
 * importer's stand-ins, were accepted with no effect). */
static int fail_unknown_file_material(struct loader *ld, const struct path *field, const char *name,
				      const struct mesh_data *mesh, const char *used,
				      const char *key)
{
	char known[600] = "", text[MESSAGE_TEXT_MAX], quoted[MESSAGE_TEXT_MAX];
	const char **names = malloc((mesh->material_count + 1) * sizeof(*names));
	size_t have = 0, count = 0;

	for (size_t i = 0; i < mesh->material_count; i++) {
		const char *n = mesh->materials[i].name;
		int seen = 0;
		if (!file_has(mesh, i, used))
			continue;
		for (size_t j = 0; j < i; j++)
			seen |= file_has(mesh, j, used) && strcmp(mesh->materials[j].name, n) == 0;
		if (seen)
			continue;
		if (names)
			names[count++] = n;
		if (have + 64 + 12 >= sizeof(known)) {
			if (!strstr(known, ", ..."))
				snprintf(known + have, sizeof(known) - have, ", ...");
			continue;
		}
		char cut[MESSAGE_TEXT_MAX];
		snprintf(known + have, sizeof(known) - have, "%s\"%s\"", have ? ", " : "",
			 short_name(n, cut));
		have = strlen(known);
	}
	if (!have)
		loader_fail(ld, field, "\"%s\" has no material \"%s\"; it has no materials",
			    one_line(name, text), short_name(key, quoted));
	else
		loader_fail(ld, field, "\"%s\" has no material \"%s\"; its materials are %s",
			    one_line(name, text), short_name(key, quoted), known);
	if (names)
		suggest_append(ld->err, ld->err_size, key, names, count, "");
	free(names);
	return -1;
}

/* The textures of one mesh file as its materials are mapped: which of them
 * went into the scene (SCENE.md, "Textures"). */
struct mesh_textures {
	const struct path *file; /* meshes[i].file, where messages point */
	const char *name;	 /* the file's name as the scene gives it */
	struct mesh_data *mesh; /* its texels taken by add_texture where one texture has them all */
	int *scene_index; /* per texture of the file: 0 not yet used, -1 left
			     out (warned), else 1 + its index in scene.textures */
	int warn;	  /* "missing_textures": "warn" */
};

static const char *const wrap_names[] = {"repeat", "clamp", "mirror"};

/* Copies the file's texture i into scene.textures and says so for -v.
 * Returns 1 + its index, or -1 with one message. */
static int add_texture(struct loader *ld, struct mesh_textures *mt, int i)
{
	const struct mesh_texture *in = &mt->mesh->textures[i];
	struct scene *s = ld->scene;
	struct scene_texture *grown, *t;
	char line[2 * MESSAGE_TEXT_MAX + 300], where[200], text[MESSAGE_TEXT_MAX],
		tex[MESSAGE_TEXT_MAX];

	grown = realloc(s->textures, (size_t)(s->texture_count + 1) * sizeof(*grown));
	if (!grown) {
		loader_write_err(ld, "%s: out of memory", ld->source);
		return -1;
	}
	s->textures = grown;
	t = &s->textures[s->texture_count];
	memset(t, 0, sizeof(*t));
	t->name = strdup(in->name);
	/* The file's only texels (the common case, a large texture among them)
	 * are taken, not copied: the import held them twice (issue 39,
	 * finding 14). */
	if (in->bytes && in->offset == 0 && in->bytes == mt->mesh->texel_bytes) {
		t->texels = mt->mesh->texels;
		mt->mesh->texels = NULL;
		mt->mesh->texel_bytes = 0;
	} else {
		t->texels = malloc(in->bytes ? (size_t)in->bytes : 1);
		if (t->texels && in->bytes)
			memcpy(t->texels, mt->mesh->texels + in->offset, (size_t)in->bytes);
	}
	if (!t->name || !t->texels) {
		free(t->name);
		free(t->texels);
		loader_write_err(ld, "%s: out of memory for texture \"%s\"", ld->source,
				 one_line(in->name, tex));
		return -1;
	}
	t->bytes = (size_t)in->bytes;
	t->mesh = (int)mt->file->parent->index;
	t->width = (int)in->width;
	t->height = (int)in->height;
	t->is_float = in->format == MESH_TEXELS_FLOAT;
	t->is_linear = in->role == MESH_TEXTURE_DATA;
	t->wrap_s = (int)in->wrap_s;
	t->wrap_t = (int)in->wrap_t;
	s->texture_count++;
	loader_format_path(mt->file->parent, where, sizeof(where));
	snprintf(line, sizeof(line), "%s \"%s\": texture \"%s\": %dx%d %s, %s/%s, %zu bytes", where,
		 one_line(mt->name, text), one_line(in->name, tex), t->width, t->height,
		 t->is_float ? "float linear" : t->is_linear ? "8-bit linear" : "8-bit sRGB",
		 wrap_names[t->wrap_s],
		 wrap_names[t->wrap_t], t->bytes);
	if (add_line(ld, &s->mesh_reports, &s->mesh_report_count, line))
		return -1;
	return s->texture_count;
}

/* The file's texture i as a material's field (1 + its index in
 * scene.textures, added at its first use), or 0 where it cannot be read and
 * missing_textures is "warn" (then a warning, once); -1 with one message
 * where it cannot be read. material: the file's material's name. */
static int use_texture(struct loader *ld, struct mesh_textures *mt, const char *material, int i)
{
	const struct mesh_texture *t = &mt->mesh->textures[i];
	char text[MESSAGE_TEXT_MAX], quoted[MESSAGE_TEXT_MAX], tex[MESSAGE_TEXT_MAX],
		why[MESSAGE_TEXT_MAX];
	char warning[4 * MESSAGE_TEXT_MAX];

	if (mt->scene_index[i])
		return mt->scene_index[i] < 0 ? 0 : mt->scene_index[i];
	if (!t->reason[0])
		return mt->scene_index[i] = add_texture(ld, mt, i);
	loader_fail(ld, mt->file, "\"%s\": material \"%s\": cannot read texture \"%s\": %s",
		    one_line(mt->name, text), short_name(material, quoted), one_line(t->name, tex),
		    one_line(t->reason, why));
	if (!mt->warn)
		return -1;
	snprintf(warning, sizeof(warning), "%s; its material renders without it", ld->err);
	if (add_line(ld, &ld->scene->warnings, &ld->scene->warning_count, warning))
		return -1;
	mt->scene_index[i] = -1;
	return 0;
}

/* Gives the scene material made from the file's material in its textures
 * and cut-out (RENDERING.md, "Textures", "Alpha cut-out"). Returns 0, or -1
 * with one message. */
static int attach_textures(struct loader *ld, struct mesh_textures *mt,
			   const struct mesh_material *in, struct scene_material *m)
{
	int base = 0, opacity = 0;

	if (in->base_texture >= 0 && (base = use_texture(ld, mt, in->name, in->base_texture)) < 0)
		return -1;
	if (in->opacity_texture >= 0 &&
	    (opacity = use_texture(ld, mt, in->name, in->opacity_texture)) < 0)
		return -1;
	m->texture = base;
	if (in->metallic_roughness_texture >= 0 &&
	    (m->metallic_roughness_texture =
		     use_texture(ld, mt, in->name, in->metallic_roughness_texture)) < 0)
		return -1;
	if (in->emissive_texture >= 0 &&
	    (m->emissive_texture = use_texture(ld, mt, in->name, in->emissive_texture)) < 0)
		return -1;
	if (in->normal_texture >= 0 &&
	    (m->normal_texture = use_texture(ld, mt, in->name, in->normal_texture)) < 0)
		return -1;
	if (in->opacity_texture >= 0) { /* MTL's map_d: cut out below 0.5 */
		m->alpha_texture = opacity;
		m->alpha_cutoff = 0.5;
		m->alpha_scale = 1;
	} else if (m->alpha_cutoff > 0) { /* glTF's MASK: the base colour's alpha */
		m->alpha_texture = base;
	}
	/* Nothing to cut where the alpha is one number at or above the cutoff. */
	if (!m->alpha_texture && m->alpha_scale >= m->alpha_cutoff)
		m->alpha_cutoff = 0;
	return 0;
}

static int map_materials(struct loader *ld, const struct path *item, const char *name,
			 const struct mesh_data *mesh, json_t *overrides, int *map,
			 const char *used, struct mesh_textures *mt);

/* The scene material of each of the file's materials (-1: the default
 * material), into map: "materials" (overrides, an object or NULL) by name,
 * else the file's own by RENDERING.md's rule; a material no triangle has is
 * left out. */
static int map_file_materials(struct loader *ld, const struct path *item, const char *name,
			      const struct mesh_data *mesh, json_t *overrides, int *map,
			      struct mesh_textures *mt)
{

	char *used = calloc(mesh->material_count ? mesh->material_count : 1, 1);

	if (!used) {
		loader_write_err(ld, "%s: out of memory", ld->source);
		return -1;
	}
	/* Only the materials some triangle has go to the device. */
	for (size_t t = 0; t < mesh->triangle_count; t++)
		if (mesh->triangle_materials[t] != MESH_NO_MATERIAL)
			used[mesh->triangle_materials[t]] = 1;
	int ret = map_materials(ld, item, name, mesh, overrides, map, used, mt);
	free(used);
	return ret;
}

static int map_materials(struct loader *ld, const struct path *item, const char *name,
			 const struct mesh_data *mesh, json_t *overrides, int *map,
			 const char *used, struct mesh_textures *mt)
{
	struct path field = child_key(item, "materials");
	char text[MESSAGE_TEXT_MAX], quoted[MESSAGE_TEXT_MAX];
	const char *key;
	json_t *value;

	for (size_t i = 0; i < mesh->material_count; i++)
		map[i] = INT_MIN; /* not yet */
	json_object_foreach(overrides, key, value)
	{
		struct path entry = child_key(&field, key);
		int index, found = 0;

		if (loader_read_material_value(ld, &entry, value, &index))
			return -1;
		for (size_t i = 0; i < mesh->material_count; i++)
			if (file_has(mesh, i, used) && strcmp(mesh->materials[i].name, key) == 0) {
				map[i] = index;
				found = 1;
			}
		if (!found)
			return fail_unknown_file_material(ld, &field, name, mesh, used, key);
	}
	for (size_t i = 0; i < mesh->material_count; i++) {
		const struct mesh_material *in = &mesh->materials[i];
		struct scene_material m;
		const char *bad;

		if (map[i] != INT_MIN)
			continue;
		if (!used[i] || in->kind == MESH_MATERIAL_MISSING) {
			map[i] = -1;
			continue;
		}
		if ((bad = loader_material_from_mesh(in, &m)))
			return loader_fail(ld, item, "\"%s\": material \"%s\": %s is not finite",
					   one_line(name, text), short_name(in->name, quoted), bad);
		if ((map[i] = loader_append_material(ld, &m)) < 0 ||
		    attach_textures(ld, mt, in, &ld->scene->materials[map[i]]))
			return -1;
	}
	return 0;
}

/* "missing_textures": "error" (the default) or "warn", into *warn. */
static int read_missing_textures(struct loader *ld, const struct path *item, json_t *obj,
				 int *warn)
{
	struct path field = child_key(item, "missing_textures");
	json_t *v = json_object_get(obj, "missing_textures");

	*warn = 0;
	if (!v)
		return 0;
	if (json_is_string(v) && strcmp(json_string_value(v), "error") == 0)
		return 0;
	if (json_is_string(v) && strcmp(json_string_value(v), "warn") == 0) {
		*warn = 1;
		return 0;
	}
	if (json_is_string(v))
		return loader_fail_quoted(ld, &field, "must be \"error\" or \"warn\", got ",
					  json_string_value(v));
	return loader_fail(ld, &field, "must be \"error\" or \"warn\", got %s",
			   loader_type_name(v));
}

/* ---- The file's camera (SCENE.md, "The camera from a mesh file") ---- */

/* "camera": true (the file's first camera), a camera's name, or false;
 * *request is NULL where the entry takes no camera. */
static int read_camera_request(struct loader *ld, const struct path *item, json_t *obj,
			       json_t **request)
{
	struct path field = child_key(item, "camera");
	json_t *v = json_object_get(obj, "camera");

	*request = NULL;
	if (!v || json_is_false(v))
		return 0;
	if (!json_is_true(v) && !json_is_string(v))
		return loader_fail(ld, &field,
				   "must be true, false or the name of a camera of the file, got %s",
				   loader_type_name(v));
	if (json_is_string(v) && !json_string_value(v)[0])
		return loader_fail(ld, &field, "must name a camera of the file, got \"\"");
	if (ld->camera_mesh)
		return loader_fail(ld, &field,
				   "meshes[%zu] gives the camera already; one mesh at most may",
				   ld->camera_mesh - 1);
	*request = v;
	return 0;
}

/* "FILE has no camera "NAME"; its cameras are ...", at field. */
static int fail_unknown_camera(struct loader *ld, const struct path *field, const char *name,
			       const struct mesh_data *mesh, const char *wanted)
{
	char known[600] = "", text[MESSAGE_TEXT_MAX], quoted[MESSAGE_TEXT_MAX];
	size_t have = 0;

	for (size_t i = 0; i < mesh->camera_count; i++) {
		char cut[MESSAGE_TEXT_MAX];
		if (have + 64 + 12 >= sizeof(known)) {
			snprintf(known + have, sizeof(known) - have, ", ...");
			break;
		}
		snprintf(known + have, sizeof(known) - have, "%s\"%s\"", have ? ", " : "",
			 short_name(mesh->cameras[i].name, cut));
		have = strlen(known);
	}
	return loader_fail(ld, field, "\"%s\" has no camera \"%s\"; its cameras are %s",
			   one_line(name, text), short_name(wanted, quoted), known);
}

static int finite3(const double v[3])
{
	return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

/* Makes the file's camera (the first, or the one request names) the
 * scene's view, placed as the mesh is: eye its position, look_at one unit
 * along its view direction, up its up (unit), fov its vertical one. */
static int take_camera(struct loader *ld, const struct path *item, const char *name,
		       const struct mesh_data *mesh, const struct placement *pl, json_t *request)
{
	struct path field = child_key(item, "camera");
	struct scene_camera *cam = &ld->scene->camera;
	const struct mesh_camera *c = NULL;
	char text[MESSAGE_TEXT_MAX], cname[MESSAGE_TEXT_MAX], buf[200], a[100], b[100], u[100],
		f[32], where[200], line[2 * MESSAGE_TEXT_MAX + 300];
	double dir[3], up[3];
	const char *problem, *which;

	one_line(name, text);
	if (mesh->camera_count == 0)
		return loader_fail(ld, &field, "\"%s\" has no camera", text);
	if (json_is_string(request)) {
		for (size_t i = 0; !c && i < mesh->camera_count; i++)
			if (strcmp(mesh->cameras[i].name, json_string_value(request)) == 0)
				c = &mesh->cameras[i];
		if (!c)
			return fail_unknown_camera(ld, &field, name, mesh,
						   json_string_value(request));
	} else {
		c = &mesh->cameras[0];
	}
	short_name(c->name, cname);
	if (c->kind == MESH_CAMERA_NOT_GLTF)
		return loader_fail(ld, &field,
				   "\"%s\": camera \"%s\": rtcl reads cameras from glTF 2.0 files "
				   "only",
				   text, cname);
	if (c->kind == MESH_CAMERA_ORTHOGRAPHIC)
		return loader_fail(ld, &field,
				   "\"%s\": camera \"%s\" is orthographic; rtcl renders only "
				   "perspective cameras",
				   text, cname);
	if (!finite3(c->position) || !finite3(c->direction) || !finite3(c->up) ||
	    !isfinite(c->fov))
		return loader_fail(ld, &field, "\"%s\": camera \"%s\" is not finite", text, cname);
	if (!(c->fov > 0 && c->fov < 180))
		return loader_fail(ld, &field,
				   "\"%s\": camera \"%s\": its vertical field of view is %s "
				   "degrees; rtcl needs 0 < fov < 180",
				   text, cname, loader_fmt_num(c->fov, f));
	place_point(pl, c->position, cam->eye);
	place_vector(pl, c->direction, dir);
	place_vector(pl, c->up, up);
	for (int i = 0; i < 3; i++)
		if (!(fabs(cam->eye[i]) <= SCENE_MAX_MAGNITUDE))
			return loader_fail(ld, &field,
					   "\"%s\": camera \"%s\" is at %s after placement, beyond "
					   "%g in magnitude (rtcl computes in float)",
					   text, cname, loader_fmt_vec3(cam->eye, a),
					   SCENE_MAX_MAGNITUDE);
	if (!place_unit(dir) || !place_unit(up))
		return loader_fail(ld, &field,
				   "\"%s\": camera \"%s\" has no %s (its node's scale is 0)", text,
				   cname, place_unit(dir) ? "up direction" : "view direction");
	for (int i = 0; i < 3; i++) {
		cam->look_at[i] = cam->eye[i] + dir[i];
		cam->up[i] = up[i];
	}
	cam->fov = c->fov;
	problem = loader_camera_problem(cam, &which, buf);
	if (problem)
		return loader_fail(ld, &field, "\"%s\": camera \"%s\": after placement, camera.%s %s",
				   text, cname, which, problem);
	loader_default_focus(cam);
	ld->camera_mesh = item->index + 1;
	loader_format_path(item, where, sizeof(where));
	snprintf(line, sizeof(line),
		 "%s \"%s\": camera \"%s\": eye %s, look_at %s, up %s, fov %s", where, text,
		 cname, loader_fmt_vec3(cam->eye, a), loader_fmt_vec3(cam->look_at, b),
		 loader_fmt_vec3(cam->up, u), loader_fmt_num(cam->fov, f));
	return add_line(ld, &ld->scene->mesh_reports, &ld->scene->mesh_report_count, line);
}

/* Every file the import read besides the mesh file is an input of the run
 * too, which no output may replace (issue 39 finding 1). */
static int add_mesh_inputs(struct loader *ld, const struct mesh_data *mesh)
{
	static const char *const kinds[] = {"texture", "material library", "glTF buffer",
					    "mesh file's companion"};

	for (size_t i = 0; i < mesh->file_count; i++) {
		char *copy = strdup(mesh->files[i].path);

		if (!copy) {
			loader_write_err(ld, "%s: out of memory", ld->source);
			return -1;
		}
		if (loader_add_input(ld, copy, kinds[mesh->files[i].kind]))
			return -1;
	}
	return 0;
}

/* A model rendered alone takes its file's lights (docs/SCENE.md, "A model
 * file alone"), placed as its triangles are, with the file's colours times
 * intensities: scene_model.c scales them. A spot light is lit as a point
 * light (rtcl has no cone), an area or ambient light is not read; -v says
 * so. */
static int take_lights(struct loader *ld, const struct path *item, const char *name,
		       const struct mesh_data *mesh, const struct placement *pl)
{
	struct scene *s = ld->scene;
	char where[200], text[MESSAGE_TEXT_MAX], lname[MESSAGE_TEXT_MAX],
		line[sizeof(where) + 2 * MESSAGE_TEXT_MAX + 64];

	if (mesh->light_count == 0)
		return 0;
	struct scene_light *grown =
		realloc(s->lights, (size_t)(s->light_count + mesh->light_count) * sizeof(*grown));
	if (!grown) {
		loader_write_err(ld, "%s: out of memory", ld->source);
		return -1;
	}
	s->lights = grown;
	loader_format_path(item, where, sizeof(where));
	one_line(name, text);
	for (size_t i = 0; i < mesh->light_count; i++) {
		const struct mesh_light *m = &mesh->lights[i];
		struct scene_light *l = &s->lights[s->light_count];
		const char *note = NULL;
		int usable = m->kind != MESH_LIGHT_OTHER;

		memset(l, 0, sizeof(*l));
		short_name(m->name, lname);
		place_point(pl, m->position, l->position);
		place_vector(pl, m->direction, l->direction);
		for (int k = 0; k < 3; k++) {
			l->color[k] = isfinite(m->color[k]) && m->color[k] > 0 ? m->color[k] : 0;
			usable &= fabs(l->position[k]) <= SCENE_MAX_MAGNITUDE;
		}
		l->directional = m->kind == MESH_LIGHT_DIRECTIONAL;
		if (l->directional)
			usable &= place_unit(l->direction);
		if (m->kind == MESH_LIGHT_OTHER)
			note = "an area or ambient light, not read";
		else if (!usable)
			note = "not finite after placement, not read";
		else if (m->kind == MESH_LIGHT_SPOT)
			note = "a spot light, lit as a point light (rtcl has no cone)";
		if (note) {
			snprintf(line, sizeof(line), "%s \"%s\": light \"%s\": %s", where, text,
				 lname, note);
			if (add_line(ld, &s->mesh_reports, &s->mesh_report_count, line))
				return -1;
		}
		if (usable)
			s->light_count++;
	}
	return 0;
}

/* Whether the file at path is glTF 1.0: a .glb of container version 1, or
 * a .gltf whose "asset" says version 1.x (glTF 2.0 requires the asset). Its
 * materials (techniques and shaders) are not glTF 2.0's, which the importer
 * reads as none: such a model rendered black (issue 44). */
static int is_gltf_1(const char *path)
{
	const char *ext = strrchr(path, '.');
	unsigned char head[12];
	char text[65537], *at;
	size_t n;
	struct stat st;
	FILE *file;
	int old = 0;

	if (!ext || (strcasecmp(ext, ".gltf") != 0 && strcasecmp(ext, ".glb") != 0))
		return 0;
	if (stat(path, &st) != 0 || !S_ISREG(st.st_mode))
		return 0; /* the importer's to refuse, without blocking on a FIFO */
	file = fopen(path, "rb");
	if (!file)
		return 0; /* the importer says why */
	if (strcasecmp(ext, ".glb") == 0) {
		old = fread(head, 1, sizeof(head), file) == sizeof(head) &&
		      memcmp(head, "glTF", 4) == 0 && head[4] == 1 && !head[5] && !head[6] &&
		      !head[7];
	} else {
		n = fread(text, 1, sizeof(text) - 1, file);
		text[n] = '\0';
		at = strstr(text, "\"asset\"");
		at = at ? strstr(at, "\"version\"") : NULL;
		at = at ? strchr(at + 9, '"') : NULL;
		old = at && at[1] == '1' && (at[2] == '.' || at[2] == '"');
	}
	fclose(file);
	return old;
}

static int read_mesh(struct loader *ld, const struct path *item, json_t *obj)
{
	static const char *const keys[] = {"file",	 "material", "materials",
					   "scale",	 "rotate",   "translate",
					   "smooth",	 "missing_textures", "camera", NULL};
	struct path file = child_key(item, "file");
	char reason[MESSAGE_TEXT_MAX], text[MESSAGE_TEXT_MAX], why[MESSAGE_TEXT_MAX];
	struct mesh_data mesh;
	struct placement pl;
	const char *name;
	int material = -1, ret, *map = NULL, warn;
	struct mesh_textures mt = {.file = &file, .name = NULL};
	char *path;
	json_t *v, *forced, *overrides, *camera;

	if (loader_expect_object(ld, item, obj, keys) ||
	    loader_get_field(ld, item, obj, "file", REQUIRED, &v))
		return -1;
	if (!json_is_string(v))
		return loader_fail(ld, &file, "must be a string, got %s", loader_type_name(v));
	name = json_string_value(v);
	if (!name[0])
		return loader_fail(ld, &file, "must name a file, got \"\"");
	forced = json_object_get(obj, "material");
	overrides = json_object_get(obj, "materials");
	if (forced && overrides)
		return loader_fail(
			ld, item,
			"\"material\" (one for the whole mesh) and \"materials\" (by the "
			"file's names) exclude each other");
	if (overrides && !json_is_object(overrides)) {
		struct path field = child_key(item, "materials");
		return loader_fail(ld, &field, "must be an object, got %s",
				   loader_type_name(overrides));
	}
	if ((forced && loader_read_material_ref(ld, item, obj, &material)) ||
	    read_placement(ld, item, obj, &pl) || read_missing_textures(ld, item, obj, &warn) ||
	    read_camera_request(ld, item, obj, &camera))
		return -1;
	path = mesh_path(ld, name);
	if (!path) {
		loader_write_err(ld, "%s: out of memory", ld->source);
		return -1;
	}
	if (is_gltf_1(path)) {
		ret = loader_fail(ld, &file,
				  "\"%s\" is a glTF 1.0 file, whose materials rtcl cannot read: "
				  "convert it to glTF 2.0 (e.g. \"npx gltf-pipeline -i %s -o "
				  "converted.gltf\", which upgrades 1.0 files) and render that",
				  one_line(name, text), text);
		free(path);
		return ret;
	}
	ret = mesh_import(path, &mesh, reason, sizeof(reason));
	if (loader_add_input(ld, path, "mesh file")) {
		if (ret == 0)
			mesh_data_free(&mesh);
		return -1;
	}
	if (ret)
		return loader_fail(ld, &file, "cannot read \"%s\": %s", one_line(name, text),
				   one_line(reason, why));
	if (add_mesh_inputs(ld, &mesh)) {
		ret = -1;
		goto out_free;
	}
	if (mesh.triangle_count == 0) {
		ret = loader_fail(ld, &file, "\"%s\" holds no triangles", one_line(name, text));
		goto out_free;
	}
	if (!forced) {
		map = malloc((mesh.material_count ? mesh.material_count : 1) * sizeof(*map));
		mt.scene_index = calloc(mesh.texture_count ? mesh.texture_count : 1, sizeof(int));
		if (!map || !mt.scene_index) {
			loader_write_err(ld, "%s: out of memory", ld->source);
			ret = -1;
			goto out_free;
		}
		mt.name = name;
		mt.mesh = &mesh;
		mt.warn = warn;
		/* The -v line of the mesh before those of its textures. */
		if ((ret = report_mesh(ld, item, name, &mesh, 0)) ||
		    (ret = map_file_materials(ld, item, name, &mesh, overrides, map, &mt)))
			goto out_free;
	} else if ((ret = report_mesh(ld, item, name, &mesh, 1))) {
		goto out_free;
	}
	/* A model rendered alone takes its file's first camera, where that is
	 * a perspective glTF camera; else its view is framed (scene_model.c). */
	if (ld->model && !camera && mesh.camera_count > 0 &&
	    mesh.cameras[0].kind == MESH_CAMERA_PERSPECTIVE)
		camera = json_true();
	ret = place_mesh(ld, &file, name, &mesh, &pl, material, map) ||
			      (camera && take_camera(ld, item, name, &mesh, &pl, camera)) ||
			      (ld->model && take_lights(ld, item, name, &mesh, &pl))
		      ? -1
		      : 0;
out_free:
	free(map);
	free(mt.scene_index);
	mesh_data_free(&mesh);
	return ret;
}

int loader_read_meshes(struct loader *ld, json_t *array)
{
	struct path p = child_key(&root_path, "meshes");

	for (size_t i = 0; i < json_array_size(array); i++) {
		struct path item = child_index(&p, i);

		if (read_mesh(ld, &item, json_array_get(array, i)))
			return -1;
	}
	return 0;
}

/* An inline triangle: "vertices" (three vec3) and "material". */
static int read_triangle(struct loader *ld, const struct path *item, json_t *obj)
{
	static const char *const keys[] = {"vertices", "material", NULL};
	struct path vertices = child_key(item, "vertices");
	struct scene *s = ld->scene;
	struct scene_triangle *tri;
	double n[3];
	json_t *v;

	if (loader_expect_object(ld, item, obj, keys) ||
	    loader_get_field(ld, item, obj, "vertices", REQUIRED, &v))
		return -1;
	if (!json_is_array(v))
		return loader_fail(ld, &vertices, "must be an array of 3 vertices, got %s",
				   loader_type_name(v));
	if (json_array_size(v) != 3)
		return loader_fail(ld, &vertices,
				   "must be an array of 3 vertices, got %zu element%s",
				   json_array_size(v), json_array_size(v) == 1 ? "" : "s");
	if (reserve(ld, item, 1))
		return -1;
	tri = &s->triangles[s->triangle_count];
	for (size_t k = 0; k < 3; k++) {
		struct path vertex = child_index(&vertices, k);

		if (loader_check_vec3(ld, &vertex, json_array_get(v, k), ANY, tri->v[k]))
			return -1;
	}
	if (!place_triangle_normal(tri->v, n)) {
		char a[100], b[100], c[100];

		return loader_fail(ld, &vertices,
				   "must span a triangle of non-zero area, got %s, %s, %s",
				   loader_fmt_vec3(tri->v[0], a), loader_fmt_vec3(tri->v[1], b),
				   loader_fmt_vec3(tri->v[2], c));
	}
	for (int k = 0; k < 3; k++)
		memcpy(tri->normal[k], n, sizeof(n));
	tri->smooth = 0;
	if (s->triangle_uvs)
		memset(&s->triangle_uvs[s->triangle_count], 0, sizeof(*s->triangle_uvs));
	if (loader_read_material_ref(ld, item, obj, &tri->material))
		return -1;
	s->triangle_count++;
	return 0;
}

int loader_read_triangles(struct loader *ld, json_t *array)
{
	struct path p = child_key(&root_path, "triangles");

	for (size_t i = 0; i < json_array_size(array); i++) {
		struct path item = child_index(&p, i);

		if (read_triangle(ld, &item, json_array_get(array, i)))
			return -1;
	}
	return 0;
}
