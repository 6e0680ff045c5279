/* Unit tests for host/scene/scene.c (the scene loader, docs: SCENE.md).
 *
 * Build and run from the repository root:
 *   gcc -std=c11 -Wall -Wextra -Ihost host/scene/scene.c test/test_scene.c \
 *       -ljansson -lcriterion -lm -o /tmp/test_scene && /tmp/test_scene
 * RTCL_BAD_SCENES overrides the folder of bad scenes (default test/bad_scenes).
 */
#define _POSIX_C_SOURCE 200809L

#include "scene/scene.h"

#include <criterion/criterion.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define HEADER "\"format\": \"rtcl-scene\", \"version\": 1, "
#define CAMERA "\"camera\": {\"eye\": [0, 1, -5], \"look_at\": [0, 1, 0]}"
/* A minimal valid scene with `extra` members appended. */
#define SCENE(extra) "{" HEADER CAMERA extra "}"

static void load_ok(struct scene *s, const char *json)
{
	char err[512] = "";
	int ret = scene_load_string(s, json, "t.json", err, sizeof(err));

	cr_assert_eq(ret, 0, "scene refused: %s\n%s", err, json);
}

/* Loads `json` expecting failure with exactly `expected`, and checks that
 * the refused scene holds nothing. */
static void load_fails(const char *json, const char *expected)
{
	struct scene s;
	char err[512] = "";
	int ret = scene_load_string(&s, json, "t.json", err, sizeof(err));

	cr_assert_eq(ret, -1, "scene accepted, expected \"%s\":\n%s", expected, json);
	cr_expect_str_eq(err, expected, "for scene:\n%s", json);
	cr_expect_null(s.source);
	cr_expect_null(s.materials);
	cr_expect_null(s.spheres);
	cr_expect_eq(s.sphere_count, 0);
}

static void expect_vec3(const double v[3], double x, double y, double z)
{
	cr_expect_float_eq(v[0], x, 1e-12, "x: %.17g != %.17g", v[0], x);
	cr_expect_float_eq(v[1], y, 1e-12, "y: %.17g != %.17g", v[1], y);
	cr_expect_float_eq(v[2], z, 1e-12, "z: %.17g != %.17g", v[2], z);
}

static void expect_default_material(const struct scene_material *m)
{
	expect_vec3(m->color, 1, 1, 1);
	cr_expect_eq(m->ambient, 1.0);
	cr_expect_eq(m->diffuse, 0.7);
	cr_expect_eq(m->specular, 0.3);
	cr_expect_eq(m->shininess, 32);
	cr_expect_eq(m->reflect, 0);
	cr_expect_eq(m->transmit, 0);
	cr_expect_eq(m->ior, 1.5);
}

Test(scene, defaults)
{
	struct scene s;

	load_ok(&s, SCENE(""));
	cr_expect_str_eq(s.source, "t.json");
	cr_expect_eq(s.width, 640);
	cr_expect_eq(s.height, 480);
	expect_vec3(s.camera.eye, 0, 1, -5);
	expect_vec3(s.camera.look_at, 0, 1, 0);
	expect_vec3(s.camera.up, 0, 1, 0);
	cr_expect_eq(s.camera.fov, 45);
	expect_vec3(s.background, 0, 0, 0);
	expect_vec3(s.ambient, 0.1, 0.1, 0.1);
	cr_expect_eq(s.max_depth, 5);
	cr_expect_eq(s.epsilon, 1e-4);
	/* Nothing uses the default material, so it is not added. */
	cr_expect_eq(s.material_count, 0);
	cr_expect_eq(s.sphere_count, 0);
	cr_expect_eq(s.plane_count, 0);
	cr_expect_eq(s.light_count, 0);
	scene_free(&s);
	cr_expect_null(s.source);
	cr_expect_null(s.materials);
}

Test(scene, partial_image_and_defaults_of_objects)
{
	struct scene s;

	load_ok(&s, SCENE(", \"image\": {\"height\": 100}, \"lights\": [{\"position\": [1, 2, 3]}],"
			  "\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 2}]"));
	cr_expect_eq(s.width, 640);
	cr_expect_eq(s.height, 100);
	cr_assert_eq(s.light_count, 1);
	expect_vec3(s.lights[0].position, 1, 2, 3);
	expect_vec3(s.lights[0].color, 1, 1, 1);
	cr_assert_eq(s.sphere_count, 1);
	cr_expect_eq(s.spheres[0].radius, 2.0);
	cr_assert_eq(s.material_count, 1);
	cr_assert_eq(s.spheres[0].material, 0);
	expect_default_material(&s.materials[0]);
	scene_free(&s);
}

