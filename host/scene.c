/* Scene loader: JSON (jansson) -> struct scene, validated as SCENE.md asks.
 *
 * Every check reports the first problem it finds as one line,
 * "FILE: PATH: what is wrong" or, for JSON syntax, "FILE:LINE:COLUMN: ...".
 * Within an object, unknown keys are reported before missing or bad values,
 * so a typo ("radus") is named instead of the field it hides ("radius").
 */
#define _POSIX_C_SOURCE 200809L

#include "scene.h"
#include "files.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <jansson.h>

/* Larger documents are refused before parsing: jansson needs many times the
 * text size in memory, and no sensible scene comes near this. */
#define SCENE_MAX_BYTES ((size_t)256 << 20)

/* The device computes in float, and squares and inverts what it is given (a
 * radius, the epsilon, an ior; the camera is normalised in double on the way):
 * a number outside these magnitudes would reach it as inf or 0 and render a
 * silently wrong picture. 0 itself is exact. */
#define SCENE_MIN_MAGNITUDE 1e-18
#define SCENE_MAX_MAGNITUDE 1e18

/* camera.up counts as parallel to the view direction when the sine of the
 * angle between them is below this. */
#define SCENE_PARALLEL_SINE 1e-9

/* A growing string that never overflows; `len` keeps counting past `size`
 * so truncation is harmless. */
struct sbuf {
	char *buf;
	size_t size;
	size_t len;
};

static void sb_vprintf(struct sbuf *sb, const char *fmt, va_list ap)
{
	char *at = sb->len < sb->size ? sb->buf + sb->len : NULL;
	size_t room = sb->len < sb->size ? sb->size - sb->len : 0;
	int n = vsnprintf(at, room, fmt, ap);

	if (n > 0)
		sb->len += (size_t)n;
}

static void sb_printf(struct sbuf *sb, const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	sb_vprintf(sb, fmt, ap);
	va_end(ap);
}

/* Appends `s` with control bytes (and, if `quoted`, quotes and backslashes)
 * escaped, so that text from the file can never split the one-line message. */
/* Names and keys longer than this are cut in messages ("abc..."), so that
 * one message stays one readable line whatever the file holds. */
#define MESSAGE_NAME_MAX 64

static void sb_escaped(struct sbuf *sb, const char *s, int quoted)
{
	const char *start = s;

	for (; *s; s++) {
		unsigned char c = (unsigned char)*s;

		/* Cut at a character boundary (not inside a UTF-8 sequence). */
		if (s - start >= MESSAGE_NAME_MAX && (c & 0xc0) != 0x80) {
			sb_printf(sb, "...");
			return;
		}
		if (quoted && (c == '"' || c == '\\'))
			sb_printf(sb, "\\%c", c);
		else if (c == '\n')
			sb_printf(sb, "\\n");
		else if (c == '\t')
			sb_printf(sb, "\\t");
		else if (c < 0x20 || c == 0x7f)
			sb_printf(sb, "\\x%02x", c);
		else
			sb_printf(sb, "%c", c);
	}
}

/* Where a value sits in the document: a chain of object keys and array
 * indices from the innermost value outwards. key == NULL means index. */
struct path {
	const struct path *parent;
	const char *key;
	size_t index;
};

static int is_identifier(const char *s)
{
	if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') || *s == '_'))
		return 0;
	for (s++; *s; s++)
		if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') ||
		      (*s >= '0' && *s <= '9') || *s == '_'))
			return 0;
	return 1;
}

/* spheres[3].radius, materials.glass.ior, materials["my glass"].ior */
static void sb_path(struct sbuf *sb, const struct path *p)
{
	if (!p->parent) {
		/* Nothing above: this is a top-level key or the document. */
		if (p->key)
			sb_printf(sb, "%s", p->key);
		else
			sb_printf(sb, "(top level)");
		return;
	}
	sb_path(sb, p->parent);
	if (!p->key) {
		sb_printf(sb, "[%zu]", p->index);
	} else if (is_identifier(p->key)) {
		sb_printf(sb, ".%s", p->key);
	} else {
		sb_printf(sb, "[\"");
		sb_escaped(sb, p->key, 1);
		sb_printf(sb, "\"]");
	}
}

