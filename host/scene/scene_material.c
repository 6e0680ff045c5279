/* The scene loader's materials (docs/SCENE.md, "Material"): the named ones,
 * and an object's reference to one by name or inline. */
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_loader.h"
#include "scene/mesh.h"
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

/* A bsdf's colour (reflectance, base_color): a color whose parts are at
 * most 1 (SCENE.md, "A material's bsdf"). */
static int read_reflectance(struct loader *ld, const struct path *p, json_t *obj, const char *key,
			    double out[3])
{
	struct path field = child_key(p, key);
	char buf[100];

	if (loader_read_vec3(ld, p, obj, key, OPTIONAL, NON_NEGATIVE, out))
		return -1;
	if (out[0] > 1 || out[1] > 1 || out[2] > 1)
		return loader_fail(ld, &field,
				   "must be a color with parts between 0 and 1, got %s",
				   loader_fmt_vec3(out, buf));
	return 0;
}

/* "bsdf" (SCENE.md, "A material's bsdf"): its type, then the fields of
 * that type with their defaults. */
static int read_bsdf(struct loader *ld, const struct path *p, json_t *obj, struct scene_bsdf *b)
{
	static const char *const types[] = {"diffuse", "conductor", "dielectric", "principled",
					    NULL};
	static const char *const diffuse_keys[] = {"type", "reflectance", NULL};
	static const char *const conductor_keys[] = {"type", "reflectance", "roughness", NULL};
	static const char *const dielectric_keys[] = {"type", "ior", "roughness", NULL};
	static const char *const principled_keys[] = {"type",	      "base_color", "metallic",
						      "roughness",    "transmission", "ior",
						      NULL};
	static const char *const *const keys[] = {diffuse_keys, conductor_keys, dielectric_keys,
						  principled_keys};
	struct path field = child_key(p, "bsdf");
	json_t *v = json_object_get(obj, "bsdf");
	int type = 0;

	if (!v)
		return 0;
	if (!json_is_object(v))
		return loader_fail(ld, &field, "must be an object, got %s", loader_type_name(v));
	if (loader_read_choice(ld, &field, v, "type", REQUIRED, types, &type) ||
	    loader_check_keys(ld, &field, v, keys[type]))
		return -1;
	b->type = SCENE_BSDF_DIFFUSE + type;
	b->roughness = b->type == SCENE_BSDF_PRINCIPLED ? 0.5 : 0;
	b->ior = 1.5;
	b->metallic = b->transmission = 0;
	for (int i = 0; i < 3; i++)
		b->color[i] = b->type == SCENE_BSDF_DIFFUSE ? 0.5 : 1;
	switch (b->type) {
	case SCENE_BSDF_DIFFUSE:
		return read_reflectance(ld, &field, v, "reflectance", b->color);
	case SCENE_BSDF_CONDUCTOR:
		return read_reflectance(ld, &field, v, "reflectance", b->color) ||
		       loader_read_number(ld, &field, v, "roughness", OPTIONAL, UNIT, &b->roughness);
	case SCENE_BSDF_DIELECTRIC:
		return loader_read_number(ld, &field, v, "ior", OPTIONAL, POSITIVE, &b->ior) ||
		       loader_read_number(ld, &field, v, "roughness", OPTIONAL, UNIT, &b->roughness);
	default:
		return read_reflectance(ld, &field, v, "base_color", b->color) ||
		       loader_read_number(ld, &field, v, "metallic", OPTIONAL, UNIT, &b->metallic) ||
		       loader_read_number(ld, &field, v, "roughness", OPTIONAL, UNIT,
					  &b->roughness) ||
		       loader_read_number(ld, &field, v, "transmission", OPTIONAL, UNIT,
					  &b->transmission) ||
		       loader_read_number(ld, &field, v, "ior", OPTIONAL, POSITIVE, &b->ior);
	}
}

static int read_material_fields(struct loader *ld, const struct path *p, json_t *obj,
				struct scene_material *m)
{
	static const char *const keys[] = {"color",    "ambient",  "diffuse", "specular",
					   "shininess", "reflect",  "transmit", "ior",
					   "fresnel",  "bsdf",	   "emission", NULL};

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
	    read_fresnel(ld, p, obj, &m->fresnel) || read_bsdf(ld, p, obj, &m->bsdf) ||
	    loader_read_vec3(ld, p, obj, "emission", OPTIONAL, NON_NEGATIVE, m->emission))
		return -1;
	return 0;
}

