/* Between the parts of the scene loader (scene.c reads the sections of
 * SCENE.md, scene_check.c words the messages and checks fields and numbers,
 * scene_literal.c finds a number's text); not for the rest of the host. */
#ifndef RTCL_SCENE_LOADER_H
#define RTCL_SCENE_LOADER_H

#include <jansson.h>
#include <stddef.h>

#include "scene/scene.h"

/* The device computes in float, and squares and inverts what it is given (a
 * radius, the epsilon, an ior; the camera is normalised in double on the way):
 * a number outside these magnitudes would reach it as inf or 0 and render a
 * silently wrong picture. 0 itself is exact. */
#define SCENE_MIN_MAGNITUDE 1e-18
#define SCENE_MAX_MAGNITUDE 1e18

/* Where a value sits in the document: a chain of object keys and array
 * indices from the innermost value outwards. key == NULL means index. */
struct path {
	const struct path *parent;
	const char *key;
	size_t index;
};

/* The document itself; top-level keys hang directly below it. */
extern const struct path root_path;

struct loader {
	const char *source;
	char *err;
	size_t err_size;
	json_t *name_index; /* material name -> index into scene.materials */
	int default_used;   /* some object has no material */
	struct scene *scene;
	const json_t *doc;
	const char *text; /* the JSON text of doc, without a byte-order mark */
	size_t text_len;
	int version;		  /* the file's "version" */
	const char *base_dir;	  /* mesh files are relative to it; NULL: the working folder */
	size_t triangle_capacity; /* room in scene->triangles */
	size_t material_capacity; /* room in scene->materials */
	size_t camera_mesh;	  /* 1 + the index of the mesh entry whose file
				     gave the camera; 0: none did */
	int model;		  /* a model file rendered alone (scene_model.c): the
				     camera may be left out, and the mesh takes its
				     file's first camera where it is a usable one */
};

/* A key below `parent`; top-level keys get a root-less path. */
static inline struct path child_key(const struct path *parent, const char *key)
{
	struct path p = {parent == &root_path ? NULL : parent, key, 0};

	return p;
}

static inline struct path child_index(const struct path *parent, size_t index)
{
	struct path p = {parent, NULL, index};

	return p;
}

enum presence { OPTIONAL, REQUIRED };

enum range {
	DIRECTION,    /* any finite number: normalised in double on load */
	ANY,	      /* 0 or a magnitude in SCENE_MIN/MAX_MAGNITUDE */
	POSITIVE,     /* > 0 */
	NON_NEGATIVE, /* >= 0 */
	UNIT,	      /* 0 ... 1 */
	FOV,	      /* 0 < x < 180 */
};

#define WRITTEN_NUMBER_MAX 40

void loader_write_err(struct loader *ld, const char *fmt, ...);

/* Records path (malloc'd; the scene takes it, also on a failure) as a file
 * the scene was read from. Returns 0, or -1 with one message. */
int loader_add_input(struct loader *ld, char *path, const char *kind);

/* PATH as messages write it (spheres[3].radius) into out[size]. */
void loader_format_path(const struct path *p, char *out, size_t size);

/* "FILE: PATH: message"; always returns -1 so callers can `return loader_fail(...)`. */
int loader_fail(struct loader *ld, const struct path *p, const char *fmt, ...);

/* "FILE:LINE:COLUMN: message" for a JSON syntax error; returns -1. */
int loader_fail_json(struct loader *ld, const json_error_t *jerr);

/* "FILE: PATH: <before>"<quoted>"", with `quoted` escaped. */
int loader_fail_quoted(struct loader *ld, const struct path *p, const char *before,
		       const char *quoted);

/* Shortest %g form that reads back as the same double: 0.1, not
 * 0.10000000000000001, and 1.0000001, not 1. */
const char *loader_fmt_num(double v, char buf[32]);

const char *loader_type_name(const json_t *v);

/* Fails on the first key of `obj` not in the NULL-terminated `allowed`. */
int loader_check_keys(struct loader *ld, const struct path *p, json_t *obj,
		      const char *const *allowed);

int loader_expect_object(struct loader *ld, const struct path *p, json_t *v,
			 const char *const *allowed);