/* The document itself; top-level keys hang directly below it. */
static const struct path root_path = {NULL, NULL, 0};

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
};

/* A key below `parent`; top-level keys get a root-less path. */
static struct path child_key(const struct path *parent, const char *key)
{
	struct path p = {parent == &root_path ? NULL : parent, key, 0};

	return p;
}

static struct path child_index(const struct path *parent, size_t index)
{
	struct path p = {parent, NULL, index};

	return p;
}

static void write_err(struct loader *ld, const char *fmt, ...)
{
	struct sbuf sb = {ld->err, ld->err_size, 0};
	va_list ap;

	va_start(ap, fmt);
	sb_vprintf(&sb, fmt, ap);
	va_end(ap);
}

/* "FILE: PATH: message"; always returns -1 so callers can `return fail(...)`. */
static int fail(struct loader *ld, const struct path *p, const char *fmt, ...)
{
	struct sbuf sb = {ld->err, ld->err_size, 0};
	va_list ap;

	sb_printf(&sb, "%s: ", ld->source);
	sb_path(&sb, p);
	sb_printf(&sb, ": ");
	va_start(ap, fmt);
	sb_vprintf(&sb, fmt, ap);
	va_end(ap);
	return -1;
}

/* "FILE: PATH: <before>"<quoted>"", with `quoted` escaped. */
static int fail_quoted(struct loader *ld, const struct path *p, const char *before,
		       const char *quoted)
{
	struct sbuf sb = {ld->err, ld->err_size, 0};

	sb_printf(&sb, "%s: ", ld->source);
	sb_path(&sb, p);
	sb_printf(&sb, ": %s\"", before);
	sb_escaped(&sb, quoted, 1);
	sb_printf(&sb, "\"");
	return -1;
}

/* Shortest %g form that reads back as the same double: 0.1, not
 * 0.10000000000000001, and 1.0000001, not 1. */
static const char *fmt_num(double v, char buf[32])
{
	for (int precision = 6; precision <= 17; precision++) {
		snprintf(buf, 32, "%.*g", precision, v);
		if (strtod(buf, NULL) == v)
			break;
	}
	return buf;
}

static const char *type_name(const json_t *v)
{
	switch (json_typeof(v)) {
	case JSON_OBJECT:
		return "an object";
	case JSON_ARRAY:
		return "an array";
	case JSON_STRING:
		return "a string";
	case JSON_INTEGER:
		return "an integer";
	case JSON_REAL:
		return "a real number";
	case JSON_TRUE:
		return "true";
	case JSON_FALSE:
		return "false";
	case JSON_NULL:
		return "null";
	}
	return "an unknown JSON value";
}

/* Fails on the first key of `obj` not in the NULL-terminated `allowed`. */
static int check_keys(struct loader *ld, const struct path *p, json_t *obj,
		      const char *const *allowed)
{
	const char *key;
	json_t *value;

	json_object_foreach(obj, key, value)
	{
		const char *const *a = allowed;

		while (*a && strcmp(*a, key) != 0)
			a++;
		if (!*a)
			return fail_quoted(ld, p, "unknown key ", key);
	}
	return 0;
}

static int expect_object(struct loader *ld, const struct path *p, json_t *v,
			 const char *const *allowed)
{
	if (!json_is_object(v))
		return fail(ld, p, "must be an object, got %s", type_name(v));
	return check_keys(ld, p, v, allowed);
}

enum presence { OPTIONAL, REQUIRED };

/* Looks up `key`; a missing optional field leaves *out at NULL and succeeds. */
static int get_field(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		     enum presence presence, json_t **out)
{
	*out = json_object_get(obj, key);
	if (!*out && presence == REQUIRED) {
		struct path field = child_key(p, key);

		return fail(ld, &field, "required field is missing");
	}
	return 0;
}

enum range {
	DIRECTION,    /* any finite number: normalised in double on load */
	ANY,	      /* 0 or a magnitude in SCENE_MIN/MAX_MAGNITUDE */
	POSITIVE,     /* > 0 */
	NON_NEGATIVE, /* >= 0 */
	UNIT,	      /* 0 ... 1 */
	FOV,	      /* 0 < x < 180 */
};