int loader_append_material(struct loader *ld, const struct scene_material *m)
{
	struct scene *s = ld->scene;

	if ((size_t)s->material_count >= ld->material_capacity) {
		size_t capacity = ld->material_capacity * 2 + 16;
		struct scene_material *grown =
			capacity <= INT_MAX ? realloc(s->materials, capacity * sizeof(*grown))
					    : NULL;

		if (!grown) {
			loader_write_err(ld, "%s: out of memory for %zu materials", ld->source,
					 capacity);
			return -1;
		}
		s->materials = grown;
		ld->material_capacity = capacity;
	}
	s->materials[s->material_count] = *m;
	return s->material_count++;
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
	json_t *v = json_object_get(obj, "material");

	if (!v) {
		ld->default_used = 1;
		*index = -1;
		return 0;
	}
	return loader_read_material_value(ld, &field, v, index);
}

int loader_read_material_value(struct loader *ld, const struct path *field, json_t *v, int *index)
{
	struct scene_material m;

	if (json_is_string(v)) {
		json_t *named = json_object_get(ld->name_index, json_string_value(v));

		if (!named)
			return fail_unknown_material(ld, field, json_string_value(v));
		*index = (int)json_integer_value(named);
		return 0;
	}
	if (!json_is_object(v))
		return loader_fail(ld, field, "must be a material name or an object, got %s",
				   loader_type_name(v));
	if (read_material_fields(ld, field, v, &m))
		return -1;
	*index = loader_append_material(ld, &m);
	return *index < 0 ? -1 : 0;
}

int loader_read_named_materials(struct loader *ld, json_t *doc)
{
	struct path p = child_key(&root_path, "materials");
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
		struct scene_material material;
		int index;

		if (read_material_fields(ld, &m, value, &material) ||
		    (index = loader_append_material(ld, &material)) < 0)
			return -1;
		if (json_object_set_new(ld->name_index, name, json_integer(index))) {
			loader_write_err(ld, "%s: out of memory", ld->source);
			return -1;
		}
	}
	return 0;
}

/* ---- A mesh file's material: RENDERING.md, "Materials from mesh files" ---- */

static double mean3(const double v[3])
{
	return (v[0] + v[1] + v[2]) / 3;
}

/* x within what SCENE.md allows a material's number: [lo, hi], magnitudes
 * below SCENE_MIN_MAGNITUDE taken as 0. */
static double allowed(double x, double lo, double hi)
{
	x = x < lo ? lo : x > hi ? hi : x;
	return fabs(x) < SCENE_MIN_MAGNITUDE ? 0 : x;
}

static void from_phong(const struct mesh_material *in, struct scene_material *m)
{
	double ka = mean3(in->ambient);
	int highlight = in->illum != 0, reflection = in->illum >= 3 && in->illum <= 7;

	memcpy(m->color, in->diffuse, sizeof(m->color));
	m->diffuse = in->opacity;
	m->ambient = ka > 0 ? ka : 1;
	m->specular = highlight ? mean3(in->specular) : 0;
	m->shininess = in->shininess;
	m->reflect = reflection ? mean3(in->specular) : 0;
	m->transmit = 1 - in->opacity;
	m->ior = in->ior > 0 ? in->ior : 1;
}

