/* Replays the scene fuzzer's findings and its minimized corpus
 * (test/fuzz_scene.c, `make fuzz`), and the mesh fuzzer's findings
 * (test/fuzz_mesh.c, test/fuzz_mesh_regressions/).
 *
 * Every file in test/fuzz_regressions/ (inputs that once crashed, leaked,
 * hung or hit undefined behaviour) and test/fuzz_corpus/ (small inputs that
 * reach distinct code) is loaded as the fuzzer loads it: accepted and packed
 * into usable numbers (scene_block_check.h), or refused with one line and
 * nothing left to free. Under `make test SAN=1`
 * AddressSanitizer and UBSan watch every load.
 */
#define _POSIX_C_SOURCE 200809L

#include "layout/scene_block.h"
#include "rtcl_shared.h"
#include "scene_block_check.h"
#include "scene/mesh.h"
#include "scene/scene.h"

#include <criterion/criterion.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Reads the whole file into a NUL-terminated buffer (NUL bytes inside stay:
 * the loader sees the text up to the first one, as in the fuzzer). */
static char *read_all(const char *path)
{
	FILE *f = fopen(path, "rb");
	size_t len = 0, capacity = 4096;
	char *buf = malloc(capacity + 1);

	cr_assert_not_null(f, "cannot open %s", path);
	cr_assert_not_null(buf);
	for (;;) {
		size_t n = fread(buf + len, 1, capacity - len, f);

		len += n;
		if (len < capacity)
			break;
		capacity *= 2;
		buf = realloc(buf, capacity + 1);
		cr_assert_not_null(buf);
	}
	cr_assert(!ferror(f), "cannot read %s", path);
	fclose(f);
	buf[len] = '\0';
	return buf;
}

/* The environment map's arrays in the whole block are those
 * scene_block_env_rows makes from the scene, here in two pieces as a
 * renderer writes them, padded with zeros to 16 bytes, and the head ends
 * where they begin. */
static void expect_environment_rows(const char *path, const struct scene *s,
				    const unsigned char *whole, size_t head)
{
	const struct rt_scene *h = (const struct rt_scene *)whole;
	const struct rt_path *p = (const struct rt_path *)(whole + h->path_offset);
	const struct scene_environment *env = &s->environment;
	size_t w = (size_t)env->width, n = w * env->height, half = w * (env->height / 2);
	size_t end = p->env_column_cdf_offset + n * sizeof(float);
	rt_vec4 *texels = malloc(n * sizeof(rt_vec4));
	float *columns = malloc(n * sizeof(float));

	cr_assert(texels && columns, "out of memory");
	cr_assert_eq(p->environment, RT_ENVIRONMENT_MAP, "%s", path);
	cr_expect_eq(head, p->env_texel_offset, "%s: the head does not end at the map's texels",
		     path);
	cr_expect_eq(p->env_column_cdf_offset, p->env_texel_offset + n * sizeof(rt_vec4), "%s",
		     path);
	scene_block_env_rows(env, 0, env->height / 2, texels, columns);
	scene_block_env_rows(env, env->height / 2, env->height, texels + half, columns + half);
	cr_expect(memcmp(whole + p->env_texel_offset, texels, n * sizeof(rt_vec4)) == 0,
		  "%s: the map's texels are not scene_block_env_rows'", path);
	cr_expect(memcmp(whole + p->env_column_cdf_offset, columns, n * sizeof(float)) == 0,
		  "%s: the map's column CDFs are not scene_block_env_rows'", path);
	for (size_t i = end; i % 16; i++)
		cr_expect_eq(whole[i], 0, "%s: padding byte %zu after the map is not 0", path, i);
	free(texels);
	free(columns);
}

/* The block a renderer packs (scene_block_pack_head) is the whole block up
 * to its texels, and the whole block holds each texture's texels, from the
 * scene, where its struct rt_texture says: the renderer writes them there. */
