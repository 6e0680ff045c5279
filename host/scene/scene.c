/* Scene loader: JSON (jansson) -> struct scene, validated as SCENE.md asks.
 *
 * Every check reports the first problem it finds as one line,
 * "FILE: PATH: what is wrong" or, for JSON syntax, "FILE:LINE:COLUMN: ...".
 * Within an object, unknown keys are reported before missing or bad values,
 * so a typo ("radus") is named instead of the field it hides ("radius").
 *
 * This file reads the sections of SCENE.md in order; scene_check.c words the
 * messages and checks each field, number and vector; scene_literal.c finds a
 * number's text to name one that underflows.
 */
#define _POSIX_C_SOURCE 200809L

#include "scene/scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "base/files.h"
#include "base/quote.h"
#include "scene/scene_loader.h"
#include "scene/hdr_read.h"

/* Larger documents are refused before parsing: jansson needs many times the
 * text size in memory, and no sensible scene comes near this. */
#define SCENE_MAX_BYTES ((size_t)256 << 20)

/* camera.up counts as parallel to the view direction when the sine of the
 * angle between them is below this. */
#define SCENE_PARALLEL_SINE 1e-9

/* Fetches an optional top-level array; a missing one counts as empty. */
static int get_array(struct loader *ld, json_t *doc, const char *key, json_t **out, size_t *count)
{
	struct path field = child_key(&root_path, key);

	*out = json_object_get(doc, key);
	*count = 0;
	if (!*out)
		return 0;
	if (!json_is_array(*out))
		return loader_fail(ld, &field, "must be an array, got %s", loader_type_name(*out));
	*count = json_array_size(*out);
	/* Cannot happen below SCENE_MAX_BYTES, but the counts are ints. */
	if (*count > INT_MAX / 4)
		return loader_fail(ld, &field, "has %zu elements, more than the limit of %d",
				   *count, INT_MAX / 4);
	return 0;
}

static int read_header(struct loader *ld, json_t *doc)
{
	struct path format = child_key(&root_path, "format");
	struct path version = child_key(&root_path, "version");
	json_t *v;
	json_int_t n;

	if (!json_is_object(doc))
		return loader_fail(ld, &root_path, "must be an object, got %s",
				   loader_type_name(doc));

	if (loader_get_field(ld, &root_path, doc, "format", REQUIRED, &v))
		return -1;
	if (!json_is_string(v))
		return loader_fail(ld, &format, "must be the string \"rtcl-scene\", got %s",
				   loader_type_name(v));
	if (strcmp(json_string_value(v), "rtcl-scene") != 0)
		return loader_fail_quoted(ld, &format, "must be \"rtcl-scene\", got ",
					  json_string_value(v));

	/* Before unknown keys: a newer file may well have fields we lack. */
	if (loader_get_field(ld, &root_path, doc, "version", REQUIRED, &v))
		return -1;
	if (loader_check_integer(ld, &version, v, LLONG_MIN, LLONG_MAX, &n))
		return -1;
	if (n > 2)
		return loader_fail(ld, &version,
				   "version %" JSON_INTEGER_FORMAT
				   " is not supported (this rtcl reads versions 1 and 2)",
				   n);
	if (n < 1)
		return loader_fail(ld, &version, "must be 1 or 2, got %" JSON_INTEGER_FORMAT, n);
	ld->version = (int)n;
	/* Before unknown keys: a version 1 file with meshes gets told why. */
	for (int i = 0; i < 2 && n == 1; i++) {
		const char *key = i == 0 ? "meshes" : "triangles";
		struct path field = child_key(&root_path, key);

		if (json_object_get(doc, key))
			return loader_fail(ld, &field,
					   "needs \"version\": 2 (the file says \"version\": 1)");
	}
	return 0;
}

/* The view direction (look_at - eye) and up of cam, checked: NULL when
 * the camera is well defined, else what is wrong, with *field the field at
 * fault ("look_at" or "up"); buf holds the values quoted. */
