/* The scene loader's messages ("FILE: PATH: what is wrong", with PATH such as
 * spheres[3].radius) and its checks of fields, numbers and vectors. */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/quote.h"
#include "base/vec3.h"
#include "scene/scene_loader.h"
#include "base/suggest.h"

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
		char escaped[QUOTE_BYTE_SIZE];

		sb_printf(sb, "%s", quote_byte(c, quoted, escaped));
	}
}

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

const struct path root_path = {NULL, NULL, 0};

void loader_format_path(const struct path *p, char *out, size_t size)
{
	struct sbuf sb = {out, size, 0};

	out[0] = '\0';
	sb_path(&sb, p);
}

void loader_write_err(struct loader *ld, const char *fmt, ...)
{
	struct sbuf sb = {ld->err, ld->err_size, 0};
	va_list ap;

	va_start(ap, fmt);
	sb_vprintf(&sb, fmt, ap);
	va_end(ap);
}

/* "FILE: PATH: message"; always returns -1 so callers can `return loader_fail(...)`. */
int loader_fail(struct loader *ld, const struct path *p, const char *fmt, ...)
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
int loader_fail_json(struct loader *ld, const json_error_t *jerr)
{
	struct sbuf sb = {ld->err, ld->err_size, 0};

	sb_printf(&sb, "%s:%d:%d: ", ld->source, jerr->line, jerr->column);
	sb_escaped(&sb, jerr->text, 0);
	return -1;
}

int loader_fail_quoted(struct loader *ld, const struct path *p, const char *before,
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
const char *loader_fmt_num(double v, char buf[32])
{
	for (int precision = 6; precision <= 17; precision++) {
		snprintf(buf, 32, "%.*g", precision, v);
		if (strtod(buf, NULL) == v)
			break;
	}
	return buf;
}

const char *loader_type_name(const json_t *v)
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
int loader_check_keys(struct loader *ld, const struct path *p, json_t *obj,
		      const char *const *allowed)
{
	const char *key;
	json_t *value;

	json_object_foreach(obj, key, value)
	{
		const char *const *a = allowed;

		while (*a && strcmp(*a, key) != 0)
			a++;
		if (!*a) {
			loader_fail_quoted(ld, p, "unknown key ", key);
			suggest_append(ld->err, ld->err_size, key, allowed, (size_t)(a - allowed),
				       "");
			return -1;
		}
	}
	return 0;
}

int loader_expect_object(struct loader *ld, const struct path *p, json_t *v,
			 const char *const *allowed)
{
	if (!json_is_object(v))
		return loader_fail(ld, p, "must be an object, got %s", loader_type_name(v));
	return loader_check_keys(ld, p, v, allowed);
}

/* Looks up `key`; a missing optional field leaves *out at NULL and succeeds. */
int loader_get_field(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		     enum presence presence, json_t **out)
{
	*out = json_object_get(obj, key);
	if (!*out && presence == REQUIRED) {
		struct path field = child_key(p, key);

		return loader_fail(ld, &field, "required field is missing");
	}
	return 0;
}

int loader_check_number(struct loader *ld, const struct path *p, json_t *v, enum range range,
			double *out)
{
	char num[32], written_buf[WRITTEN_NUMBER_MAX];
	const char *written;
	double x;

	if (!json_is_number(v))
		return loader_fail(ld, p, "must be a number, got %s", loader_type_name(v));
	x = json_number_value(v);
	/* jansson refuses overflowing literals; this is a second line. */
	if (!isfinite(x))
		return loader_fail(ld, p, "must be finite, got %s", loader_fmt_num(x, num));
	/* jansson reads 1e-400 as 0 without a word: where a positive value is
	 * required, name the number as written rather than "got 0". */
	written = (range == POSITIVE || range == FOV) && fpclassify(x) != FP_NORMAL
			  ? loader_underflow_text(ld, v, written_buf)
			  : NULL;
	if (written) {
		if (range == POSITIVE)
			return loader_fail(
				ld, p,
				"must be between %g and %g (rtcl computes in float), got %s, "
				"which underflows to 0",
				SCENE_MIN_MAGNITUDE, SCENE_MAX_MAGNITUDE, written);
		return loader_fail(ld, p, "must be > 0 and < 180, got %s, which underflows to 0",
				   written);
	}
	switch (range) {
	case DIRECTION:
	case ANY:
		break;
	case POSITIVE:
		if (!(x > 0))
			return loader_fail(ld, p, "must be > 0, got %s", loader_fmt_num(x, num));
		break;
	case NON_NEGATIVE:
		if (!(x >= 0))
			return loader_fail(ld, p, "must be >= 0, got %s", loader_fmt_num(x, num));
		break;
	case UNIT:
		if (!(x >= 0 && x <= 1))
			return loader_fail(ld, p, "must be between 0 and 1, got %s",
					   loader_fmt_num(x, num));
		break;
	case FOV:
		if (!(x > 0 && x < 180))
			return loader_fail(ld, p, "must be > 0 and < 180, got %s",
					   loader_fmt_num(x, num));
		break;
	}
	if (range != DIRECTION && x != 0 &&
	    !(fabs(x) >= SCENE_MIN_MAGNITUDE && fabs(x) <= SCENE_MAX_MAGNITUDE))
		return loader_fail(ld, p,
				   "must be %sbetween %g and %g%s (rtcl computes in float), got %s",
				   range == POSITIVE || range == FOV ? "" : "0 or ",
				   SCENE_MIN_MAGNITUDE, SCENE_MAX_MAGNITUDE,
				   range == ANY ? " in magnitude" : "", loader_fmt_num(x, num));
	*out = x;
	return 0;
}

int loader_read_number(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		       enum presence presence, enum range range, double *out)
{
	struct path field = child_key(p, key);
	json_t *v;

	if (loader_get_field(ld, p, obj, key, presence, &v))
		return -1;
	return v ? loader_check_number(ld, &field, v, range, out) : 0;
}

/* A JSON integer (not 2.0) in lo ... hi. */
int loader_check_integer(struct loader *ld, const struct path *p, json_t *v, json_int_t lo,
			 json_int_t hi, json_int_t *out)
{
	char num[32];
	json_int_t x;

	if (json_is_real(v)) {
		loader_fmt_num(json_real_value(v), num);
		/* 2.0 must not read as "got 2". */
		if (!strpbrk(num, ".eni"))
			strcat(num, ".0");
		return loader_fail(ld, p, "must be an integer, got %s", num);
	}
	if (!json_is_integer(v))
		return loader_fail(ld, p, "must be an integer, got %s", loader_type_name(v));
	x = json_integer_value(v);
	if (x < lo || x > hi)
		return loader_fail(ld, p,
				   "must be between %" JSON_INTEGER_FORMAT
				   " and %" JSON_INTEGER_FORMAT ", got %" JSON_INTEGER_FORMAT,
				   lo, hi, x);
	*out = x;
	return 0;
}

int loader_read_int(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		    enum presence presence, int lo, int hi, int *out)
{
	struct path field = child_key(p, key);
	json_int_t x;
	json_t *v;

	if (loader_get_field(ld, p, obj, key, presence, &v))
		return -1;
	if (!v)
		return 0;
	if (loader_check_integer(ld, &field, v, lo, hi, &x))
		return -1;
	*out = (int)x;
	return 0;
}

int loader_check_vec3(struct loader *ld, const struct path *p, json_t *v, enum range range,
		      double out[3])
{
	double parts[3];

	if (!json_is_array(v))
		return loader_fail(ld, p, "must be an array of 3 numbers, got %s",
				   loader_type_name(v));
	if (json_array_size(v) != 3)
		return loader_fail(ld, p, "must be an array of 3 numbers, got %zu element%s",
				   json_array_size(v), json_array_size(v) == 1 ? "" : "s");
	for (size_t i = 0; i < 3; i++) {
		struct path part = child_index(p, i);

		if (loader_check_number(ld, &part, json_array_get(v, i), range, &parts[i]))
			return -1;
	}
	memcpy(out, parts, sizeof(parts));
	return 0;
}

/* A vec3 (range ANY or DIRECTION) or a color (range NON_NEGATIVE). */
int loader_read_vec3(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		     enum presence presence, enum range range, double out[3])
{
	struct path field = child_key(p, key);
	json_t *v;

	if (loader_get_field(ld, p, obj, key, presence, &v))
		return -1;
	return v ? loader_check_vec3(ld, &field, v, range, out) : 0;
}

const char *loader_fmt_vec3(const double v[3], char buf[100])
{
	char a[32], b[32], c[32];

	snprintf(buf, 100, "[%s, %s, %s]", loader_fmt_num(v[0], a), loader_fmt_num(v[1], b),
		 loader_fmt_num(v[2], c));
	return buf;
}

/* Scales v so its largest part has magnitude 1, so that squaring it can
 * neither overflow nor underflow. Returns 0 for the zero vector. */
int loader_scale_to_unit_max(const double v[3], double out[3])
{
	double m = fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));

	if (m == 0)
		return 0;
	for (int i = 0; i < 3; i++)
		out[i] = v[i] / m;
	return 1;
}