static void expect_head_and_texels(const char *path, const struct scene *s,
				   const struct mesh_block *mesh, const struct bvh *bvh,
				   const unsigned char *whole, size_t whole_bytes)
{
	size_t bytes = 0, head = scene_block_head_bytes(whole);
	unsigned char *packed =
		scene_block_pack_head(s, mesh, bvh, s->width, s->height, s->max_depth, &bytes);
	const struct rt_scene *h = (const struct rt_scene *)whole;
	const struct rt_texture *t = (const struct rt_texture *)(whole + h->texture_offset);

	cr_assert_not_null(packed, "%s: scene_block_pack_head failed", path);
	cr_expect_eq(bytes, whole_bytes, "%s: the head says %zu bytes, the block %zu", path, bytes,
		     whole_bytes);
	cr_expect_eq(scene_block_head_bytes(packed), head, "%s", path);
	cr_expect(head <= whole_bytes && memcmp(packed, whole, head) == 0,
		  "%s: the head differs from the block's first %zu bytes", path, head);
	cr_expect_eq(h->texture_count, scene_has_textures(s) ? s->texture_count : 0, "%s", path);
	if (s->integrator == SCENE_INTEGRATOR_PATH && s->environment.rgb)
		expect_environment_rows(path, s, whole, head);
	for (rt_int i = 0; i < h->texture_count; i++) {
		cr_expect_geq(t[i].offset, head, "%s: texture %d inside the head", path, i);
		cr_expect(memcmp(whole + t[i].offset, s->textures[i].texels,
				 s->textures[i].bytes) == 0,
			  "%s: texture %d's texels are not where its header says", path, i);
	}
	free(packed);
}

/* Loads the scene document json (named path in the messages) as the
 * fuzzers do. */
static void check_load(const char *path, const char *json)
{
	char err[512] = "";
	struct scene s;

	if (scene_load_string(&s, json, path, err, sizeof(err)) == 0) {
		size_t bytes = 0;
		struct bvh bvh;
		struct mesh_block mesh;
		cr_assert_eq(bvh_build_scene(&s, BVH_TRIANGLE_COST, &bvh), 0, "%s: out of memory",
			     path);
		cr_assert_eq(mesh_block_build(&s, &mesh), 0, "%s: out of memory", path);
		/* As a GPU packs it (binary nodes), then as a CPU (four-wide). */
		for (int wide = 0; wide < 2; wide++) {
			cr_assert(!wide || bvh_widen(&bvh) == 0, "%s: out of memory", path);
			void *packed = scene_block_pack(&s, &mesh, &bvh, s.width, s.height,
							s.max_depth, &bytes);
			cr_assert_not_null(packed, "%s: scene_block_pack failed", path);
			cr_expect_gt(bytes, 0);
			cr_expect_null(scene_block_problem(packed),
				       "%s: accepted, but packs (%s nodes) with %s", path,
				       wide ? "four-wide" : "binary", scene_block_problem(packed));
			expect_head_and_texels(path, &s, &mesh, &bvh, packed, bytes);
			free(packed);
		}
		bvh_free(&bvh);
		mesh_block_free(&mesh);
		scene_free(&s);
	} else {
		cr_expect_neq(err[0], '\0', "%s: refused without a message", path);
		/* The file's fault, not the helper's (a sanitizer report in a
		 * SAN=1 build, a helper that did not run): host/scene/mesh.h. */
		cr_expect_eq(mesh_importer_failures(), 0, "%s: %s", path, err);
		cr_expect_null(strchr(err, '\n'), "%s: message of several lines: %s", path, err);
		cr_expect_null(s.source, "%s: refused scene holds memory", path);
		cr_expect_null(s.materials, "%s: refused scene holds memory", path);
		cr_expect_null(s.spheres, "%s: refused scene holds memory", path);
		cr_expect_null(s.planes, "%s: refused scene holds memory", path);
		cr_expect_null(s.lights, "%s: refused scene holds memory", path);
	}
}

static void load_cleanly(const char *path)
{
	char *json = read_all(path);

	check_load(path, json);
	free(json);
}