const char *loader_camera_problem(const struct scene_camera *cam, const char **field,
				  char buf[200])
{
	double dir[3], d[3], u[3], cross[3];
	char vec[100];

	/* Halved first so that the difference cannot overflow. */
	for (int i = 0; i < 3; i++)
		dir[i] = cam->look_at[i] / 2 - cam->eye[i] / 2;
	*field = "look_at";
	if (!loader_scale_to_unit_max(dir, d)) {
		snprintf(buf, 200, "must differ from camera.eye, both are %s",
			 loader_fmt_vec3(cam->eye, vec));
		return buf;
	}
	*field = "up";
	if (!loader_scale_to_unit_max(cam->up, u))
		return "must be non-zero";
	cross[0] = u[1] * d[2] - u[2] * d[1];
	cross[1] = u[2] * d[0] - u[0] * d[2];
	cross[2] = u[0] * d[1] - u[1] * d[0];
	if (loader_length3(cross) <= SCENE_PARALLEL_SINE * loader_length3(u) * loader_length3(d)) {
		snprintf(buf, 200, "must not be parallel to look_at - eye, got %s",
			 loader_fmt_vec3(cam->up, vec));
		return buf;
	}
	return NULL;
}

/* camera.focus_distance when not given: the distance from the eye to
 * look_at (halved first, so that the difference cannot overflow). */
void loader_default_focus(struct scene_camera *cam)
{
	double half[3];

	if (cam->focus_given)
		return;
	for (int i = 0; i < 3; i++)
		half[i] = cam->look_at[i] / 2 - cam->eye[i] / 2;
	cam->focus_distance = 2 * loader_length3(half);
}

/* The first mesh entry whose "camera" is there and not false, or -1;
 * *valid: whether it is true or a name. Another value (null, a number) is
 * that entry's error (scene_mesh.c), never a request for the file's camera
 * (issue 39: null was taken for true). */
static long camera_mesh_entry(json_t *doc, int *valid)
{
	json_t *meshes = json_object_get(doc, "meshes");

	for (size_t i = 0; i < json_array_size(meshes); i++) {
		json_t *v = json_object_get(json_array_get(meshes, i), "camera");
		if (v && !json_is_false(v)) {
			*valid = json_is_true(v) || json_is_string(v);
			return (long)i;
		}
	}
	return -1;
}

/* The camera's lens where the view comes from a mesh file's camera
 * (scene_mesh.c sets the view): "camera" may be left out, and gives only
 * "aperture" and "focus_distance". */
static int read_lens_only(struct loader *ld, const struct path *p, json_t *obj, long mesh)
{
	static const char *const view[] = {"eye", "look_at", "up", "fov", NULL};
	struct scene_camera *cam = &ld->scene->camera;

	if (!obj)
		return 0;
	for (int i = 0; view[i]; i++)
		if (json_object_get(obj, view[i])) {
			struct path at = child_key(p, view[i]);
			return loader_fail(ld, &at,
					   "the view comes from the camera of meshes[%ld]'s file; "
					   "the scene's \"camera\" may give only \"aperture\" and "
					   "\"focus_distance\" then",
					   mesh);
		}
	if (loader_read_number(ld, p, obj, "aperture", OPTIONAL, NON_NEGATIVE, &cam->aperture) ||
	    loader_read_number(ld, p, obj, "focus_distance", OPTIONAL, POSITIVE,
			       &cam->focus_distance))
		return -1;
	cam->focus_given = json_object_get(obj, "focus_distance") != NULL;
	return 0;
}

static int read_camera(struct loader *ld, json_t *doc)
{
	static const char *const keys[] = {"eye", "look_at",  "up", "fov", "aperture",
					   "focus_distance", NULL};
	struct path p = child_key(&root_path, "camera");
	struct scene_camera *cam = &ld->scene->camera;
	int valid = 0;
	long from_mesh = camera_mesh_entry(doc, &valid);
	const char *field, *problem;
	char buf[200];
	json_t *obj;

	cam->up[0] = 0, cam->up[1] = 1, cam->up[2] = 0;
	cam->fov = 45;
	cam->aperture = 0;
	cam->focus_distance = 0;
	if (from_mesh >= 0 && !valid)
		return 0; /* meshes[from_mesh].camera is refused with its own words */
	/* A model's view is its file's camera or framed from its bounds
	 * (scene_model.c). */
	if (ld->model && !json_object_get(doc, "camera"))
		return 0;
	if (loader_get_field(ld, &root_path, doc, "camera", from_mesh >= 0 ? OPTIONAL : REQUIRED,
			     &obj) ||
	    (obj && loader_expect_object(ld, &p, obj, keys)))
		return -1;
	if (from_mesh >= 0)
		return read_lens_only(ld, &p, obj, from_mesh);
	if (loader_read_vec3(ld, &p, obj, "eye", REQUIRED, ANY, cam->eye) ||
	    loader_read_vec3(ld, &p, obj, "look_at", REQUIRED, ANY, cam->look_at) ||
	    loader_read_vec3(ld, &p, obj, "up", OPTIONAL, ANY, cam->up) ||
	    loader_read_number(ld, &p, obj, "fov", OPTIONAL, FOV, &cam->fov) ||
	    loader_read_number(ld, &p, obj, "aperture", OPTIONAL, NON_NEGATIVE, &cam->aperture) ||
	    loader_read_number(ld, &p, obj, "focus_distance", OPTIONAL, POSITIVE,
			       &cam->focus_distance))
		return -1;
	cam->focus_given = json_object_get(obj, "focus_distance") != NULL;

	problem = loader_camera_problem(cam, &field, buf);
	if (problem) {
		struct path at = child_key(&p, field);
		return loader_fail(ld, &at, "%s", problem);
	}
	loader_default_focus(cam);
	return 0;
}