/* Looks up `key`; a missing optional field leaves *out at NULL and succeeds. */
int loader_get_field(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		     enum presence presence, json_t **out);

int loader_check_number(struct loader *ld, const struct path *p, json_t *v, enum range range,
			double *out);

int loader_read_number(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		       enum presence presence, enum range range, double *out);

/* A string that must be one of the NULL-terminated names: *out its index
 * (left as it is when an optional key is absent). A wrong one is refused
 * with the names and the nearest one ("must be "whitted" or "path", got
 * "paths"; did you mean "path"?"). */
int loader_read_choice(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		       enum presence presence, const char *const *names, int *out);

/* A JSON integer (not 2.0) in lo ... hi. */
int loader_check_integer(struct loader *ld, const struct path *p, json_t *v, json_int_t lo,
			 json_int_t hi, json_int_t *out);

int loader_read_int(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		    enum presence presence, int lo, int hi, int *out);

/* A vec3 (range ANY or DIRECTION) or a color (range NON_NEGATIVE), the value
 * v found at p. */
int loader_check_vec3(struct loader *ld, const struct path *p, json_t *v, enum range range,
		      double out[3]);

/* A vec3 (range ANY or DIRECTION) or a color (range NON_NEGATIVE). */
int loader_read_vec3(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		     enum presence presence, enum range range, double out[3]);

/* The view direction (look_at - eye) and up of cam, checked: NULL when
 * the camera is well defined, else what is wrong, with *field the field at
 * fault ("look_at" or "up"); buf holds the values quoted. */
const char *loader_camera_problem(const struct scene_camera *cam, const char **field,
				  char buf[200]);

/* Sets camera.focus_distance, where not given, to the distance from the
 * eye to look_at. */
void loader_default_focus(struct scene_camera *cam);

/* SCENE.md's material defaults, for fields left out and for objects without
 * a material. */
extern const struct scene_material loader_default_material;

/* The top-level "materials", each appended to scene->materials and named in
 * ld->name_index. */
int loader_read_named_materials(struct loader *ld, json_t *doc);

/* An object's "material": a name, an inline object (appended after the
 * named ones), or absent (-1 until the default material gets its index). */
int loader_read_material_ref(struct loader *ld, const struct path *p, json_t *obj, int *index);

/* A material value at field: a name or an inline object (appended). */
int loader_read_material_value(struct loader *ld, const struct path *field, json_t *v, int *index);

/* Appends m to scene->materials, growing it. Returns its index, or -1 with
 * one message. */
int loader_append_material(struct loader *ld, const struct scene_material *m);

struct mesh_material;
/* A mesh file's material (not a missing one) as a scene material, by the
 * rule of RENDERING.md "Materials from mesh files". Returns NULL, or the
 * name (as the file's format writes it) of the first number that is not
 * finite. */
const char *loader_material_from_mesh(const struct mesh_material *in, struct scene_material *m);

/* Version 2 (scene_mesh.c): the "meshes" and the inline "triangles",
 * appended to scene->triangles in that order. */
int loader_read_meshes(struct loader *ld, json_t *array);

/* Parses and validates `len` bytes of JSON into scene; `source` names them
 * in messages, mesh files are relative to base_dir (NULL: the working
 * folder); model: as struct loader's. Returns 0, or -1 with one message in
 * err and nothing held. */
int loader_load_buffer(struct scene *scene, const char *json, size_t len, const char *source,
		       const char *base_dir, int model, char *err, size_t err_size);
int loader_read_triangles(struct loader *ld, json_t *array);

const char *loader_fmt_vec3(const double v[3], char buf[100]);

/* Scales v so its largest part has magnitude 1, so that squaring it can
 * neither overflow nor underflow. Returns 0 for the zero vector. */
int loader_scale_to_unit_max(const double v[3], double out[3]);

double loader_length3(const double v[3]);

/* The number `v` as written in the file ("a 400-character number" if too
 * long to quote) if that text is nonzero but jansson read it as 0 or a
 * denormal (1e-400, 1e-320), else NULL. Looked up only for the one number
 * that fails a check, so a scene costs at most one walk. */
const char *loader_underflow_text(const struct loader *ld, const json_t *v,
				  char buf[WRITTEN_NUMBER_MAX]);

#endif