/* The example of SCENE.md, field by field. */
Test(scene, full_example)
{
	static const char json[] =
		"{\n"
		"  \"format\": \"rtcl-scene\",\n"
		"  \"version\": 1,\n"
		"  \"image\":  { \"width\": 2000, \"height\": 1500 },\n"
		"  \"camera\": { \"eye\": [0, 6, -24], \"look_at\": [0, 1, 0], \"up\": [0, 1, 0], "
		"\"fov\": 40.5 },\n"
		"  \"background\": [0.05, 0.07, 0.12],\n"
		"  \"ambient\":    [0.10, 0.10, 0.10],\n"
		"  \"max_depth\": 7,\n"
		"  \"epsilon\": 1e-3,\n"
		"  \"materials\": {\n"
		"    \"glass\": { \"color\": [1, 1, 1], \"ambient\": 0.5, \"diffuse\": 0.05, "
		"\"specular\": 0.8, \"shininess\": 200,\n"
		"               \"reflect\": 0.1, \"transmit\": 0.85, \"ior\": 1.5 }\n"
		"  },\n"
		"  \"lights\":  [ { \"position\": [-10, 20, -10], \"color\": [0.8, 0.8, 0.8] } ],\n"
		"  \"spheres\": [ { \"center\": [0, 1, 0], \"radius\": 1, \"material\": \"glass\" "
		"},\n"
		"               { \"center\": [2, 1, 1], \"radius\": 1.5, \"material\": { "
		"\"color\": "
		"[0.9, 0.2, 0.2] } } ],\n"
		"  \"planes\":  [ { \"point\": [0, 0, 0], \"normal\": [0, 1, 0],\n"
		"                 \"material\": { \"color\": [0.9, 0.9, 0.9], \"reflect\": 0.3 },\n"
		"                 \"checker\": { \"size\": 2, \"color\": [0.2, 0.2, 0.2] } } ]\n"
		"}\n";
	struct scene s;
	const struct scene_material *m;

	load_ok(&s, json);
	cr_expect_eq(s.width, 2000);
	cr_expect_eq(s.height, 1500);
	expect_vec3(s.camera.eye, 0, 6, -24);
	expect_vec3(s.camera.look_at, 0, 1, 0);
	expect_vec3(s.camera.up, 0, 1, 0);
	cr_expect_eq(s.camera.fov, 40.5);
	expect_vec3(s.background, 0.05, 0.07, 0.12);
	expect_vec3(s.ambient, 0.1, 0.1, 0.1);
	cr_expect_eq(s.max_depth, 7);
	cr_expect_eq(s.epsilon, 1e-3);

	/* glass, the sphere's inline material, the plane's; no default. */
	cr_assert_eq(s.material_count, 3);
	m = &s.materials[0];
	expect_vec3(m->color, 1, 1, 1);
	cr_expect_eq(m->ambient, 0.5);
	cr_expect_eq(m->diffuse, 0.05);
	cr_expect_eq(m->specular, 0.8);
	cr_expect_eq(m->shininess, 200);
	cr_expect_eq(m->reflect, 0.1);
	cr_expect_eq(m->transmit, 0.85);
	cr_expect_eq(m->ior, 1.5);
	m = &s.materials[1];
	expect_vec3(m->color, 0.9, 0.2, 0.2);
	cr_expect_eq(m->diffuse, 0.7, "inline materials take the defaults");
	cr_expect_eq(m->reflect, 0);
	m = &s.materials[2];
	expect_vec3(m->color, 0.9, 0.9, 0.9);
	cr_expect_eq(m->reflect, 0.3);
	cr_expect_eq(m->shininess, 32);

	cr_assert_eq(s.light_count, 1);
	expect_vec3(s.lights[0].position, -10, 20, -10);
	expect_vec3(s.lights[0].color, 0.8, 0.8, 0.8);

	cr_assert_eq(s.sphere_count, 2);
	expect_vec3(s.spheres[0].center, 0, 1, 0);
	cr_expect_eq(s.spheres[0].radius, 1);
	cr_expect_eq(s.spheres[0].material, 0);
	expect_vec3(s.spheres[1].center, 2, 1, 1);
	cr_expect_eq(s.spheres[1].radius, 1.5);
	cr_expect_eq(s.spheres[1].material, 1);

	cr_assert_eq(s.plane_count, 1);
	expect_vec3(s.planes[0].point, 0, 0, 0);
	expect_vec3(s.planes[0].normal, 0, 1, 0);
	cr_expect_eq(s.planes[0].material, 2);
	cr_expect_eq(s.planes[0].has_checker, 1);
	cr_expect_eq(s.planes[0].checker_size, 2);
	expect_vec3(s.planes[0].checker_color, 0.2, 0.2, 0.2);
	scene_free(&s);
}

/* Named materials in document order (not sorted), then inline ones (spheres,
 * then planes), then one shared default; unused named ones are kept. */
Test(scene, material_resolution_order)
{
	struct scene s;

	load_ok(&s,
		SCENE(", \"materials\": {\"zinc\": {\"ior\": 3}, \"amber\": {\"ior\": 2},"
		      "\"unused\": {\"ior\": 4}},"
		      "\"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0]},"
		      "{\"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"material\": {\"ior\": 7}},"
		      "{\"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"material\": \"amber\"}],"
		      "\"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1, \"material\": "
		      "\"zinc\"},"
		      "{\"center\": [0, 0, 0], \"radius\": 1},"
		      "{\"center\": [0, 0, 0], \"radius\": 1, \"material\": {\"ior\": 5}},"
		      "{\"center\": [0, 0, 0], \"radius\": 1, \"material\": {\"ior\": 6}}]"));
	cr_assert_eq(s.material_count, 7);
	cr_expect_eq(s.materials[0].ior, 3);
	cr_expect_eq(s.materials[1].ior, 2);
	cr_expect_eq(s.materials[2].ior, 4);
	cr_expect_eq(s.materials[3].ior, 5);
	cr_expect_eq(s.materials[4].ior, 6);
	cr_expect_eq(s.materials[5].ior, 7);
	expect_default_material(&s.materials[6]);

	cr_assert_eq(s.sphere_count, 4);
	cr_expect_eq(s.spheres[0].material, 0);
	cr_expect_eq(s.spheres[1].material, 6);
	cr_expect_eq(s.spheres[2].material, 3);
	cr_expect_eq(s.spheres[3].material, 4);
	cr_assert_eq(s.plane_count, 3);
	cr_expect_eq(s.planes[0].material, 6);
	cr_expect_eq(s.planes[1].material, 5);
	cr_expect_eq(s.planes[2].material, 1);
	cr_expect_eq(s.planes[0].has_checker, 0);
	scene_free(&s);
}