int scene_override_camera(struct scene *scene, const struct camera_override *o, char *err,
			  size_t err_size)
{
	struct scene_camera *cam = &scene->camera;
	const char *field, *problem;
	char buf[200];

	if (o->eye_given)
		memcpy(cam->eye, o->eye, sizeof(cam->eye));
	if (o->look_at_given)
		memcpy(cam->look_at, o->look_at, sizeof(cam->look_at));
	if (o->fov_given)
		cam->fov = o->fov;
	if (o->aperture_given)
		cam->aperture = o->aperture;
	if (o->focus_given) {
		cam->focus_distance = o->focus_distance;
		cam->focus_given = 1;
	}
	problem = loader_camera_problem(cam, &field, buf);
	if (problem) {
		snprintf(err, err_size, "%s%s%s: camera.%s %s", o->eye_given ? "--eye" : "",
			 o->eye_given && o->look_at_given ? " and " : "",
			 o->look_at_given ? "--look-at" : "", field, problem);
		return -1;
	}
	loader_default_focus(cam);
	return 0;
}

/* "environment" (SCENE.md): the map's file joined to the scene's folder,
 * its scale and rotation; read by the path integrator. */
static int read_environment(struct loader *ld, json_t *doc)
{
	static const char *const keys[] = {"file", "scale", "rotate", NULL};
	struct path p = child_key(&root_path, "environment");
	struct scene_environment *env = &ld->scene->environment;
	json_t *obj, *file;

	env->scale = 1;
	env->rotate = 0;
	if (loader_get_field(ld, &root_path, doc, "environment", OPTIONAL, &obj))
		return -1;
	if (!obj)
		return 0;
	if (loader_expect_object(ld, &p, obj, keys) ||
	    loader_read_number(ld, &p, obj, "scale", OPTIONAL, NON_NEGATIVE, &env->scale) ||
	    loader_read_number(ld, &p, obj, "rotate", OPTIONAL, ANY, &env->rotate))
		return -1;
	file = json_object_get(obj, "file");
	if (!file)
		return loader_fail(ld, &p, "needs \"file\"");
	if (!json_is_string(file) || json_string_value(file)[0] == '\0') {
		struct path field = child_key(&p, "file");
		return loader_fail(ld, &field, "must be a file name, got %s",
				   json_is_string(file) ? "\"\"" : loader_type_name(file));
	}
	const char *name = json_string_value(file);
	const char *dir = name[0] == '/' || !ld->base_dir ? "" : ld->base_dir;
	size_t size = strlen(dir) + strlen(name) + 1;
	env->file = malloc(size);
	if (!env->file) {
		loader_write_err(ld, "%s: out of memory", ld->source);
		return -1;
	}
	snprintf(env->file, size, "%s%s", dir, name);

	struct hdr_image image;
	struct path field = child_key(&p, "file");
	char reason[512];
	if (hdr_read(env->file, name, &image, reason, sizeof(reason)))
		return loader_fail(ld, &field, "%s", reason);
	env->width = image.width;
	env->height = image.height;
	env->rgb = image.rgb;
	char *input = strdup(env->file);
	return input ? loader_add_input(ld, input, "environment map") : -1;
}