#define WRITTEN_NUMBER_MAX 40

static const char *underflow_text(const struct loader *ld, const json_t *v,
				  char buf[WRITTEN_NUMBER_MAX]);

static int check_number(struct loader *ld, const struct path *p, json_t *v, enum range range,
			double *out)
{
	char num[32], written_buf[WRITTEN_NUMBER_MAX];
	const char *written;
	double x;

	if (!json_is_number(v))
		return fail(ld, p, "must be a number, got %s", type_name(v));
	x = json_number_value(v);
	/* jansson refuses overflowing literals; this is a second line. */
	if (!isfinite(x))
		return fail(ld, p, "must be finite, got %s", fmt_num(x, num));
	/* jansson reads 1e-400 as 0 without a word: where a positive value is
	 * required, name the number as written rather than "got 0". */
	written = (range == POSITIVE || range == FOV) && fpclassify(x) != FP_NORMAL
			  ? underflow_text(ld, v, written_buf)
			  : NULL;
	if (written) {
		if (range == POSITIVE)
			return fail(ld, p,
				    "must be between %g and %g (rtcl computes in float), got %s, "
				    "which underflows to 0",
				    SCENE_MIN_MAGNITUDE, SCENE_MAX_MAGNITUDE, written);
		return fail(ld, p, "must be > 0 and < 180, got %s, which underflows to 0", written);
	}
	switch (range) {
	case DIRECTION:
	case ANY:
		break;
	case POSITIVE:
		if (!(x > 0))
			return fail(ld, p, "must be > 0, got %s", fmt_num(x, num));
		break;
	case NON_NEGATIVE:
		if (!(x >= 0))
			return fail(ld, p, "must be >= 0, got %s", fmt_num(x, num));
		break;
	case UNIT:
		if (!(x >= 0 && x <= 1))
			return fail(ld, p, "must be between 0 and 1, got %s", fmt_num(x, num));
		break;
	case FOV:
		if (!(x > 0 && x < 180))
			return fail(ld, p, "must be > 0 and < 180, got %s", fmt_num(x, num));
		break;
	}
	if (range != DIRECTION && x != 0 &&
	    !(fabs(x) >= SCENE_MIN_MAGNITUDE && fabs(x) <= SCENE_MAX_MAGNITUDE))
		return fail(ld, p, "must be %sbetween %g and %g%s (rtcl computes in float), got %s",
			    range == POSITIVE || range == FOV ? "" : "0 or ", SCENE_MIN_MAGNITUDE,
			    SCENE_MAX_MAGNITUDE, range == ANY ? " in magnitude" : "",
			    fmt_num(x, num));
	*out = x;
	return 0;
}

static int read_number(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		       enum presence presence, enum range range, double *out)
{
	struct path field = child_key(p, key);
	json_t *v;

	if (get_field(ld, p, obj, key, presence, &v))
		return -1;
	return v ? check_number(ld, &field, v, range, out) : 0;
}

/* A JSON integer (not 2.0) in lo ... hi. */
static int check_integer(struct loader *ld, const struct path *p, json_t *v, json_int_t lo,
			 json_int_t hi, json_int_t *out)
{
	char num[32];
	json_int_t x;

	if (json_is_real(v)) {
		fmt_num(json_real_value(v), num);
		/* 2.0 must not read as "got 2". */
		if (!strpbrk(num, ".eni"))
			strcat(num, ".0");
		return fail(ld, p, "must be an integer, got %s", num);
	}
	if (!json_is_integer(v))
		return fail(ld, p, "must be an integer, got %s", type_name(v));
	x = json_integer_value(v);
	if (x < lo || x > hi)
		return fail(ld, p,
			    "must be between %" JSON_INTEGER_FORMAT " and %" JSON_INTEGER_FORMAT
			    ", got %" JSON_INTEGER_FORMAT,
			    lo, hi, x);
	*out = x;
	return 0;
}

static int read_int(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		    enum presence presence, int lo, int hi, int *out)
{
	struct path field = child_key(p, key);
	json_int_t x;
	json_t *v;

	if (get_field(ld, p, obj, key, presence, &v))
		return -1;
	if (!v)
		return 0;
	if (check_integer(ld, &field, v, lo, hi, &x))
		return -1;
	*out = (int)x;
	return 0;
}