Test(scene, plane_normals_are_normalised)
{
	static const struct {
		const char *normal;
		double x, y, z;
	} cases[] = {
		{"[0, 5, 0]", 0, 1, 0},
		{"[0, 0, -0.25]", 0, 0, -1},
		{"[3, 0, 4]", 0.6, 0, 0.8},
		{"[1, 1, 1]", 0.57735026918962573, 0.57735026918962573, 0.57735026918962573},
		/* Squaring these parts would underflow or overflow. */
		{"[1e-300, 0, 1e-300]", 0.70710678118654752, 0, 0.70710678118654752},
		{"[1e300, -1e300, 0]", 0.70710678118654752, -0.70710678118654752, 0},
		{"[5e-324, 0, 0]", 1, 0, 0},
	};

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		char json[256];
		struct scene s;

		snprintf(json, sizeof(json),
			 SCENE(", \"planes\": [{\"point\": [1, 2, 3], \"normal\": %s}]"),
			 cases[i].normal);
		load_ok(&s, json);
		cr_assert_eq(s.plane_count, 1);
		expect_vec3(s.planes[0].normal, cases[i].x, cases[i].y, cases[i].z);
		cr_expect_float_eq(sqrt(s.planes[0].normal[0] * s.planes[0].normal[0] +
					s.planes[0].normal[1] * s.planes[0].normal[1] +
					s.planes[0].normal[2] * s.planes[0].normal[2]),
				   1.0, 1e-15);
		expect_vec3(s.planes[0].point, 1, 2, 3);
		scene_free(&s);
	}
}

Test(scene, boundary_values_are_accepted)
{
	struct scene s;

	load_ok(&s, "{" HEADER "\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [0, 0, 1], "
		    "\"up\": [0.001, 1, 0], \"fov\": 179.9},"
		    "\"image\": {\"width\": 32768, \"height\": 1}, \"max_depth\": 0,"
		    "\"background\": [0, -0.0, 0], \"epsilon\": 1e-18,"
		    "\"materials\": {\"m\": {\"reflect\": 1, \"transmit\": 0, \"shininess\": 0,"
		    "\"ambient\": 0, \"diffuse\": 0, \"specular\": 0, \"ior\": 1e18}}}");
	cr_expect_eq(s.width, 32768);
	cr_expect_eq(s.height, 1);
	cr_expect_eq(s.max_depth, 0);
	cr_expect_eq(s.camera.fov, 179.9);
	cr_expect_eq(s.epsilon, 1e-18);
	cr_expect_eq(s.materials[0].ior, 1e18);
	cr_expect_eq(s.materials[0].reflect, 1);
	scene_free(&s);

	load_ok(&s, SCENE(", \"image\": {\"width\": 1}, \"max_depth\": 64"));
	cr_expect_eq(s.width, 1);
	cr_expect_eq(s.max_depth, 64);
	scene_free(&s);

	/* The largest and smallest magnitudes, which float holds squared. */
	load_ok(&s, "{" HEADER "\"camera\": {\"eye\": [-1e18, 0, 0], \"look_at\": [1e18, 0, 0],"
		    "\"up\": [0, 1e-18, 0]}, \"spheres\": [{\"center\": [0, 0, -1e-18], "
		    "\"radius\": 1e-18}, {\"center\": [0, 0, 0], \"radius\": 1e18}]}");
	scene_free(&s);
}