static int read_image_and_globals(struct loader *ld, json_t *doc)
{
	static const char *const image_keys[] = {"width", "height", "samples", NULL};
	struct path image = child_key(&root_path, "image");
	struct scene *s = ld->scene;
	json_t *obj;

	s->width = 640;
	s->height = 480;
	s->samples = 1;
	s->background[0] = s->background[1] = s->background[2] = 0;
	s->ambient[0] = s->ambient[1] = s->ambient[2] = 0.1;
	s->max_depth = 5;
	s->epsilon = 1e-4;

	if (loader_get_field(ld, &root_path, doc, "image", OPTIONAL, &obj))
		return -1;
	if (obj && (loader_expect_object(ld, &image, obj, image_keys) ||
		    loader_read_int(ld, &image, obj, "width", OPTIONAL, 1, SCENE_MAX_IMAGE_SIDE,
				    &s->width) ||
		    loader_read_int(ld, &image, obj, "height", OPTIONAL, 1, SCENE_MAX_IMAGE_SIDE,
				    &s->height) ||
		    loader_read_int(ld, &image, obj, "samples", OPTIONAL, 1, SCENE_MAX_SAMPLES,
				    &s->samples)))
		return -1;
	static const char *const integrators[] = {"whitted", "path", NULL};

	s->integrator = SCENE_INTEGRATOR_WHITTED;
	s->ambient_given = json_object_get(doc, "ambient") != NULL;
	if (loader_read_choice(ld, &root_path, doc, "integrator", OPTIONAL, integrators,
			       &s->integrator) ||
	    read_environment(ld, doc) || read_camera(ld, doc) ||
	    loader_read_vec3(ld, &root_path, doc, "background", OPTIONAL, NON_NEGATIVE,
			     s->background) ||
	    loader_read_vec3(ld, &root_path, doc, "ambient", OPTIONAL, NON_NEGATIVE, s->ambient) ||
	    loader_read_int(ld, &root_path, doc, "max_depth", OPTIONAL, 0, SCENE_MAX_DEPTH,
			    &s->max_depth) ||
	    loader_read_number(ld, &root_path, doc, "epsilon", OPTIONAL, POSITIVE, &s->epsilon))
		return -1;
	return 0;
}

/* A directional light's direction (normalised; the way its light travels)
 * and angle, or a point or sphere light's position and radius: the one pair
 * the light gives, each field refused on a light of the other kind. */
static int read_light_kind(struct loader *ld, const struct path *item, json_t *obj,
			   struct scene_light *l)
{
	int has_position = json_object_get(obj, "position") != NULL;
	int has_direction = json_object_get(obj, "direction") != NULL;
	struct path radius = child_key(item, "radius"), angle = child_key(item, "angle");
	struct path direction = child_key(item, "direction");
	double scaled[3];

	if (has_position == has_direction)
		return loader_fail(ld, item,
				   has_position ? "has both \"position\" and \"direction\": give one"
						: "needs \"position\" (a point or sphere light) or "
						  "\"direction\" (a directional light)");
	l->directional = has_direction;
	if (has_position) {
		if (json_object_get(obj, "angle"))
			return loader_fail(ld, &angle, "a point or sphere light has no angle; "
						       "give its \"radius\"");
		return loader_read_vec3(ld, item, obj, "position", REQUIRED, ANY, l->position) ||
		       loader_read_number(ld, item, obj, "radius", OPTIONAL, NON_NEGATIVE,
					  &l->radius);
	}
	if (json_object_get(obj, "radius"))
		return loader_fail(ld, &radius,
				   "a directional light has no radius; give its \"angle\"");
	if (loader_read_vec3(ld, item, obj, "direction", REQUIRED, DIRECTION, l->direction) ||
	    loader_read_number(ld, item, obj, "angle", OPTIONAL, NON_NEGATIVE, &l->angle))
		return -1;
	if (!loader_scale_to_unit_max(l->direction, scaled))
		return loader_fail(ld, &direction, "must be non-zero");
	for (int i = 0; i < 3; i++)
		l->direction[i] = scaled[i] / loader_length3(scaled);
	if (l->angle >= 90) {
		char buf[32];
		return loader_fail(ld, &angle, "must be >= 0 and < 90, got %s",
				   loader_fmt_num(l->angle, buf));
	}
	return 0;
}