/* A vec3 (range ANY or DIRECTION) or a color (range NON_NEGATIVE). */
static int read_vec3(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		     enum presence presence, enum range range, double out[3])
{
	struct path field = child_key(p, key);
	double parts[3];
	json_t *v;

	if (get_field(ld, p, obj, key, presence, &v))
		return -1;
	if (!v)
		return 0;
	if (!json_is_array(v))
		return fail(ld, &field, "must be an array of 3 numbers, got %s", type_name(v));
	if (json_array_size(v) != 3)
		return fail(ld, &field, "must be an array of 3 numbers, got %zu element%s",
			    json_array_size(v), json_array_size(v) == 1 ? "" : "s");
	for (size_t i = 0; i < 3; i++) {
		struct path part = child_index(&field, i);

		if (check_number(ld, &part, json_array_get(v, i), range, &parts[i]))
			return -1;
	}
	memcpy(out, parts, sizeof(parts));
	return 0;
}

static const char *fmt_vec3(const double v[3], char buf[100])
{
	char a[32], b[32], c[32];

	snprintf(buf, 100, "[%s, %s, %s]", fmt_num(v[0], a), fmt_num(v[1], b), fmt_num(v[2], c));
	return buf;
}

/* Scales v so its largest part has magnitude 1, so that squaring it can
 * neither overflow nor underflow. Returns 0 for the zero vector. */
static int scale_to_unit_max(const double v[3], double out[3])
{
	double m = fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));

	if (m == 0)
		return 0;
	for (int i = 0; i < 3; i++)
		out[i] = v[i] / m;
	return 1;
}