static const struct {
	const char *json;
	const char *message;
} error_cases[] = {
	/* JSON syntax: FILE:LINE:COLUMN with jansson's text. */
	{"", "t.json:1:0: '[' or '{' expected near end of file"},
	{"{\n\"a\": 1,\n}", "t.json:3:1: string or '}' expected near '}'"},
	{"{\"format\": \"rtcl-scene\",\n \"format\": \"rtcl-scene\"}",
	 "t.json:2:9: duplicate object key near '\"format\"'"},
	{"{\"epsilon\": 1e999}", "t.json:1:17: real number overflow near '1e999'"},
	{"[]", "t.json: (top level): must be an object, got an array"},
	/* Header. */
	{"{}", "t.json: format: required field is missing"},
	{"{\"format\": \"scene\"}", "t.json: format: must be \"rtcl-scene\", got \"scene\""},
	{"{\"format\": null}", "t.json: format: must be the string \"rtcl-scene\", got null"},
	{"{\"format\": \"rtcl-scene\"}", "t.json: version: required field is missing"},
	{"{\"format\": \"rtcl-scene\", \"version\": 3, \"new_thing\": 1}",
	 "t.json: version: version 3 is not supported (this rtcl reads versions 1 and 2)"},
	{"{\"format\": \"rtcl-scene\", \"version\": 0}", "t.json: version: must be 1 or 2, got 0"},
	{"{\"format\": \"rtcl-scene\", \"version\": 1.5}",
	 "t.json: version: must be an integer, got 1.5"},
	{"{\"format\": \"rtcl-scene\", \"version\": \"1\"}",
	 "t.json: version: must be an integer, got a string"},
	{SCENE(", \"spheers\": []"), "t.json: (top level): unknown key \"spheers\"; did you mean \"spheres\"?"},
	{SCENE(", \"a\\nb\": []"), "t.json: (top level): unknown key \"a\\nb\""},
	/* Image. */
	{SCENE(", \"image\": [640, 480]"), "t.json: image: must be an object, got an array"},
	{SCENE(", \"image\": {\"width\": 0}"),
	 "t.json: image.width: must be between 1 and 32768, got 0"},
	{SCENE(", \"image\": {\"width\": 40000}"),
	 "t.json: image.width: must be between 1 and 32768, got 40000"},
	{SCENE(", \"image\": {\"height\": -3}"),
	 "t.json: image.height: must be between 1 and 32768, got -3"},
	{SCENE(", \"image\": {\"width\": 2.5}"),
	 "t.json: image.width: must be an integer, got 2.5"},
	{SCENE(", \"image\": {\"height\": 480.0}"),
	 "t.json: image.height: must be an integer, got 480.0"},
	{SCENE(", \"image\": {\"width\": 9223372036854775807}"),
	 "t.json: image.width: must be between 1 and 32768, got 9223372036854775807"},
	{SCENE(", \"image\": {\"w\": 1}"), "t.json: image: unknown key \"w\""},
	/* Camera. */
	{"{" HEADER "\"image\": {}}", "t.json: camera: required field is missing"},
	{"{" HEADER "\"camera\": true}", "t.json: camera: must be an object, got true"},
	{"{" HEADER "\"camera\": {\"look_at\": [0, 0, 0]}}",
	 "t.json: camera.eye: required field is missing"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 0, 0]}}",
	 "t.json: camera.look_at: required field is missing"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [1, 0, 0], \"fov\": 0}}",
	 "t.json: camera.fov: must be > 0 and < 180, got 0"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [1, 0, 0], \"fov\": 180}}",
	 "t.json: camera.fov: must be > 0 and < 180, got 180"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [1, 0, 0], \"fov\": -45}}",
	 "t.json: camera.fov: must be > 0 and < 180, got -45"},
	{"{" HEADER "\"camera\": {\"eye\": [1, 2, 3], \"look_at\": [1, 2, 3]}}",
	 "t.json: camera.look_at: must differ from camera.eye, both are [1, 2, 3]"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 5, 0], \"look_at\": [0, 0, 0]}}",
	 "t.json: camera.up: must not be parallel to look_at - eye, got [0, 1, 0]"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [1, 2, 3], "
	 "\"up\": [-2, -4, -6]}}",
	 "t.json: camera.up: must not be parallel to look_at - eye, got [-2, -4, -6]"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [1, 0, 0], \"up\": [0, 0, 0]}}",
	 "t.json: camera.up: must be non-zero"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [1, 0, 0], \"fob\": 40}}",
	 "t.json: camera: unknown key \"fob\"; did you mean \"fov\"?"},
	/* vec3 and colours. */
	{"{" HEADER "\"camera\": {\"eye\": [0, 0], \"look_at\": [1, 0, 0]}}",
	 "t.json: camera.eye: must be an array of 3 numbers, got 2 elements"},
	{"{" HEADER "\"camera\": {\"eye\": [0], \"look_at\": [1, 0, 0]}}",
	 "t.json: camera.eye: must be an array of 3 numbers, got 1 element"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 0, 0, 0], \"look_at\": [1, 0, 0]}}",
	 "t.json: camera.eye: must be an array of 3 numbers, got 4 elements"},
	{"{" HEADER "\"camera\": {\"eye\": {}, \"look_at\": [1, 0, 0]}}",
	 "t.json: camera.eye: must be an array of 3 numbers, got an object"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [1, null, 0]}}",
	 "t.json: camera.look_at[1]: must be a number, got null"},
	{SCENE(", \"background\": [0, 0, -1]"), "t.json: background[2]: must be >= 0, got -1"},
	{SCENE(", \"ambient\": [-0.25, 0, 0]"), "t.json: ambient[0]: must be >= 0, got -0.25"},
	{SCENE(", \"ambient\": 0.1"),
	 "t.json: ambient: must be an array of 3 numbers, got a real number"},
	/* max_depth, epsilon. */
	{SCENE(", \"max_depth\": 65"), "t.json: max_depth: must be between 0 and 64, got 65"},
	{SCENE(", \"max_depth\": -1"), "t.json: max_depth: must be between 0 and 64, got -1"},
	{SCENE(", \"max_depth\": 5.5"), "t.json: max_depth: must be an integer, got 5.5"},
	{SCENE(", \"epsilon\": 0"), "t.json: epsilon: must be > 0, got 0"},
	{SCENE(", \"epsilon\": -1e-4"), "t.json: epsilon: must be > 0, got -0.0001"},
	{SCENE(", \"epsilon\": \"small\""), "t.json: epsilon: must be a number, got a string"},
	/* Materials. */
	{SCENE(", \"materials\": []"), "t.json: materials: must be an object, got an array"},
	{SCENE(", \"materials\": {\"glass\": 1}"),
	 "t.json: materials.glass: must be an object, got an integer"},
	{SCENE(", \"materials\": {\"glass\": {\"colour\": [1, 1, 1]}}"),
	 "t.json: materials.glass: unknown key \"colour\"; did you mean \"color\"?"},
	{SCENE(", \"materials\": {\"glass\": {\"reflect\": 1.5}}"),
	 "t.json: materials.glass.reflect: must be between 0 and 1, got 1.5"},
	{SCENE(", \"materials\": {\"glass\": {\"reflect\": 1.0000001}}"),
	 "t.json: materials.glass.reflect: must be between 0 and 1, got 1.0000001"},
	{SCENE(", \"materials\": {\"glass\": {\"transmit\": -0.1}}"),
	 "t.json: materials.glass.transmit: must be between 0 and 1, got -0.1"},
	{SCENE(", \"materials\": {\"glass\": {\"ior\": 0}}"),
	 "t.json: materials.glass.ior: must be > 0, got 0"},
	{SCENE(", \"materials\": {\"glass\": {\"shininess\": -1}}"),
	 "t.json: materials.glass.shininess: must be >= 0, got -1"},
	{SCENE(", \"materials\": {\"glass\": {\"ambient\": -1}}"),
	 "t.json: materials.glass.ambient: must be >= 0, got -1"},
	{SCENE(", \"materials\": {\"glass\": {\"diffuse\": -0.5}}"),
	 "t.json: materials.glass.diffuse: must be >= 0, got -0.5"},
	{SCENE(", \"materials\": {\"glass\": {\"specular\": -2}}"),
	 "t.json: materials.glass.specular: must be >= 0, got -2"},
	{SCENE(", \"materials\": {\"glass\": {\"color\": [1, 1, -1]}}"),
	 "t.json: materials.glass.color[2]: must be >= 0, got -1"},
	{SCENE(", \"materials\": {\"my glass\": {\"ior\": -1}}"),
	 "t.json: materials[\"my glass\"].ior: must be > 0, got -1"},
	{SCENE(", \"materials\": {\"glass\": {}}, \"spheres\": ["
	       "{\"center\": [0, 0, 0], \"radius\": 1, \"material\": \"glass\"},"
	       "{\"center\": [0, 0, 0], \"radius\": 1},"
	       "{\"center\": [0, 0, 0], \"radius\": 1, \"material\": \"glas\"}]"),
	 "t.json: spheres[2].material: unknown material \"glas\"; did you mean \"glass\"?"},
	{SCENE(", \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"material\": "
	       "\"floor\"}]"),
	 "t.json: planes[0].material: unknown material \"floor\""},
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1, \"material\": 2}]"),
	 "t.json: spheres[0].material: must be a material name or an object, got an integer"},
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1, \"material\": "
	       "{\"transmit\": 2}}]"),
	 "t.json: spheres[0].material.transmit: must be between 0 and 1, got 2"},
	/* Lights. */
	{SCENE(", \"lights\": {}"), "t.json: lights: must be an array, got an object"},
	{SCENE(", \"lights\": [{\"color\": [1, 1, 1]}]"),
	 "t.json: lights[0]: needs \"position\" (a point or sphere light) or \"direction\" (a directional light)"},
	{SCENE(", \"lights\": [{\"position\": [0, 0, 0], \"color\": [1, -1, 1]}]"),
	 "t.json: lights[0].color[1]: must be >= 0, got -1"},
	{SCENE(", \"lights\": [{\"position\": [0, 0, 0], \"intensity\": 1}]"),
	 "t.json: lights[0]: unknown key \"intensity\""},
	/* Spheres. */
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radus\": 1}]"),
	 "t.json: spheres[0]: unknown key \"radus\"; did you mean \"radius\"?"},
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}, {\"center\": [0, 0, 0], "
	       "\"radius\": 1}, {\"center\": [0, 0, 0], \"radius\": 1}, {\"center\": [0, 0, 0], "
	       "\"radius\": -1}]"),
	 "t.json: spheres[3].radius: must be > 0, got -1"},
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 0}]"),
	 "t.json: spheres[0].radius: must be > 0, got 0"},
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radius\": -1e-300}]"),
	 "t.json: spheres[0].radius: must be > 0, got -1e-300"},
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0]}]"),
	 "t.json: spheres[0].radius: required field is missing"},
	/* Numbers that float cannot hold, or hold squared or inverted (found by
	 * the fuzzer: test/fuzz_regressions/). */
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1e-19}]"),
	 "t.json: spheres[0].radius: must be between 1e-18 and 1e+18 (rtcl computes in float), "
	 "got 1e-19"},
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 2e19}]"),
	 "t.json: spheres[0].radius: must be between 1e-18 and 1e+18 (rtcl computes in float), "
	 "got 2e+19"},
	{SCENE(", \"spheres\": [{\"center\": [0, -1e39, 0], \"radius\": 1}]"),
	 "t.json: spheres[0].center[1]: must be 0 or between 1e-18 and 1e+18 in magnitude (rtcl "
	 "computes in float), got -1e+39"},
	/* A nonzero number that reads as 0 or a denormal where a positive one is
	 * required is named as written, not as "got 0". */
	{SCENE(", \"epsilon\": 1e-320"), "t.json: epsilon: must be between 1e-18 and 1e+18 (rtcl "
					 "computes in float), got 1e-320, which underflows to 0"},
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1e-400}]"),
	 "t.json: spheres[0].radius: must be between 1e-18 and 1e+18 (rtcl computes in float), "
	 "got 1e-400, which underflows to 0"},
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 0.0}, {\"center\": [0, 0, 0], "
	       "\"radius\": 1e-400}]"),
	 "t.json: spheres[0].radius: must be > 0, got 0"},
	/* The walk pairs numbers with their text past keys and strings that
	 * hold digits, quotes and e. */
	{SCENE(", \"materials\": {\"a\\\"1e-400\": {\"ior\": 2, \"color\": [0, 1e-999, 0]},"
	       " \"m\": {\"reflect\": 0.5, \"ior\": -1E-400}}"),
	 "t.json: materials.m.ior: must be between 1e-18 and 1e+18 (rtcl computes in float), got "
	 "-1E-400, which underflows to 0"},
	{SCENE(", \"materials\": {\"m\": {\"ior\": 0e-9}}"),
	 "t.json: materials.m.ior: must be > 0, got 0"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 1, -5], \"look_at\": [0, 1, 0], \"fov\": 1e-400}}",
	 "t.json: camera.fov: must be > 0 and < 180, got 1e-400, which underflows to 0"},
	{SCENE(", \"materials\": {\"glass\": {\"ior\": 1e308}}"),
	 "t.json: materials.glass.ior: must be between 1e-18 and 1e+18 (rtcl computes in float), "
	 "got 1e+308"},
	{SCENE(", \"materials\": {\"m\": {\"reflect\": 1e-30}}"),
	 "t.json: materials.m.reflect: must be 0 or between 1e-18 and 1e+18 (rtcl computes in "
	 "float), got 1e-30"},
	{SCENE(", \"background\": [1e20, 0, 0]"),
	 "t.json: background[0]: must be 0 or between 1e-18 and 1e+18 (rtcl computes in float), "
	 "got 1e+20"},
	{"{" HEADER "\"camera\": {\"eye\": [-1e308, 0, 0], \"look_at\": [1e308, 0, 0]}}",
	 "t.json: camera.eye[0]: must be 0 or between 1e-18 and 1e+18 in magnitude (rtcl computes "
	 "in float), got -1e+308"},
	{"{" HEADER "\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [1e-320, 0, 1]}}",
	 "t.json: camera.look_at[0]: must be 0 or between 1e-18 and 1e+18 in magnitude (rtcl "
	 "computes in float), got 9.99989e-321"},
	{"{" HEADER
	 "\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [0, 0, 1], \"up\": [0, 1e-300, 0]}}",
	 "t.json: camera.up[1]: must be 0 or between 1e-18 and 1e+18 in magnitude (rtcl computes "
	 "in "
	 "float), got 1e-300"},
	{SCENE(", \"spheres\": [{\"radius\": 1}]"),
	 "t.json: spheres[0].center: required field is missing"},
	{SCENE(", \"spheres\": [{\"center\": [0, 0, 0], \"radius\": \"1\"}]"),
	 "t.json: spheres[0].radius: must be a number, got a string"},
	{SCENE(", \"spheres\": [null]"), "t.json: spheres[0]: must be an object, got null"},
	/* Planes and checkers. */
	{SCENE(", \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 0, 0]}]"),
	 "t.json: planes[0].normal: must be non-zero"},
	{SCENE(", \"planes\": [{\"point\": [0, 0, 0]}]"),
	 "t.json: planes[0].normal: required field is missing"},
	{SCENE(", \"planes\": [{\"normal\": [0, 1, 0]}]"),
	 "t.json: planes[0].point: required field is missing"},
	{SCENE(", \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"checker\": "
	       "{\"color\": [0, 0, 0]}}]"),
	 "t.json: planes[0].checker.size: required field is missing"},
	{SCENE(", \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"checker\": "
	       "{\"size\": 1}}]"),
	 "t.json: planes[0].checker.color: required field is missing"},
	{SCENE(", \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"checker\": "
	       "{\"size\": 0, \"color\": [0, 0, 0]}}]"),
	 "t.json: planes[0].checker.size: must be > 0, got 0"},
	{SCENE(", \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"checker\": "
	       "{\"size\": 1, \"color\": [0, -1, 0]}}]"),
	 "t.json: planes[0].checker.color[1]: must be >= 0, got -1"},
	{SCENE(", \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"checker\": true}]"),
	 "t.json: planes[0].checker: must be an object, got true"},
	{SCENE(", \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"checker\": "
	       "{\"size\": 1, \"color\": [0, 0, 0], \"colour2\": [1, 1, 1]}}]"),
	 "t.json: planes[0].checker: unknown key \"colour2\"; did you mean \"color\"?"},
};