static int read_lights(struct loader *ld, json_t *array)
{
	static const char *const keys[] = {"position", "direction", "color", "radius", "angle",
					   NULL};
	struct path p = child_key(&root_path, "lights");
	struct scene *s = ld->scene;

	for (size_t i = 0; i < json_array_size(array); i++) {
		struct path item = child_index(&p, i);
		struct scene_light *l = &s->lights[i];
		json_t *obj = json_array_get(array, i);

		l->color[0] = l->color[1] = l->color[2] = 1;
		if (loader_expect_object(ld, &item, obj, keys) ||
		    read_light_kind(ld, &item, obj, l) ||
		    loader_read_vec3(ld, &item, obj, "color", OPTIONAL, NON_NEGATIVE, l->color))
			return -1;
		s->light_count++;
	}
	return 0;
}

static int read_spheres(struct loader *ld, json_t *array)
{
	static const char *const keys[] = {"center", "radius", "material", NULL};
	struct path p = child_key(&root_path, "spheres");
	struct scene *s = ld->scene;

	for (size_t i = 0; i < json_array_size(array); i++) {
		struct path item = child_index(&p, i);
		struct scene_sphere *sp = &s->spheres[i];
		json_t *obj = json_array_get(array, i);

		if (loader_expect_object(ld, &item, obj, keys) ||
		    loader_read_vec3(ld, &item, obj, "center", REQUIRED, ANY, sp->center) ||
		    loader_read_number(ld, &item, obj, "radius", REQUIRED, POSITIVE, &sp->radius) ||
		    loader_read_material_ref(ld, &item, obj, &sp->material))
			return -1;
		s->sphere_count++;
	}
	return 0;
}

static int read_checker(struct loader *ld, const struct path *plane, json_t *obj,
			struct scene_plane *pl)
{
	static const char *const keys[] = {"size", "color", NULL};
	struct path p = child_key(plane, "checker");
	json_t *checker;

	if (loader_get_field(ld, plane, obj, "checker", OPTIONAL, &checker))
		return -1;
	if (!checker)
		return 0;
	if (loader_expect_object(ld, &p, checker, keys) ||
	    loader_read_number(ld, &p, checker, "size", REQUIRED, POSITIVE, &pl->checker_size) ||
	    loader_read_vec3(ld, &p, checker, "color", REQUIRED, NON_NEGATIVE, pl->checker_color))
		return -1;
	pl->has_checker = 1;
	return 0;
}

static int read_planes(struct loader *ld, json_t *array)
{
	static const char *const keys[] = {"point", "normal", "material", "checker", NULL};
	struct path p = child_key(&root_path, "planes");
	struct scene *s = ld->scene;

	for (size_t i = 0; i < json_array_size(array); i++) {
		struct path item = child_index(&p, i);
		struct path normal = child_key(&item, "normal");
		struct scene_plane *pl = &s->planes[i];
		json_t *obj = json_array_get(array, i);
		double n[3], len;

		if (loader_expect_object(ld, &item, obj, keys) ||
		    loader_read_vec3(ld, &item, obj, "point", REQUIRED, ANY, pl->point) ||
		    loader_read_vec3(ld, &item, obj, "normal", REQUIRED, DIRECTION, pl->normal))
			return -1;
		if (!loader_scale_to_unit_max(pl->normal, n))
			return loader_fail(ld, &normal, "must be non-zero");
		len = loader_length3(n);
		for (int k = 0; k < 3; k++)
			pl->normal[k] = n[k] / len;
		if (loader_read_material_ref(ld, &item, obj, &pl->material) ||
		    read_checker(ld, &item, obj, pl))
			return -1;
		s->plane_count++;
	}
	return 0;
}

static const char *const top_level_keys[] = {
	"format",  "version",	"image",   "camera",	"background",
	"ambient", "max_depth", "epsilon", "materials", "lights",
	"spheres", "planes",	"meshes",  "triangles", "integrator",
	"environment", NULL,
};

/* Fills ld->scene from the parsed document; on failure the caller frees
 * whatever was allocated. */