static void from_metallic_roughness(const struct mesh_material *in, struct scene_material *m)
{
	double metal = allowed(in->metallic, 0, 1), rough = allowed(in->roughness, 0, 1);
	double t = allowed(in->transmission, 0, 1);
	double alpha = in->alpha_mode == MESH_ALPHA_BLEND ? allowed(in->base[3], 0, 1) : 1;
	double r4 = rough * rough * rough * rough;

	memcpy(m->color, in->base, sizeof(m->color));
	m->diffuse = (1 - metal) * (1 - t) * alpha;
	m->ambient = m->diffuse;
	m->specular = (0.04 * (1 - metal) + metal) * (1 - rough) * alpha;
	m->shininess = 2 / (r4 > 1e-4 ? r4 : 1e-4) - 2;
	m->reflect = metal * (1 - rough) * alpha;
	m->transmit = 1 - alpha * (1 - (1 - metal) * t);
	m->ior = in->has_ior ? in->ior : t > 0 ? 1.5 : 1;
	/* The path integrator's principled BSDF takes the factors as glTF
	 * gives them (RENDERING.md, "The BSDFs"). */
	m->bsdf.type = SCENE_BSDF_PRINCIPLED;
	for (int i = 0; i < 3; i++)
		m->bsdf.color[i] = allowed(in->base[i], 0, 1);
	m->bsdf.metallic = metal;
	m->bsdf.roughness = rough;
	m->bsdf.transmission = t;
	m->bsdf.ior = in->has_ior && in->ior > 0 ? allowed(in->ior, 1e-18, SCENE_MAX_MAGNITUDE)
						 : 1.5;
	/* RENDERING.md, "Alpha cut-out": a = b.a times the texture's alpha;
	 * the texture is the scene loader's to give (scene_mesh.c). */
	if (in->alpha_mode == MESH_ALPHA_MASK) {
		m->alpha_cutoff = allowed(in->alpha_cutoff, 0, SCENE_MAX_MAGNITUDE);
		m->alpha_scale = allowed(in->base[3], 0, 1);
	}
}

/* The first number of in the rule reads that is not finite: its name as
 * the file's format writes it, or NULL. */
static const char *not_finite(const struct mesh_material *in)
{
	static const char *const phong[] = {"Kd", "Kd", "Kd", "Ks", "Ks", "Ks",
					    "Ka", "Ka", "Ka", "Ns", "d",  "Ni"};
	static const char *const pbr[] = {
		"baseColorFactor", "baseColorFactor", "baseColorFactor",    "baseColorFactor",
		"metallicFactor",  "roughnessFactor", "transmissionFactor", "ior", "alphaCutoff"};
	const double phong_values[] = {in->diffuse[0],	in->diffuse[1],	 in->diffuse[2],
				       in->specular[0], in->specular[1], in->specular[2],
				       in->ambient[0],	in->ambient[1],	 in->ambient[2],
				       in->shininess,	in->opacity,	 in->ior};
	const double pbr_values[] = {in->base[0],  in->base[1],	  in->base[2],	    in->base[3],
				     in->metallic, in->roughness, in->transmission, in->ior,
				     in->alpha_cutoff};

	if (in->kind == MESH_MATERIAL_PHONG) {
		for (size_t i = 0; i < sizeof(phong_values) / sizeof(phong_values[0]); i++)
			if (!isfinite(phong_values[i]))
				return phong[i];
	} else {
		for (size_t i = 0; i < sizeof(pbr_values) / sizeof(pbr_values[0]); i++)
			if (!isfinite(pbr_values[i]))
				return pbr[i];
	}
	return NULL;
}

const char *loader_material_from_mesh(const struct mesh_material *in, struct scene_material *m)
{
	const char *bad = not_finite(in);

	if (bad)
		return bad;
	/* The fields the rules leave (fresnel off, no texture) as a scene
	 * material's defaults. */
	*m = loader_default_material;
	if (in->kind == MESH_MATERIAL_METALLIC_ROUGHNESS)
		from_metallic_roughness(in, m);
	else
		from_phong(in, m);
	for (int i = 0; i < 3; i++)
		m->color[i] = allowed(m->color[i], 0, SCENE_MAX_MAGNITUDE);
	m->ambient = allowed(m->ambient, 0, SCENE_MAX_MAGNITUDE);
	m->diffuse = allowed(m->diffuse, 0, SCENE_MAX_MAGNITUDE);
	m->specular = allowed(m->specular, 0, SCENE_MAX_MAGNITUDE);
	m->shininess = allowed(m->shininess, 0, SCENE_MAX_MAGNITUDE);
	m->reflect = allowed(m->reflect, 0, 1);
	m->transmit = allowed(m->transmit, 0, 1);
	m->ior = allowed(m->ior, 0, SCENE_MAX_MAGNITUDE);
	if (m->ior == 0)
		m->ior = 1;
	for (int i = 0; i < 3; i++)
		m->emission[i] = allowed(in->emissive[i], 0, SCENE_MAX_MAGNITUDE);
	return NULL;
}