Test(scene, every_error_rule_has_its_message)
{
	for (size_t i = 0; i < sizeof(error_cases) / sizeof(error_cases[0]); i++)
		load_fails(error_cases[i].json, error_cases[i].message);
}

/* A number too long to quote is described by its length. */
Test(scene, long_underflowing_number_is_described)
{
	char json[1024];
	char number[400] = "0.";

	memset(number + 2, '0', 330); /* 1e-331: below the smallest denormal */
	strcpy(number + 332, "1");
	snprintf(json, sizeof(json), SCENE(", \"epsilon\": %s"), number);
	load_fails(json, "t.json: epsilon: must be between 1e-18 and 1e+18 (rtcl computes in "
			 "float), got a 333-character number, which underflows to 0");
}

/* SCENE.md: a leading UTF-8 byte-order mark is skipped; JSON error columns
 * then count from after it, as an editor shows them. */
Test(scene, leading_byte_order_mark_is_skipped)
{
	struct scene s;

	load_ok(&s, "\xef\xbb\xbf" SCENE(", \"epsilon\": 0.5"));
	cr_expect_eq(s.epsilon, 0.5);
	scene_free(&s);
	load_fails("\xef\xbb\xbf" SCENE(", \"radius\": 1"),
		   "t.json: (top level): unknown key \"radius\"");
	load_fails("\xef\xbb\xbf[", "t.json:1:1: ']' expected near end of file");
	/* Only one, and only at the start. */
	load_fails("\xef\xbb\xbf\xef\xbb\xbf{}",
		   "t.json:1:1: '[' or '{' expected near '\xef\xbb\xbf'");
	load_fails(" \xef\xbb\xbf{}", "t.json:1:2: '[' or '{' expected near '\xef\xbb\xbf'");
}