static int read_scene(struct loader *ld, json_t *doc)
{
	struct scene *s = ld->scene;
	json_t *lights, *spheres, *planes, *meshes, *triangles, *named;
	size_t light_count, sphere_count, plane_count, mesh_count, triangle_count;
	size_t material_capacity;

	if (read_header(ld, doc) || loader_check_keys(ld, &root_path, doc, top_level_keys) ||
	    read_image_and_globals(ld, doc) ||
	    get_array(ld, doc, "lights", &lights, &light_count) ||
	    get_array(ld, doc, "spheres", &spheres, &sphere_count) ||
	    get_array(ld, doc, "planes", &planes, &plane_count) ||
	    get_array(ld, doc, "meshes", &meshes, &mesh_count) ||
	    get_array(ld, doc, "triangles", &triangles, &triangle_count))
		return -1;

	/* Upper bound: every object brings an inline material, plus the default. */
	named = json_object_get(doc, "materials");
	material_capacity = (json_is_object(named) ? json_object_size(named) : 0) + sphere_count +
			    plane_count + mesh_count + triangle_count + 1;
	s->materials = calloc(material_capacity, sizeof(*s->materials));
	ld->material_capacity = material_capacity;
	s->lights = calloc(light_count ? light_count : 1, sizeof(*s->lights));
	s->spheres = calloc(sphere_count ? sphere_count : 1, sizeof(*s->spheres));
	s->planes = calloc(plane_count ? plane_count : 1, sizeof(*s->planes));
	ld->name_index = json_object();
	if (!s->materials || !s->lights || !s->spheres || !s->planes || !ld->name_index) {
		loader_write_err(ld, "%s: out of memory", ld->source);
		return -1;
	}

	if (loader_read_named_materials(ld, doc) || read_lights(ld, lights) ||
	    read_spheres(ld, spheres) || read_planes(ld, planes) ||
	    loader_read_meshes(ld, meshes) || loader_read_triangles(ld, triangles))
		return -1;

	if (ld->default_used) {
		int index = loader_append_material(ld, &loader_default_material);

		if (index < 0)
			return -1;
		for (int i = 0; i < s->sphere_count; i++)
			if (s->spheres[i].material < 0)
				s->spheres[i].material = index;
		for (int i = 0; i < s->plane_count; i++)
			if (s->planes[i].material < 0)
				s->planes[i].material = index;
		for (int i = 0; i < s->triangle_count; i++)
			if (s->triangles[i].material < 0)
				s->triangles[i].material = index;
	}
	return 0;
}

/* The UTF-8 encoding of U+FEFF, which some editors put at the start of a
 * file; SCENE.md allows it there. */
static const char utf8_bom[] = "\xef\xbb\xbf";

int loader_load_buffer(struct scene *scene, const char *json, size_t len, const char *source,
		       const char *base_dir, int model, char *err, size_t err_size)
{
	/* Messages show the name with its control bytes escaped (quote.h). */
	char *shown = strdup(quote_text(source));
	struct loader ld = {.source = shown ? shown : "(scene)",
			    .err = err,
			    .err_size = err_size,
			    .scene = scene,
			    .base_dir = base_dir,
			    .model = model};
	json_error_t jerr;
	json_t *doc;
	int ret;

	memset(scene, 0, sizeof(*scene));
	if (len > SCENE_MAX_BYTES) {
		loader_write_err(&ld, "%s: scene is %zu bytes, more than the limit of %zu bytes",
				 ld.source, len, SCENE_MAX_BYTES);
		free(shown);
		return -1;
	}
	if (len >= 3 && memcmp(json, utf8_bom, 3) == 0) {
		json += 3;
		len -= 3;
	}
	doc = json_loadb(json, len, JSON_REJECT_DUPLICATES, &jerr);
	if (!doc) {
		loader_fail_json(&ld, &jerr);
		free(shown);
		return -1;
	}

	scene->source = strdup(source);
	if (!scene->source || !shown) {
		loader_write_err(&ld, "%s: out of memory", ld.source);
		ret = -1;
	} else {
		ld.doc = doc;
		ld.text = json;
		ld.text_len = len;
		ret = read_scene(&ld, doc);
	}
	json_decref(ld.name_index);
	json_decref(doc);
	free(shown);
	if (ret)
		scene_free(scene);
	return ret;
}