static double length3(const double v[3])
{
	return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static const struct scene_material default_material = {
	.color = {1, 1, 1},
	.ambient = 1.0,
	.diffuse = 0.7,
	.specular = 0.3,
	.shininess = 32,
	.reflect = 0,
	.transmit = 0,
	.ior = 1.5,
};

static int read_material_fields(struct loader *ld, const struct path *p, json_t *obj,
				struct scene_material *m)
{
	static const char *const keys[] = {"color",    "ambient",   "diffuse",
					   "specular", "shininess", "reflect",
					   "transmit", "ior",	    NULL};

	*m = default_material;
	if (expect_object(ld, p, obj, keys) ||
	    read_vec3(ld, p, obj, "color", OPTIONAL, NON_NEGATIVE, m->color) ||
	    read_number(ld, p, obj, "ambient", OPTIONAL, NON_NEGATIVE, &m->ambient) ||
	    read_number(ld, p, obj, "diffuse", OPTIONAL, NON_NEGATIVE, &m->diffuse) ||
	    read_number(ld, p, obj, "specular", OPTIONAL, NON_NEGATIVE, &m->specular) ||
	    read_number(ld, p, obj, "shininess", OPTIONAL, NON_NEGATIVE, &m->shininess) ||
	    read_number(ld, p, obj, "reflect", OPTIONAL, UNIT, &m->reflect) ||
	    read_number(ld, p, obj, "transmit", OPTIONAL, UNIT, &m->transmit) ||
	    read_number(ld, p, obj, "ior", OPTIONAL, POSITIVE, &m->ior))
		return -1;
	return 0;
}

/* An object's "material": a name, an inline object (appended after the
 * named ones), or absent (-1 until the default material gets its index). */
static int read_material_ref(struct loader *ld, const struct path *p, json_t *obj, int *index)
{
	struct path field = child_key(p, "material");
	struct scene *s = ld->scene;
	json_t *v = json_object_get(obj, "material");

	if (!v) {
		ld->default_used = 1;
		*index = -1;
		return 0;
	}
	if (json_is_string(v)) {
		json_t *named = json_object_get(ld->name_index, json_string_value(v));

		if (!named)
			return fail_quoted(ld, &field, "unknown material ", json_string_value(v));
		*index = (int)json_integer_value(named);
		return 0;
	}
	if (!json_is_object(v))
		return fail(ld, &field, "must be a material name or an object, got %s",
			    type_name(v));
	if (read_material_fields(ld, &field, v, &s->materials[s->material_count]))
		return -1;
	*index = s->material_count++;
	return 0;
}

/* Fetches an optional top-level array; a missing one counts as empty. */
static int get_array(struct loader *ld, json_t *doc, const char *key, json_t **out, size_t *count)
{
	struct path field = child_key(&root_path, key);

	*out = json_object_get(doc, key);
	*count = 0;
	if (!*out)
		return 0;
	if (!json_is_array(*out))
		return fail(ld, &field, "must be an array, got %s", type_name(*out));
	*count = json_array_size(*out);
	/* Cannot happen below SCENE_MAX_BYTES, but the counts are ints. */
	if (*count > INT_MAX / 4)
		return fail(ld, &field, "has %zu elements, more than the limit of %d", *count,
			    INT_MAX / 4);
	return 0;
}

static int read_header(struct loader *ld, json_t *doc)
{
	struct path format = child_key(&root_path, "format");
	struct path version = child_key(&root_path, "version");
	json_t *v;
	json_int_t n;

	if (!json_is_object(doc))
		return fail(ld, &root_path, "must be an object, got %s", type_name(doc));

	if (get_field(ld, &root_path, doc, "format", REQUIRED, &v))
		return -1;
	if (!json_is_string(v))
		return fail(ld, &format, "must be the string \"rtcl-scene\", got %s", type_name(v));
	if (strcmp(json_string_value(v), "rtcl-scene") != 0)
		return fail_quoted(ld, &format, "must be \"rtcl-scene\", got ",
				   json_string_value(v));

	/* Before unknown keys: a newer file may well have fields we lack. */
	if (get_field(ld, &root_path, doc, "version", REQUIRED, &v))
		return -1;
	if (check_integer(ld, &version, v, LLONG_MIN, LLONG_MAX, &n))
		return -1;
	if (n > 1)
		return fail(ld, &version,
			    "version %" JSON_INTEGER_FORMAT
			    " is not supported (this rtcl reads version 1)",
			    n);
	if (n < 1)
		return fail(ld, &version, "must be 1, got %" JSON_INTEGER_FORMAT, n);
	return 0;
}

static int read_camera(struct loader *ld, json_t *doc)
{
	static const char *const keys[] = {"eye", "look_at", "up", "fov", NULL};
	struct path p = child_key(&root_path, "camera");
	struct path look_at = child_key(&p, "look_at");
	struct path up = child_key(&p, "up");
	struct scene_camera *cam = &ld->scene->camera;
	double dir[3], d[3], u[3], cross[3];
	char buf[100];
	json_t *obj;

	cam->up[0] = 0, cam->up[1] = 1, cam->up[2] = 0;
	cam->fov = 45;
	if (get_field(ld, &root_path, doc, "camera", REQUIRED, &obj) ||
	    expect_object(ld, &p, obj, keys) ||
	    read_vec3(ld, &p, obj, "eye", REQUIRED, ANY, cam->eye) ||
	    read_vec3(ld, &p, obj, "look_at", REQUIRED, ANY, cam->look_at) ||
	    read_vec3(ld, &p, obj, "up", OPTIONAL, ANY, cam->up) ||
	    read_number(ld, &p, obj, "fov", OPTIONAL, FOV, &cam->fov))
		return -1;

	/* Halved first so that the difference cannot overflow. */
	for (int i = 0; i < 3; i++)
		dir[i] = cam->look_at[i] / 2 - cam->eye[i] / 2;
	if (!scale_to_unit_max(dir, d))
		return fail(ld, &look_at, "must differ from camera.eye, both are %s",
			    fmt_vec3(cam->eye, buf));
	if (!scale_to_unit_max(cam->up, u))
		return fail(ld, &up, "must be non-zero");
	cross[0] = u[1] * d[2] - u[2] * d[1];
	cross[1] = u[2] * d[0] - u[0] * d[2];
	cross[2] = u[0] * d[1] - u[1] * d[0];
	if (length3(cross) <= SCENE_PARALLEL_SINE * length3(u) * length3(d))
		return fail(ld, &up, "must not be parallel to look_at - eye, got %s",
			    fmt_vec3(cam->up, buf));
	return 0;
}

static int read_image_and_globals(struct loader *ld, json_t *doc)
{
	static const char *const image_keys[] = {"width", "height", NULL};
	struct path image = child_key(&root_path, "image");
	struct scene *s = ld->scene;
	json_t *obj;

	s->width = 640;
	s->height = 480;
	s->background[0] = s->background[1] = s->background[2] = 0;
	s->ambient[0] = s->ambient[1] = s->ambient[2] = 0.1;
	s->max_depth = 5;
	s->epsilon = 1e-4;

	if (get_field(ld, &root_path, doc, "image", OPTIONAL, &obj))
		return -1;
	if (obj &&
	    (expect_object(ld, &image, obj, image_keys) ||
	     read_int(ld, &image, obj, "width", OPTIONAL, 1, SCENE_MAX_IMAGE_SIDE, &s->width) ||
	     read_int(ld, &image, obj, "height", OPTIONAL, 1, SCENE_MAX_IMAGE_SIDE, &s->height)))
		return -1;
	if (read_camera(ld, doc) ||
	    read_vec3(ld, &root_path, doc, "background", OPTIONAL, NON_NEGATIVE, s->background) ||
	    read_vec3(ld, &root_path, doc, "ambient", OPTIONAL, NON_NEGATIVE, s->ambient) ||
	    read_int(ld, &root_path, doc, "max_depth", OPTIONAL, 0, SCENE_MAX_DEPTH,
		     &s->max_depth) ||
	    read_number(ld, &root_path, doc, "epsilon", OPTIONAL, POSITIVE, &s->epsilon))
		return -1;
	return 0;
}

static int read_named_materials(struct loader *ld, json_t *doc)
{
	struct path p = child_key(&root_path, "materials");
	struct scene *s = ld->scene;
	const char *name;
	json_t *named, *value;

	if (get_field(ld, &root_path, doc, "materials", OPTIONAL, &named))
		return -1;
	if (!named)
		return 0;
	if (!json_is_object(named))
		return fail(ld, &p, "must be an object, got %s", type_name(named));
	json_object_foreach(named, name, value)
	{
		struct path m = child_key(&p, name);

		if (read_material_fields(ld, &m, value, &s->materials[s->material_count]))
			return -1;
		if (json_object_set_new(ld->name_index, name, json_integer(s->material_count))) {
			write_err(ld, "%s: out of memory", ld->source);
			return -1;
		}
		s->material_count++;
	}
	return 0;
}

static int read_lights(struct loader *ld, json_t *array)
{
	static const char *const keys[] = {"position", "color", NULL};
	struct path p = child_key(&root_path, "lights");
	struct scene *s = ld->scene;

	for (size_t i = 0; i < json_array_size(array); i++) {
		struct path item = child_index(&p, i);
		struct scene_light *l = &s->lights[i];
		json_t *obj = json_array_get(array, i);

		l->color[0] = l->color[1] = l->color[2] = 1;
		if (expect_object(ld, &item, obj, keys) ||
		    read_vec3(ld, &item, obj, "position", REQUIRED, ANY, l->position) ||
		    read_vec3(ld, &item, obj, "color", OPTIONAL, NON_NEGATIVE, l->color))
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

		if (expect_object(ld, &item, obj, keys) ||
		    read_vec3(ld, &item, obj, "center", REQUIRED, ANY, sp->center) ||
		    read_number(ld, &item, obj, "radius", REQUIRED, POSITIVE, &sp->radius) ||
		    read_material_ref(ld, &item, obj, &sp->material))
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

	if (get_field(ld, plane, obj, "checker", OPTIONAL, &checker))
		return -1;
	if (!checker)
		return 0;
	if (expect_object(ld, &p, checker, keys) ||
	    read_number(ld, &p, checker, "size", REQUIRED, POSITIVE, &pl->checker_size) ||
	    read_vec3(ld, &p, checker, "color", REQUIRED, NON_NEGATIVE, pl->checker_color))
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

		if (expect_object(ld, &item, obj, keys) ||
		    read_vec3(ld, &item, obj, "point", REQUIRED, ANY, pl->point) ||
		    read_vec3(ld, &item, obj, "normal", REQUIRED, DIRECTION, pl->normal))
			return -1;
		if (!scale_to_unit_max(pl->normal, n))
			return fail(ld, &normal, "must be non-zero");
		len = length3(n);
		for (int k = 0; k < 3; k++)
			pl->normal[k] = n[k] / len;
		if (read_material_ref(ld, &item, obj, &pl->material) ||
		    read_checker(ld, &item, obj, pl))
			return -1;
		s->plane_count++;
	}
	return 0;
}

static const char *const top_level_keys[] = {
	"format",  "version",	"image",  "camera",  "background", "ambient", "max_depth",
	"epsilon", "materials", "lights", "spheres", "planes",	   NULL,
};

/* Fills ld->scene from the parsed document; on failure the caller frees
 * whatever was allocated. */
static int read_scene(struct loader *ld, json_t *doc)
{
	struct scene *s = ld->scene;
	json_t *lights, *spheres, *planes, *named;
	size_t light_count, sphere_count, plane_count, material_capacity;

	if (read_header(ld, doc) || check_keys(ld, &root_path, doc, top_level_keys) ||
	    read_image_and_globals(ld, doc) ||
	    get_array(ld, doc, "lights", &lights, &light_count) ||
	    get_array(ld, doc, "spheres", &spheres, &sphere_count) ||
	    get_array(ld, doc, "planes", &planes, &plane_count))
		return -1;

	/* Upper bound: every object brings an inline material, plus the default. */
	named = json_object_get(doc, "materials");
	material_capacity = (json_is_object(named) ? json_object_size(named) : 0) + sphere_count +
			    plane_count + 1;
	s->materials = calloc(material_capacity, sizeof(*s->materials));
	s->lights = calloc(light_count ? light_count : 1, sizeof(*s->lights));
	s->spheres = calloc(sphere_count ? sphere_count : 1, sizeof(*s->spheres));
	s->planes = calloc(plane_count ? plane_count : 1, sizeof(*s->planes));
	ld->name_index = json_object();
	if (!s->materials || !s->lights || !s->spheres || !s->planes || !ld->name_index) {
		write_err(ld, "%s: out of memory", ld->source);
		return -1;
	}

	if (read_named_materials(ld, doc) || read_lights(ld, lights) || read_spheres(ld, spheres) ||
	    read_planes(ld, planes))
		return -1;

	if (ld->default_used) {
		int index = s->material_count++;

		s->materials[index] = default_material;
		for (int i = 0; i < s->sphere_count; i++)
			if (s->spheres[i].material < 0)
				s->spheres[i].material = index;
		for (int i = 0; i < s->plane_count; i++)
			if (s->planes[i].material < 0)
				s->planes[i].material = index;
	}
	return 0;
}

/* The number literals of a document jansson has accepted, in document
 * order: next_number_literal sets *start and *len to the next one and returns
 * 1, or returns 0 at the end. Strings (keys too) are skipped; true, false and
 * null hold no digit or '-', so a number starts at the first '-' or digit. */
struct literal_scan {
	const char *at, *end;
};

static int next_number_literal(struct literal_scan *sc, const char **start, size_t *len)
{
	while (sc->at < sc->end) {
		char c = *sc->at;

		if (c == '"') {
			for (sc->at++; sc->at < sc->end && *sc->at != '"'; sc->at++)
				if (*sc->at == '\\')
					sc->at++;
			sc->at++;
		} else if (c == '-' || (c >= '0' && c <= '9')) {
			*start = sc->at;
			while (sc->at < sc->end && *sc->at && strchr("+-.eE0123456789", *sc->at))
				sc->at++;
			*len = (size_t)(sc->at - *start);
			return 1;
		} else {
			sc->at++;
		}
	}
	return 0;
}

/* Whether a number literal has a nonzero digit before its exponent. */
static int nonzero_as_written(const char *start, size_t len)
{
	for (size_t i = 0; i < len && start[i] != 'e' && start[i] != 'E'; i++)
		if (start[i] >= '1' && start[i] <= '9')
			return 1;
	return 0;
}

/* Walks `v` in document order (jansson keeps the order of object keys),
 * pairing each number with the next literal of the text, until it meets
 * `target`: returns 1 with *start and *len set to its literal, 0 if target is
 * not below v, -1 if the numbers and the literals do not pair up. */
static int find_literal(const json_t *v, const json_t *target, struct literal_scan *sc,
			const char **start, size_t *len)
{
	const char *key;
	json_t *member;
	size_t i;
	int found;

	switch (json_typeof(v)) {
	case JSON_OBJECT:
		json_object_foreach((json_t *)v, key, member)
		{
			found = find_literal(member, target, sc, start, len);
			if (found)
				return found;
		}
		return 0;
	case JSON_ARRAY:
		json_array_foreach(v, i, member)
		{
			found = find_literal(member, target, sc, start, len);
			if (found)
				return found;
		}
		return 0;
	case JSON_INTEGER:
	case JSON_REAL:
		if (!next_number_literal(sc, start, len))
			return -1;
		return v == target;
	default:
		return 0;
	}
}

/* The number `v` as written in the file ("a 400-character number" if too
 * long to quote) if that text is nonzero but jansson read it as 0 or a
 * denormal (1e-400, 1e-320), else NULL. Looked up only for the one number
 * that fails a check, so a scene costs at most one walk. */
static const char *underflow_text(const struct loader *ld, const json_t *v,
				  char buf[WRITTEN_NUMBER_MAX])
{
	struct literal_scan sc = {ld->text, ld->text + ld->text_len};
	const char *start;
	size_t len;

	if (!ld->doc || find_literal(ld->doc, v, &sc, &start, &len) != 1 ||
	    !nonzero_as_written(start, len))
		return NULL;
	if (len < WRITTEN_NUMBER_MAX)
		snprintf(buf, WRITTEN_NUMBER_MAX, "%.*s", (int)len, start);
	else
		snprintf(buf, WRITTEN_NUMBER_MAX, "a %zu-character number", len);
	return buf;
}

/* The UTF-8 encoding of U+FEFF, which some editors put at the start of a
 * file; SCENE.md allows it there. */
static const char utf8_bom[] = "\xef\xbb\xbf";

/* Parses and validates `len` bytes of JSON; `source` names them in messages. */
static int load_buffer(struct scene *scene, const char *json, size_t len, const char *source,
		       char *err, size_t err_size)
{
	struct loader ld = {.source = source, .err = err, .err_size = err_size, .scene = scene};
	json_error_t jerr;
	json_t *doc;
	int ret;

	memset(scene, 0, sizeof(*scene));
	if (len > SCENE_MAX_BYTES) {
		write_err(&ld, "%s: scene is %zu bytes, more than the limit of %zu bytes", source,
			  len, SCENE_MAX_BYTES);
		return -1;
	}
	if (len >= 3 && memcmp(json, utf8_bom, 3) == 0) {
		json += 3;
		len -= 3;
	}
	doc = json_loadb(json, len, JSON_REJECT_DUPLICATES, &jerr);
	if (!doc) {
		struct sbuf sb = {err, err_size, 0};

		sb_printf(&sb, "%s:%d:%d: ", source, jerr.line, jerr.column);
		sb_escaped(&sb, jerr.text, 0);
		return -1;
	}

	scene->source = strdup(source);
	if (!scene->source) {
		write_err(&ld, "%s: out of memory", source);
		ret = -1;
	} else {
		ld.doc = doc;
		ld.text = json;
		ld.text_len = len;
		ret = read_scene(&ld, doc);
	}
	json_decref(ld.name_index);
	json_decref(doc);
	if (ret)
		scene_free(scene);
	return ret;
}

int scene_load_file(struct scene *scene, const char *path, char *err, size_t err_size)
{
	size_t len;
	char *buf;
	int ret;

	memset(scene, 0, sizeof(*scene));
	if (files_read(path, "scene", SCENE_MAX_BYTES, &buf, &len, err, err_size))
		return -1;
	ret = load_buffer(scene, buf, len, path, err, err_size);
	free(buf);
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
		write_err(&ld, "%s: no scene text", name);
		return -1;
	}
	return load_buffer(scene, json, strlen(json), name, err, err_size);
}

void scene_free(struct scene *scene)
{
	free(scene->source);
	free(scene->materials);
	free(scene->spheres);
	free(scene->planes);
	free(scene->lights);
	memset(scene, 0, sizeof(*scene));
}