/* A typo is reported as the typo, not as the field it hides. */
Test(scene, unknown_key_wins_over_missing_field)
{
	load_fails(SCENE(", \"spheres\": [{\"centre\": [0, 0, 0], \"radius\": 1}]"),
		   "t.json: spheres[0]: unknown key \"centre\"; did you mean \"center\"?");
}

Test(scene, message_is_truncated_safely)
{
	struct scene s;
	char err[16];

	memset(err, 'x', sizeof(err));
	cr_assert_eq(scene_load_string(&s, SCENE(", \"epsilon\": 0"), "t.json", err, sizeof(err)),
		     -1);
	cr_expect_str_eq(err, "t.json: epsilon");
	/* No buffer at all must not crash either. */
	cr_expect_eq(scene_load_string(&s, "{}", "t.json", NULL, 0), -1);
}

static char *temp_dir(void)
{
	char tmpl[] = "/tmp/rtcl_test_scene_XXXXXX";
	char *dir = mkdtemp(tmpl);

	cr_assert_not_null(dir);
	return strdup(dir);
}

static void write_file(const char *path, const char *text)
{
	FILE *f = fopen(path, "w");

	cr_assert_not_null(f, "cannot create %s", path);
	fputs(text, f);
	fclose(f);
}

Test(scene_file, loads_a_file_and_names_it)
{
	char *dir = temp_dir();
	char path[256], err[512] = "";
	struct scene s;

	snprintf(path, sizeof(path), "%s/ok.json", dir);
	write_file(path, SCENE(", \"image\": {\"width\": 320}"));
	cr_assert_eq(scene_load_file(&s, path, err, sizeof(err)), 0, "%s", err);
	cr_expect_str_eq(s.source, path);
	cr_expect_eq(s.width, 320);
	scene_free(&s);
	remove(path);
	rmdir(dir);
	free(dir);
}