double loader_length3(const double v[3])
{
	return vec3_length(v);
}

/* The scene loader's files: recorded here, with the messages, so that the
 * parts of the loader (scene.c, scene_mesh.c) need not call each other. */
int loader_add_input(struct loader *ld, char *path, const char *kind)
{
	struct scene *scene = ld->scene;
	struct scene_input *grown =
		realloc(scene->inputs, ((size_t)scene->input_count + 1) * sizeof(*grown));

	if (!grown) {
		free(path);
		loader_write_err(ld, "%s: out of memory", ld->source);
		return -1;
	}
	scene->inputs = grown;
	scene->inputs[scene->input_count++] = (struct scene_input){path, kind};
	return 0;
}

int loader_read_choice(struct loader *ld, const struct path *p, json_t *obj, const char *key,
		       enum presence presence, const char *const *names, int *out)
{
	struct path field = child_key(p, key);
	char rule[200];
	size_t count = 0, used = 0;
	json_t *v;

	if (loader_get_field(ld, p, obj, key, presence, &v))
		return -1;
	if (!v)
		return 0;
	while (names[count])
		count++;
	/* must be "a", "b" or "c", got */
	used += (size_t)snprintf(rule, sizeof(rule), "must be ");
	for (size_t i = 0; i < count && used < sizeof(rule); i++)
		used += (size_t)snprintf(rule + used, sizeof(rule) - used, "\"%s\"%s", names[i],
					 i + 2 < count ? ", " : i + 2 == count ? " or " : "");
	if (used < sizeof(rule))
		snprintf(rule + used, sizeof(rule) - used, ", got ");
	if (!json_is_string(v))
		return loader_fail(ld, &field, "%s%s", rule, loader_type_name(v));
	for (size_t i = 0; i < count; i++)
		if (strcmp(json_string_value(v), names[i]) == 0) {
			*out = (int)i;
			return 0;
		}
	loader_fail_quoted(ld, &field, rule, json_string_value(v));
	suggest_append(ld->err, ld->err_size, json_string_value(v), names, count, "");
	return -1;
}