/* A mesh file, placed by a scene as test/fuzz_mesh.c places its inputs. */
static void load_mesh_cleanly(const char *path)
{
	char *full = realpath(path, NULL), json[2048];

	cr_assert_not_null(full, "%s: no such file", path);
	snprintf(json, sizeof(json),
		 "{\"format\": \"rtcl-scene\", \"version\": 2,"
		 " \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
		 " \"meshes\": [{\"file\": \"%s\"}]}",
		 full);
	check_load(path, json);
	free(full);
}

/* Loads every regular file in `dir_name` with load; returns how many. */
static int load_folder(const char *dir_name, void (*load)(const char *path))
{
	DIR *dir = opendir(dir_name);
	struct dirent *entry;
	int loaded = 0;

	cr_assert_not_null(dir, "cannot open %s (run from the repository root)", dir_name);
	while ((entry = readdir(dir))) {
		char path[1024];

		if (entry->d_name[0] == '.' || strcmp(entry->d_name, "README.md") == 0)
			continue;
		snprintf(path, sizeof(path), "%s/%s", dir_name, entry->d_name);
		load(path);
		loaded++;
	}
	closedir(dir);
	return loaded;
}

/* An environment map (37x5: its column CDFs end off a 16-byte boundary) is
 * left out of the head, and its arrays are scene_block_env_rows'. */
Test(fuzz, an_environment_maps_arrays_follow_the_head)
{
	static const char json[] =
		"{\"format\": \"rtcl-scene\", \"version\": 1, \"integrator\": \"path\","
		" \"camera\": {\"eye\": [0, 1, -3], \"look_at\": [0, 0, 0]},"
		" \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}]}";
	enum { W = 37, H = 5 };
	char err[512] = "";
	struct scene s;
	struct bvh bvh;
	struct mesh_block mesh;
	size_t bytes = 0;

	cr_assert_eq(scene_load_string(&s, json, "env", err, sizeof(err)), 0, "%s", err);
	cr_assert_eq(s.integrator, SCENE_INTEGRATOR_PATH);
	s.environment = (struct scene_environment){.file = strdup("map (hand-built)"),
						   .scale = 1.5,
						   .rotate = 70,
						   .width = W,
						   .height = H,
						   .rgb = malloc(3 * W * H * sizeof(float))};
	cr_assert(s.environment.file && s.environment.rgb, "out of memory");
	for (int i = 0; i < 3 * W * H; i++)
		s.environment.rgb[i] = (float)((i * 7) % 11) / 4;
	cr_assert_eq(bvh_build_scene(&s, BVH_TRIANGLE_COST, &bvh), 0, "out of memory");
	cr_assert_eq(mesh_block_build(&s, &mesh), 0, "out of memory");
	unsigned char *packed =
		scene_block_pack(&s, &mesh, &bvh, s.width, s.height, s.max_depth, &bytes);
	cr_assert_not_null(packed, "scene_block_pack failed");
	cr_expect_null(scene_block_problem(packed), "%s", scene_block_problem(packed));
	expect_head_and_texels("env", &s, &mesh, &bvh, packed, bytes);
	free(packed);
	bvh_free(&bvh);
	mesh_block_free(&mesh);
	scene_free(&s);
}

Test(fuzz, regressions_load_cleanly)
{
	int n = load_folder("test/fuzz_regressions", load_cleanly);

	cr_expect_geq(n, 1, "no inputs in test/fuzz_regressions");
}

Test(fuzz, corpus_loads_cleanly)
{
	int n = load_folder("test/fuzz_corpus", load_cleanly);

	cr_expect_geq(n, 20, "only %d inputs in test/fuzz_corpus", n);
}

/* The mesh fuzzer's findings (test/fuzz_mesh.c; its README says what each
 * is): PLY headers on which Assimp loops, a file on which it aborts (now in
 * the helper, host/scene/mesh.h), a face naming a missing vertex, and a mesh whose
 * triangles all have area 0, which once packed a NULL array. */
Test(fuzz, mesh_regressions_load_cleanly)
{
	int n = load_folder("test/fuzz_mesh_regressions", load_mesh_cleanly);

	cr_expect_geq(n, 10, "only %d inputs in test/fuzz_mesh_regressions", n);
}