Test(scene_file, file_errors)
{
	char *dir = temp_dir();
	char path[256], expected[512], err[512] = "";
	struct scene s;

	snprintf(path, sizeof(path), "%s/missing.json", dir);
	cr_expect_eq(scene_load_file(&s, path, err, sizeof(err)), -1);
	snprintf(expected, sizeof(expected), "%s: cannot open: No such file or directory", path);
	cr_expect_str_eq(err, expected);
	cr_expect_null(s.source);

	cr_expect_eq(scene_load_file(&s, dir, err, sizeof(err)), -1);
	snprintf(expected, sizeof(expected), "%s: not a regular file", dir);
	cr_expect_str_eq(err, expected);

	snprintf(path, sizeof(path), "%s/empty.json", dir);
	write_file(path, "");
	cr_expect_eq(scene_load_file(&s, path, err, sizeof(err)), -1);
	snprintf(expected, sizeof(expected), "%s:1:0: '[' or '{' expected near end of file", path);
	cr_expect_str_eq(err, expected);
	remove(path);

	snprintf(path, sizeof(path), "%s/huge.json", dir);
	write_file(path, "");
	cr_assert_eq(truncate(path, ((off_t)256 << 20) + 1), 0);
	cr_expect_eq(scene_load_file(&s, path, err, sizeof(err)), -1);
	snprintf(expected, sizeof(expected),
		 "%s: scene is 268435457 bytes, more than the limit of 268435456 bytes", path);
	cr_expect_str_eq(err, expected);
	remove(path);

	rmdir(dir);
	free(dir);
}

/* Each test/bad_scenes/NAME.json is refused with exactly the line in
 * NAME.expect, where {FILE} stands for the path given to the loader. */
Test(scene_file, bad_scenes_match_their_expect_files)
{
	const char *dir_name =
		getenv("RTCL_BAD_SCENES") ? getenv("RTCL_BAD_SCENES") : "test/bad_scenes";
	DIR *dir = opendir(dir_name);
	struct dirent *entry;
	int checked = 0;

	cr_assert_not_null(dir, "cannot open %s (run from the repository root)", dir_name);
	while ((entry = readdir(dir))) {
		char path[512], expect_path[512], line[1024], expected[1024], err[1024];
		size_t len = strlen(entry->d_name);
		const char *mark;
		struct scene s;
		FILE *f;

		if (len < 6 || strcmp(entry->d_name + len - 5, ".json") != 0)
			continue;
		snprintf(path, sizeof(path), "%s/%s", dir_name, entry->d_name);
		snprintf(expect_path, sizeof(expect_path), "%s/%.*s.expect", dir_name,
			 (int)(len - 5), entry->d_name);
		f = fopen(expect_path, "r");
		cr_assert_not_null(f, "%s has no %s", path, expect_path);
		cr_assert_not_null(fgets(line, sizeof(line), f), "%s is empty", expect_path);
		fclose(f);
		cr_assert(strchr(line, '\n'), "%s: line not terminated", expect_path);
		*strchr(line, '\n') = '\0';
		mark = strstr(line, "{FILE}");
		cr_assert_not_null(mark, "%s lacks {FILE}", expect_path);
		snprintf(expected, sizeof(expected), "%.*s%s%s", (int)(mark - line), line, path,
			 mark + 6);

		cr_expect_eq(scene_load_file(&s, path, err, sizeof(err)), -1, "%s was accepted",
			     path);
		cr_expect_str_eq(err, expected);
		checked++;
	}
	closedir(dir);
	cr_expect_geq(checked, 30, "only %d bad scenes found", checked);
}

/* ---- Version 2: meshes and inline triangles (SCENE.md) ---- */

#define SCENE2(extra) "{\"format\": \"rtcl-scene\", \"version\": 2, " CAMERA extra "}"

Test(scene_v2, inline_triangle_gets_its_geometric_normal_and_the_default_material)
{
	struct scene s;

	load_ok(&s, SCENE2(", \"triangles\": [{\"vertices\": [[0, 0, 0], [0, 2, 0], [2, 0, 0]]}]"));
	cr_assert_eq(s.triangle_count, 1);
	expect_vec3(s.triangles[0].v[1], 0, 2, 0);
	/* (v1 - v0) x (v2 - v0) = (0,2,0) x (2,0,0) = (0,0,-4) */
	for (int k = 0; k < 3; k++)
		expect_vec3(s.triangles[0].normal[k], 0, 0, -1);
	cr_expect_eq(s.triangles[0].smooth, 0);
	cr_assert_eq(s.material_count, 1);
	cr_expect_eq(s.triangles[0].material, 0);
	expect_default_material(&s.materials[0]);
	scene_free(&s);
}

/* scale, then rotate (x, then y, then z, world axes), then translate. */
Test(scene_v2, placement_is_scale_then_rotate_then_translate)
{
	struct scene s;

	load_ok(&s, SCENE2(", \"meshes\": [{\"file\": \"test/meshes/tri.stl\", \"scale\": [2, 3, "
			   "1], \"rotate\": [0, 0, 90], \"translate\": [10, 0, 0]}]"));
	cr_assert_eq(s.triangle_count, 1);
	/* (1,0,0) -> (2,0,0) -> about z by 90: (0,2,0) -> (10,2,0);
	 * (0,1,0) -> (0,3,0) -> (-3,0,0) -> (7,0,0). */
	expect_vec3(s.triangles[0].v[0], 10, 0, 0);
	expect_vec3(s.triangles[0].v[1], 10, 2, 0);
	expect_vec3(s.triangles[0].v[2], 7, 0, 0);
	/* The file's facet normal (0,0,1) stays (0,0,1) and is used, smooth. */
	cr_expect_eq(s.triangles[0].smooth, 1);
	expect_vec3(s.triangles[0].normal[0], 0, 0, 1);
	scene_free(&s);

	/* x first, then y: (1,0,0) about x stays, about y by 90 goes to (0,0,-1). */
	load_ok(&s, SCENE2(", \"meshes\": [{\"file\": \"test/meshes/tri.stl\", "
			   "\"rotate\": [90, 90, 0]}]"));
	expect_vec3(s.triangles[0].v[1], 0, 0, -1);
	/* (0,1,0) about x by 90: (0,0,1); about y by 90: (1,0,0). */
	expect_vec3(s.triangles[0].v[2], 1, 0, 0);
	scene_free(&s);
}