int scene_load_file(struct scene *scene, const char *path, char *err, size_t err_size)
{
	const char *slash = strrchr(path, '/');
	char *dir = strndup(path, slash ? (size_t)(slash - path) + 1 : 0);
	size_t len;
	char *buf;
	int ret;

	memset(scene, 0, sizeof(*scene));
	if (!dir) {
		snprintf(err, err_size, "%s: out of memory", quote_text(path));
		return -1;
	}
	ret = files_read(path, "scene", SCENE_MAX_BYTES, &buf, &len, err, err_size);
	if (ret == 0) {
		/* Mesh files are found relative to the scene file's folder. */
		ret = loader_load_buffer(scene, buf, len, path, dir, 0, err, err_size);
		free(buf);
	}
	if (ret == 0) {
		struct loader ld = {
			.source = path, .err = err, .err_size = err_size, .scene = scene};
		char *copy = strdup(path);

		if (!copy)
			loader_write_err(&ld, "%s: out of memory", path);
		if (!copy || loader_add_input(&ld, copy, "scene file")) {
			scene_free(scene);
			ret = -1;
		}
	}
	free(dir);
	return ret;
}

int scene_load_string(struct scene *scene, const char *json, const char *name, char *err,
		      size_t err_size)
{
	if (!name)
		name = "(string)";
	if (!json) {
		struct loader ld = {.source = name, .err = err, .err_size = err_size};

		memset(scene, 0, sizeof(*scene));
		loader_write_err(&ld, "%s: no scene text", quote_text(name));
		return -1;
	}
	return loader_load_buffer(scene, json, strlen(json), name, NULL, 0, err, err_size);
}

void scene_free(struct scene *scene)
{
	free(scene->source);
	free(scene->environment.file);
	free(scene->environment.rgb);
	for (int i = 0; i < scene->input_count; i++)
		free(scene->inputs[i].path);
	free(scene->inputs);
	for (int i = 0; i < scene->mesh_report_count; i++)
		free(scene->mesh_reports[i]);
	free(scene->mesh_reports);
	for (int i = 0; i < scene->warning_count; i++)
		free(scene->warnings[i]);
	free(scene->warnings);
	for (int i = 0; i < scene->texture_count; i++) {
		free(scene->textures[i].name);
		free(scene->textures[i].texels);
	}
	free(scene->textures);
	free(scene->triangle_uvs);
	free(scene->materials);
	free(scene->spheres);
	free(scene->planes);
	free(scene->lights);
	free(scene->triangles);
	memset(scene, 0, sizeof(*scene));
}

/* Widens lo..hi to hold p ± r. */
static void grow_box(double lo[3], double hi[3], const double p[3], double r)
{
	for (int a = 0; a < 3; a++) {
		lo[a] = p[a] - r < lo[a] ? p[a] - r : lo[a];
		hi[a] = p[a] + r > hi[a] ? p[a] + r : hi[a];
	}
}

int scene_bounds(const struct scene *scene, double lo[3], double hi[3])
{
	double box_lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL};
	double box_hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};

	for (int i = 0; i < scene->sphere_count; i++)
		grow_box(box_lo, box_hi, scene->spheres[i].center, scene->spheres[i].radius);
	for (int i = 0; i < scene->triangle_count; i++)
		for (int k = 0; k < 3; k++)
			grow_box(box_lo, box_hi, scene->triangles[i].v[k], 0);
	if (scene->sphere_count + scene->triangle_count == 0)
		return 0;
	memcpy(lo, box_lo, sizeof(box_lo));
	memcpy(hi, box_hi, sizeof(box_hi));
	return scene->sphere_count + scene->triangle_count;
}

/* FNV-1a over n bytes. */
static void digest_bytes(unsigned long long *h, const void *data, size_t n)
{
	const unsigned char *b = data;

	for (size_t i = 0; i < n; i++) {
		*h ^= b[i];
		*h *= 0x100000001b3ULL;
	}
}

static void digest_doubles(unsigned long long *h, const double *v, size_t n)
{
	digest_bytes(h, v, n * sizeof(double));
}

static void digest_int(unsigned long long *h, long long v)
{
	digest_bytes(h, &v, sizeof(v));
}