/* Issue 24's mesh findings and the fuzzer's later ones (the README says what
 * each is): refused, with the words that say why. */
Test(fuzz, issue_24_mesh_files_are_refused)
{
	static const struct {
		const char *file, *why;
	} refused[] = {
		{"ply-face-count-two-billion.ply", "\"face\" records, at least 4000000017 bytes"},
		{"ply-fewer-faces-than-declared.ply", "but the file ends after 1 of them"},
		{"ply-all-area-zero.ply", "have area 0 (after placement)"},
		{"obj-all-area-zero.obj", "have area 0 (after placement)"},
		{"ply-element-line-with-count-in-name.ply",
		 "line 7 of the PLY header: an element line must be \"element NAME COUNT\""},
		{"assimp-abort-ply-header-twice.ply",
		 "line 9 of the PLY header: \"ply\" again: a header starts once"},
		{"ply-header-twice-bad-free.ply",
		 "line 9 of the PLY header: \"ply\" again: a header starts once"},
		/* Assimp's own crash (SIGSEGV in the plain helper, an
		 * AddressSanitizer report in libassimp in the sanitized one). */
		{"ply-postprocess-segv.ply", "the importer (Assimp) crashed on it"},
		/* An allocation of 32 GiB: over the memory limit in the plain
		 * helper, an AddressSanitizer out-of-memory report in the
		 * sanitized one. */
		{"ply-header-twice-huge-list.ply", "the import needed more memory than"},
	};

	for (size_t i = 0; i < sizeof(refused) / sizeof(refused[0]); i++) {
		char path[256], *full, json[2048], err[512] = "";
		struct scene s;

		snprintf(path, sizeof(path), "test/fuzz_mesh_regressions/%s", refused[i].file);
		full = realpath(path, NULL);
		cr_assert_not_null(full, "%s: no such file", path);
		snprintf(json, sizeof(json),
			 "{\"format\": \"rtcl-scene\", \"version\": 2,"
			 " \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
			 " \"meshes\": [{\"file\": \"%s\"}]}",
			 full);
		free(full);
		cr_expect_neq(scene_load_string(&s, json, path, err, sizeof(err)), 0,
			      "%s: accepted", path);
		cr_expect(strstr(err, refused[i].why) != NULL, "%s: %s", path, err);
	}
}

/* Issue 39's glTF files (the README says what each is): refused with these
 * words, or (why NULL) loaded. */
Test(fuzz, issue_39_gltf_files)
{
	static const struct {
		const char *file, *why;
	} cases[] = {
		{"gltf-index-out-of-range.gltf", "names a vertex its primitive does not have"},
		{"gltf-extension-required-unknown.gltf",
		 "requires the glTF extension \"EXT_not_a_real_one\""},
		{"gltf-json-number-overflow.gltf",
		 "its glTF JSON does not parse: line 1, column 82: real number overflow"},
		{"gltf-camera-duplicate-node-names.gltf", NULL},
		{"gltf-texture-transform.gltf", NULL},
	};

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		char path[256], *full, json[2048], err[512] = "";
		struct scene s;
		int ret;

		snprintf(path, sizeof(path), "test/fuzz_mesh_regressions/%s", cases[i].file);
		full = realpath(path, NULL);
		cr_assert_not_null(full, "%s: no such file", path);
		snprintf(json, sizeof(json),
			 "{\"format\": \"rtcl-scene\", \"version\": 2,"
			 " \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
			 " \"meshes\": [{\"file\": \"%s\"}]}",
			 full);
		free(full);
		ret = scene_load_string(&s, json, path, err, sizeof(err));
		if (!cases[i].why) {
			cr_expect_eq(ret, 0, "%s: %s", path, err);
			if (ret == 0)
				scene_free(&s);
			continue;
		}
		cr_expect_neq(ret, 0, "%s: accepted", path);
		cr_expect(strstr(err, cases[i].why) != NULL, "%s: %s", path, err);
	}
}