Test(scene_v2, gltf_node_transforms_come_before_the_placement)
{
	struct scene s;

	load_ok(&s, SCENE2(", \"meshes\": [{\"file\": \"test/meshes/nodes.gltf\", \"translate\": "
			   "[1, 0, 0], \"smooth\": false}]"));
	cr_assert_eq(s.triangle_count, 1);
	/* The nodes: scale 2, then translate (0,0,5); then ours, (1,0,0). */
	expect_vec3(s.triangles[0].v[0], 1, 0, 5);
	expect_vec3(s.triangles[0].v[1], 3, 0, 5);
	expect_vec3(s.triangles[0].v[2], 1, 2, 5);
	scene_free(&s);
}

Test(scene_v2, zero_area_triangles_of_files_are_skipped_and_counted)
{
	struct scene s;

	load_ok(&s, SCENE2(", \"meshes\": [{\"file\": \"test/meshes/degenerate.obj\"}]"));
	cr_expect_eq(s.triangle_count, 1);
	cr_expect_eq(s.skipped_triangles, 1);
	scene_free(&s);
	/* An inline one is an error that names it. */
	load_fails(SCENE2(", \"triangles\": [{\"vertices\": [[0, 0, 0], [1, 1, 1], [3, 3, 3]]}]"),
		   "t.json: triangles[0].vertices: must span a triangle of non-zero area, "
		   "got [0, 0, 0], [1, 1, 1], [3, 3, 3]");
}

/* Quads are triangulated; without normals in the file, smooth normals are
 * area-weighted over the triangles at each position (a flat quad: its own). */
Test(scene_v2, area_weighted_normals_without_file_normals)
{
	struct scene s;

	load_ok(&s, SCENE2(", \"meshes\": [{\"file\": \"test/meshes/quad.ply\"}]"));
	cr_assert_eq(s.triangle_count, 2);
	for (int t = 0; t < 2; t++) {
		cr_expect_eq(s.triangles[t].smooth, 1);
		for (int k = 0; k < 3; k++)
			expect_vec3(s.triangles[t].normal[k], 0, 0, 1);
	}
	scene_free(&s);

	/* A cube's corners: the sum over the faces that meet there leans out of
	 * the cube, along the corner's diagonal's sign in every axis. */
	load_ok(&s, SCENE2(", \"meshes\": [{\"file\": \"test/meshes/cube.obj\"}]"));
	cr_assert_eq(s.triangle_count, 12);
	for (int t = 0; t < 12; t++)
		for (int k = 0; k < 3; k++)
			for (int i = 0; i < 3; i++)
				cr_expect_gt(s.triangles[t].normal[k][i] * s.triangles[t].v[k][i],
					     0);
	scene_free(&s);
}

/* A mirroring scale reverses each triangle's vertex order, so that the
 * geometric normals of a closed mesh still point out of it. */
Test(scene_v2, mirroring_scale_keeps_normals_outward)
{
	struct scene s;

	load_ok(&s, SCENE2(", \"meshes\": [{\"file\": \"test/meshes/cube.obj\", \"scale\": [-1, 2, "
			   "1], \"smooth\": false}]"));
	cr_assert_eq(s.triangle_count, 12);
	for (int t = 0; t < 12; t++) {
		const struct scene_triangle *tri = &s.triangles[t];
		double centroid = 0;

		for (int i = 0; i < 3; i++)
			centroid +=
				tri->normal[0][i] * (tri->v[0][i] + tri->v[1][i] + tri->v[2][i]);
		cr_expect_gt(centroid, 0, "triangle %d points into the cube", t);
	}
	scene_free(&s);
}

/* Mesh files are found relative to the scene file's folder. */
Test(scene_v2, mesh_paths_are_relative_to_the_scene_file)
{
	struct scene s;
	char err[512];

	cr_assert_eq(scene_load_file(&s, "test/meshes/mesh_scene.json", err, sizeof(err)), 0, "%s",
		     err);
	cr_expect_eq(s.triangle_count, 320 + 12 + 2 + 1);
	cr_expect_eq(s.skipped_triangles, 0);
	scene_free(&s);
}

/* SCENE.md: an absolute path is used as it is, wherever the scene file is. */
Test(scene_v2, absolute_mesh_paths_are_used_as_they_are)
{
	char *dir = temp_dir(), *mesh = realpath("test/meshes/tri.stl", NULL);
	char path[256], json[1024], err[512] = "";
	struct scene s;

	cr_assert_not_null(mesh, "run from the repository root");
	snprintf(json, sizeof(json), SCENE2(", \"meshes\": [{\"file\": \"%s\"}]"), mesh);
	snprintf(path, sizeof(path), "%s/abs.json", dir);
	write_file(path, json);
	cr_assert_eq(scene_load_file(&s, path, err, sizeof(err)), 0, "%s", err);
	cr_expect_eq(s.triangle_count, 1);
	expect_vec3(s.triangles[0].v[1], 1, 0, 0);
	scene_free(&s);
	/* From a string (no folder of its own) too. */
	load_ok(&s, json);
	cr_expect_eq(s.triangle_count, 1);
	scene_free(&s);
	remove(path);
	rmdir(dir);
	free(dir);
	free(mesh);
}

Test(scene_v2, version_1_refuses_meshes_and_reads_as_before)
{
	load_fails(SCENE(", \"triangles\": []"),
		   "t.json: triangles: needs \"version\": 2 (the file says \"version\": 1)");
	load_fails(SCENE2(", \"meshes\": [{\"file\": \"test/meshes/cube.obj\", \"scale\": 0}]"),
		   "t.json: meshes[0].scale: must not be 0");
}
