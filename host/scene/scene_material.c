/* The scene loader's materials (docs/SCENE.md, "Material"): the named ones,
 * and an object's reference to one by name or inline. */
#include <jansson.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_loader.h"
#include "base/suggest.h"

const struct scene_material loader_default_material = {
	.color = {1, 1, 1},
	.ambient = 1.0,
	.diffuse = 0.7,
	.specular = 0.3,
	.shininess = 32,
	.reflect = 0,
	.transmit = 0,
	.ior = 1.5,
	.fresnel = SCENE_FRESNEL_OFF,
};

/* "fresnel": "dielectric", "conductor" or false (SCENE.md, "Material"). */
static int read_fresnel(struct loader *ld, const struct path *p, json_t *obj, int *fresnel)
{
	struct path field = child_key(p, "fresnel");
	json_t *v = json_object_get(obj, "fresnel");
	const char *rule = "must be \"dielectric\", \"conductor\" or false, got ";

	if (!v || json_is_false(v))
		return 0;
	if (json_is_string(v) && strcmp(json_string_value(v), "dielectric") == 0)
		*fresnel = SCENE_FRESNEL_DIELECTRIC;
	else if (json_is_string(v) && strcmp(json_string_value(v), "conductor") == 0)
		*fresnel = SCENE_FRESNEL_CONDUCTOR;
	else if (json_is_string(v))
		return loader_fail_quoted(ld, &field, rule, json_string_value(v));
	else
		return loader_fail(ld, &field, "%s%s", rule,
				   json_is_true(v) ? "true" : loader_type_name(v));
	return 0;
}

static int read_material_fields(struct loader *ld, const struct path *p, json_t *obj,
				struct scene_material *m)
{
	static const char *const keys[] = {"color",    "ambient",   "diffuse",
					   "specular", "shininess", "reflect",
					   "transmit", "ior",	    "fresnel",
					   NULL};

	*m = loader_default_material;
	if (loader_expect_object(ld, p, obj, keys) ||
	    loader_read_vec3(ld, p, obj, "color", OPTIONAL, NON_NEGATIVE, m->color) ||
	    loader_read_number(ld, p, obj, "ambient", OPTIONAL, NON_NEGATIVE, &m->ambient) ||
	    loader_read_number(ld, p, obj, "diffuse", OPTIONAL, NON_NEGATIVE, &m->diffuse) ||
	    loader_read_number(ld, p, obj, "specular", OPTIONAL, NON_NEGATIVE, &m->specular) ||
	    loader_read_number(ld, p, obj, "shininess", OPTIONAL, NON_NEGATIVE, &m->shininess) ||
	    loader_read_number(ld, p, obj, "reflect", OPTIONAL, UNIT, &m->reflect) ||
	    loader_read_number(ld, p, obj, "transmit", OPTIONAL, UNIT, &m->transmit) ||
	    loader_read_number(ld, p, obj, "ior", OPTIONAL, POSITIVE, &m->ior) ||
	    read_fresnel(ld, p, obj, &m->fresnel))
		return -1;
	return 0;
}

/* "unknown material "NAME"", with the nearest named material suggested. */
static int fail_unknown_material(struct loader *ld, const struct path *p, const char *name)
{
	size_t count = json_object_size(ld->name_index), n = 0;
	const char **names = malloc((count ? count : 1) * sizeof(*names));
	const char *key;
	json_t *value;

	loader_fail_quoted(ld, p, "unknown material ", name);
	if (!names)
		return -1; /* the message without a suggestion */
	json_object_foreach(ld->name_index, key, value)
	{
		names[n++] = key;
	}
	suggest_append(ld->err, ld->err_size, name, names, n, "");
	free(names);
	return -1;
}

int loader_read_material_ref(struct loader *ld, const struct path *p, json_t *obj, int *index)
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
			return fail_unknown_material(ld, &field, json_string_value(v));
		*index = (int)json_integer_value(named);
		return 0;
	}
	if (!json_is_object(v))
		return loader_fail(ld, &field, "must be a material name or an object, got %s",
				   loader_type_name(v));
	if (read_material_fields(ld, &field, v, &s->materials[s->material_count]))
		return -1;
	*index = s->material_count++;
	return 0;
}

int loader_read_named_materials(struct loader *ld, json_t *doc)
{
	struct path p = child_key(&root_path, "materials");
	struct scene *s = ld->scene;
	const char *name;
	json_t *named, *value;

	if (loader_get_field(ld, &root_path, doc, "materials", OPTIONAL, &named))
		return -1;
	if (!named)
		return 0;
	if (!json_is_object(named))
		return loader_fail(ld, &p, "must be an object, got %s", loader_type_name(named));
	json_object_foreach(named, name, value)
	{
		struct path m = child_key(&p, name);

		if (read_material_fields(ld, &m, value, &s->materials[s->material_count]))
			return -1;
		if (json_object_set_new(ld->name_index, name, json_integer(s->material_count))) {
			loader_write_err(ld, "%s: out of memory", ld->source);
			return -1;
		}
		s->material_count++;
	}
	return 0;
}