unsigned long long scene_digest(const struct scene *scene)
{
	unsigned long long h = 0xcbf29ce484222325ULL;
	const struct scene_camera *c = &scene->camera;

	digest_int(&h, scene->width);
	digest_int(&h, scene->height);
	digest_int(&h, scene->samples);
	digest_int(&h, scene->max_depth);
	digest_doubles(&h, c->eye, 3);
	digest_doubles(&h, c->look_at, 3);
	digest_doubles(&h, c->up, 3);
	digest_doubles(&h, &c->fov, 1);
	digest_doubles(&h, &c->aperture, 1);
	digest_doubles(&h, &c->focus_distance, 1);
	digest_doubles(&h, scene->background, 3);
	digest_doubles(&h, scene->ambient, 3);
	digest_doubles(&h, &scene->epsilon, 1);
	digest_int(&h, scene->integrator);
	digest_int(&h, scene->environment.file != NULL);
	if (scene->environment.file) {
		digest_bytes(&h, scene->environment.file, strlen(scene->environment.file));
		digest_doubles(&h, &scene->environment.scale, 1);
		digest_doubles(&h, &scene->environment.rotate, 1);
		digest_bytes(&h, scene->environment.rgb, (size_t)scene->environment.width *
								 scene->environment.height * 3 *
								 sizeof(float));
	}
	/* Field by field: the structs' padding holds whatever it held. */
	digest_int(&h, scene->material_count);
	for (int i = 0; i < scene->material_count; i++) {
		const struct scene_material *m = &scene->materials[i];
		double fields[] = {m->ambient, m->diffuse,  m->specular, m->shininess,
				   m->reflect, m->transmit, m->ior};
		digest_doubles(&h, m->color, 3);
		digest_doubles(&h, fields, sizeof(fields) / sizeof(fields[0]));
		digest_int(&h, m->fresnel);
		digest_int(&h, m->texture);
		digest_int(&h, m->alpha_texture);
		digest_doubles(&h, &m->alpha_cutoff, 1);
		digest_doubles(&h, &m->alpha_scale, 1);
		double bsdf[] = {m->bsdf.roughness, m->bsdf.ior, m->bsdf.metallic,
				 m->bsdf.transmission};
		digest_int(&h, m->bsdf.type);
		digest_doubles(&h, m->bsdf.color, 3);
		digest_doubles(&h, bsdf, sizeof(bsdf) / sizeof(bsdf[0]));
		digest_doubles(&h, m->emission, 3);
	}
	digest_int(&h, scene->texture_count);
	for (int i = 0; i < scene->texture_count; i++) {
		const struct scene_texture *t = &scene->textures[i];
		digest_int(&h, t->width);
		digest_int(&h, t->height);
		digest_int(&h, t->is_float);
		digest_int(&h, t->wrap_s);
		digest_int(&h, t->wrap_t);
		digest_bytes(&h, t->texels, t->bytes);
	}
	digest_int(&h, scene->triangle_uvs != NULL);
	for (int i = 0; scene->triangle_uvs && i < scene->triangle_count; i++)
		digest_doubles(&h, &scene->triangle_uvs[i].uv[0][0], 6);
	digest_int(&h, scene->sphere_count);
	for (int i = 0; i < scene->sphere_count; i++) {
		digest_doubles(&h, scene->spheres[i].center, 3);
		digest_doubles(&h, &scene->spheres[i].radius, 1);
		digest_int(&h, scene->spheres[i].material);
	}
	digest_int(&h, scene->plane_count);
	for (int i = 0; i < scene->plane_count; i++) {
		const struct scene_plane *p = &scene->planes[i];
		digest_doubles(&h, p->point, 3);
		digest_doubles(&h, p->normal, 3);
		digest_int(&h, p->material);
		digest_int(&h, p->has_checker);
		digest_doubles(&h, &p->checker_size, 1);
		digest_doubles(&h, p->checker_color, 3);
	}
	digest_int(&h, scene->light_count);
	for (int i = 0; i < scene->light_count; i++) {
		const struct scene_light *l = &scene->lights[i];
		digest_doubles(&h, l->position, 3);
		digest_doubles(&h, l->color, 3);
		digest_doubles(&h, &l->radius, 1);
		digest_int(&h, l->directional);
		digest_doubles(&h, l->direction, 3);
		digest_doubles(&h, &l->angle, 1);
	}
	digest_int(&h, scene->triangle_count);
	for (int i = 0; i < scene->triangle_count; i++) {
		const struct scene_triangle *t = &scene->triangles[i];
		digest_doubles(&h, &t->v[0][0], 9);
		digest_doubles(&h, &t->normal[0][0], 9);
		digest_int(&h, t->material);
		digest_int(&h, t->smooth);
	}
	return h;
}
