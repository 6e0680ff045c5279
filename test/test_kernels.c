/* Kernel tests on tiny images, on the first OpenCL device (PoCL in CI).
 *
 * Every scheduling kernel must give the same 8-bit image as every other, write
 * every pixel exactly once and nothing outside the image (guard zones around
 * the output buffer: under PoCL an out-of-bounds write would silently corrupt
 * the host heap), and come close to the CPU reference.
 */
#include <criterion/criterion.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "device/device.h"
#include "layout/scene_block.h"
#include "output/image.h"
#include "render/block.h"
#include "render/reference.h"
#include "render/render.h"
#include "render/launch.h"
#include "render/renderer.h"
#include "scene/scene.h"

static char err[65536];

static void open_device(struct device *dev)
{
	cr_assert_eq(device_open(dev, -1, -1, err, sizeof(err)), 0, "%s", err);
}

static void load(struct scene *scene, const char *path)
{
	cr_assert_eq(scene_load_file(scene, path, err, sizeof(err)), 0, "%s", err);
}

static struct render_settings settings_for(const char *kernel, int width, int height, int wx,
					   int wy, int max_depth)
{
	struct render_settings s;

	memset(&s, 0, sizeof(s));
	s.kernel = render_find_kernel(kernel);
	cr_assert_not_null(s.kernel, "no kernel %s", kernel);
	s.workgroup[0] = wx;
	s.workgroup[1] = wy;
	s.width = width;
	s.height = height;
	s.max_depth = max_depth;
	s.repeat = 1;
	s.check_writes = 1;
	s.accel = ACCEL_BVH; /* rtcl's default; bvh_matches_brute_force checks none */
	return s;
}

/* Renders and checks that every pixel was written exactly once per pass and
 * nothing around the image was touched. Returns the image in 8 bits. */
static unsigned char *render_checked(struct device *dev, const struct scene *scene,
				     const struct render_settings *s, const char *what)
{
	struct render_result res;
	size_t pixels = (size_t)s->width * s->height;

	cr_assert_eq(render(dev, scene, s, &res, err, sizeof(err)), 0, "%s: %s", what, err);
	cr_assert(res.guards_intact, "%s: wrote outside the image", what);
	for (size_t i = 0; i < pixels; i++)
		cr_assert_eq(res.write_counts[i], (uint32_t)res.passes,
			     "%s: pixel (%zu, %zu) written %u times in %d passes", what,
			     i % s->width, i / s->width, res.write_counts[i], res.passes);

	unsigned char *bytes = malloc(pixels * 3);
	cr_assert_not_null(bytes);
	for (size_t i = 0; i < pixels * 3; i++)
		bytes[i] = image_to_8bit(res.rgb[i]);
	render_result_free(&res);
	return bytes;
}

static void expect_same_image(const unsigned char *want, const unsigned char *got, int width,
			      int height, const char *what)
{
	for (size_t i = 0; i < (size_t)width * height * 3; i++)
		cr_assert_eq(got[i], want[i],
			     "%s: pixel (%zu, %zu) channel %zu is %u, serial gave %u", what,
			     i / 3 % width, i / 3 / width, i % 3, got[i], want[i]);
}

/* Every kernel, every work-group shape, several sizes (two not divisible by
 * the shapes, and 160x96 beside 161x97, where a prototype once corrupted
 * PoCL's heap): the same image as the serial kernel. */
static void check_kernels_identical(const char *path)
{
	static const int sizes[][2] = {{61, 47}, {161, 97}, {160, 96}};
	static const int shapes[][2] = {{1, 1}, {8, 8}, {16, 4}, {32, 1}};
	static const char *const parallel[] = {"naive", "cyclic", "dynamic", "persistent"};
	struct device dev;
	struct scene scene;

	open_device(&dev);
	load(&scene, path);
	for (size_t z = 0; z < sizeof(sizes) / sizeof(sizes[0]); z++) {
		int w = sizes[z][0], h = sizes[z][1];
		char what[256];
		struct render_settings s = settings_for("serial", w, h, 1, 1, scene.max_depth);

		snprintf(what, sizeof(what), "%s serial %dx%d", path, w, h);
		unsigned char *want = render_checked(&dev, &scene, &s, what);
		for (size_t k = 0; k < 4; k++) {
			for (size_t p = 0; p < sizeof(shapes) / sizeof(shapes[0]); p++) {
				s = settings_for(parallel[k], w, h, shapes[p][0], shapes[p][1],
						 scene.max_depth);
				snprintf(what, sizeof(what), "%s %s %dx%d -w %dx%d", path,
					 parallel[k], w, h, shapes[p][0], shapes[p][1]);
				unsigned char *got = render_checked(&dev, &scene, &s, what);
				expect_same_image(want, got, w, h, what);
				free(got);
			}
		}
		/* Persistent groups: fewer than the chunks, and more. */
		for (int g = 0; g < 2; g++) {
			for (size_t k = 1; k < 4; k++) {
				s = settings_for(parallel[k], w, h, 8, 8, scene.max_depth);
				s.groups[0] = g ? 40 : 3;
				s.groups[1] = g ? 30 : 2;
				snprintf(what, sizeof(what), "%s %s %dx%d --groups %dx%d", path,
					 parallel[k], w, h, s.groups[0], s.groups[1]);
				unsigned char *got = render_checked(&dev, &scene, &s, what);
				expect_same_image(want, got, w, h, what);
				free(got);
			}
		}
		/* The persistent kernel fetching several pixels at a time. */
		s = settings_for("persistent", w, h, 16, 4, scene.max_depth);
		s.batch = 7;
		snprintf(what, sizeof(what), "%s persistent %dx%d --batch 7", path, w, h);
		unsigned char *batched = render_checked(&dev, &scene, &s, what);
		expect_same_image(want, batched, w, h, what);
		free(batched);
		free(want);
	}
	scene_free(&scene);
	device_close(&dev);
}

Test(kernels, identical_paper60, .timeout = 600)
{
	check_kernels_identical("scenes/paper60.json");
}

Test(kernels, identical_two_balls, .timeout = 600)
{
	check_kernels_identical("scenes/two_balls.json");
}

Test(kernels, identical_tir, .timeout = 600)
{
	check_kernels_identical("scenes/tir.json");
}

Test(kernels, identical_empty, .timeout = 600)
{
	check_kernels_identical("scenes/empty.json");
}

/* The double-precision reference of `scene` at max_depth and `samples`,
 * checked finite; `what` names it in failures. */
static float *reference_checked(const struct scene *scene, int width, int height, int max_depth,
				int samples, const char *what)
{
	size_t pixels = (size_t)width * height;
	float *want = malloc(pixels * 3 * sizeof(float));

	cr_assert_not_null(want);
	cr_assert_eq(reference_render_samples(scene, width, height, max_depth, samples, want), 0);
	for (size_t i = 0; i < pixels * 3; i++)
		cr_assert(isfinite(want[i]), "%s: the reference gave %g at pixel (%zu, %zu)", what,
			  (double)want[i], i / 3 % width, i / 3 / width);
	return want;
}

/* The image of `kernel` against the reference image `want` (rendered with the
 * same depth and samples): PSNR >= 40 dB and at most 0.1% of the pixels off by
 * more than 2/255. */
static void expect_kernel_near_reference(struct device *dev, const struct scene *scene,
					 const char *path, const char *kernel, int width,
					 int height, int max_depth, int samples, const float *want)
{
	size_t pixels = (size_t)width * height;
	char what[256];

	snprintf(what, sizeof(what), "%s %s depth %d spp %d", path, kernel, max_depth, samples);
	struct render_settings s = settings_for(kernel, width, height, 8, 8, max_depth);
	s.samples = samples;
	unsigned char *got = render_checked(dev, scene, &s, what);

	double squared = 0;
	size_t off = 0;
	for (size_t i = 0; i < pixels; i++) {
		int worst = 0;
		for (int c = 0; c < 3; c++) {
			int d = abs((int)got[3 * i + c] - (int)image_to_8bit(want[3 * i + c]));
			squared += (d / 255.0) * (d / 255.0);
			worst = d > worst ? d : worst;
		}
		off += worst > 2;
	}
	double mse = squared / (pixels * 3);
	double psnr = mse > 0 ? 10 * log10(1 / mse) : INFINITY;
	double off_percent = 100.0 * off / pixels;
	fprintf(stderr,
		"reference check: %s at %dx%d: PSNR %.1f dB, %.4f%% of pixels off by > 2/255\n",
		what, width, height, psnr, off_percent);
	cr_expect_geq(psnr, 40.0, "%s: PSNR %.2f dB", what, psnr);
	cr_expect_leq(off_percent, 0.1, "%s: %.4f%% of pixels off by more than 2/255", what,
		      off_percent);
	free(got);
}

/* Each of `kernels` at max_depth (< 0: the scene's) and `samples` against the
 * reference, which is rendered once for all of them. */
static void check_kernels_against_reference_spp(const char *path, const char *const *kernels,
						size_t kernel_count, int width, int height,
						int max_depth, int samples)
{
	struct device dev;
	struct scene scene;
	char what[256];

	open_device(&dev);
	load(&scene, path);
	if (max_depth < 0)
		max_depth = scene.max_depth;
	snprintf(what, sizeof(what), "%s depth %d spp %d", path, max_depth, samples);
	float *want = reference_checked(&scene, width, height, max_depth, samples, what);
	for (size_t k = 0; k < kernel_count; k++)
		expect_kernel_near_reference(&dev, &scene, path, kernels[k], width, height,
					     max_depth, samples, want);
	free(want);
	scene_free(&scene);
	device_close(&dev);
}

static void check_kernel_against_reference_spp(const char *path, const char *kernel, int width,
					       int height, int max_depth, int samples)
{
	check_kernels_against_reference_spp(path, &kernel, 1, width, height, max_depth, samples);
}

static void check_against_reference(const char *path, int width, int height)
{
	check_kernel_against_reference_spp(path, "dynamic", width, height, -1, 1);
}

/* Every kernel at max_depth 64, the deepest SCENE.md allows, on images small
 * enough for the ray trees (glass spawns two rays a bounce): the reference
 * once returned inf there (its directions drifted from unit length). The
 * reference is rendered once and compared with each kernel. */
static void check_every_kernel_at_depth_64(const char *path, int width, int height)
{
	static const char *const kernels[] = {"serial",	 "naive",      "cyclic",
					      "dynamic", "persistent", "wavefront"};
	check_kernels_against_reference_spp(path, kernels, sizeof(kernels) / sizeof(kernels[0]),
					    width, height, 64, 1);
}

/* make test's share of it: the stack walk once (the four parallel kernels
 * run its very code; kernels::identical_* hold them to serial's bytes) and
 * the wavefront, whose bounces are its own; the depth-64 programs cost 3 s
 * each unoptimised on two_balls' ray trees. kernels_slow runs all six. */
static void check_walk_and_wavefront_at_depth_64(const char *path, int width, int height)
{
	static const char *const kernels[] = {"dynamic", "wavefront"};
	check_kernels_against_reference_spp(path, kernels, sizeof(kernels) / sizeof(kernels[0]),
					    width, height, 64, 1);
}

Test(kernels, depth_64_matches_reference_two_balls, .timeout = 600)
{
	check_walk_and_wavefront_at_depth_64("scenes/two_balls.json", 8, 6);
}

Test(kernels, depth_64_matches_reference_paper60, .timeout = 600)
{
	check_walk_and_wavefront_at_depth_64("scenes/paper60.json", 16, 12);
}

Test(kernels_slow, depth_64_every_kernel_matches_reference_two_balls, .timeout = 900)
{
	check_every_kernel_at_depth_64("scenes/two_balls.json", 8, 6);
}

Test(kernels_slow, depth_64_every_kernel_matches_reference_paper60, .timeout = 600)
{
	check_every_kernel_at_depth_64("scenes/paper60.json", 16, 12);
}

Test(kernels, matches_reference_paper60, .timeout = 600)
{
	check_against_reference("scenes/paper60.json", 300, 300);
}

Test(kernels, matches_reference_two_balls, .timeout = 600)
{
	check_against_reference("scenes/two_balls.json", 320, 240);
}

Test(kernels, matches_reference_tir, .timeout = 600)
{
	check_against_reference("scenes/tir.json", 320, 240);
}

/* Glass through closed meshes (an icosphere with the file's normals, a cube
 * without, flat), a mesh with area-weighted normals, an inline triangle, a
 * sphere and a plane. */
Test(kernels, identical_mesh_scene, .timeout = 900)
{
	check_kernels_identical("test/meshes/mesh_scene.json");
}

Test(kernels, matches_reference_mesh_scene, .timeout = 600)
{
	check_against_reference("test/meshes/mesh_scene.json", 160, 120);
}

Test(kernels_slow, depth_64_matches_reference_mesh_scene, .timeout = 600)
{
	check_every_kernel_at_depth_64("test/meshes/mesh_scene.json", 8, 6);
}

/* A scene larger than one device buffer is refused with its size and the
 * limit, before anything is packed or allocated. */
Test(kernels, scene_larger_than_a_buffer_is_refused)
{
	struct device dev;
	struct scene scene;
	char want[512];

	memset(&dev, 0, sizeof(dev));
	snprintf(dev.name, sizeof(dev.name), "Tiny Device");
	struct mesh_block mesh;
	load(&scene, "test/meshes/mesh_scene.json");
	cr_assert_eq(mesh_block_build(&scene, &mesh), 0);
	size_t bytes = scene_block_bytes(&scene, &mesh, NULL);
	dev.max_alloc_size = bytes;
	cr_expect_eq(block_check_scene_fits(&dev, &scene, &mesh, NULL, err, sizeof(err)), 0, "%s",
		     err);
	dev.max_alloc_size--;
	cr_assert_eq(block_check_scene_fits(&dev, &scene, &mesh, NULL, err, sizeof(err)), -1);
	mesh_block_free(&mesh);
	snprintf(want, sizeof(want),
		 "test/meshes/mesh_scene.json: the scene (335 triangles) needs "
		 "%zu bytes of device memory, more than the limit of %zu bytes in one buffer on "
		 "Tiny Device (CL_DEVICE_MAX_MEM_ALLOC_SIZE)",
		 bytes, bytes - 1);
	cr_expect_str_eq(err, want);
	scene_free(&scene);
}

Test(kernels, matches_reference_empty, .timeout = 600)
{
	check_against_reference("scenes/empty.json", 64, 48);
}

Test(kernels, dynamic_is_stable_over_50_launches, .timeout = 600)
{
	struct device dev;
	struct scene scene;
	struct render_settings s = settings_for("dynamic", 161, 97, 8, 8, 5);

	open_device(&dev);
	load(&scene, "scenes/paper60.json");
	s.max_depth = scene.max_depth;
	unsigned char *first = render_checked(&dev, &scene, &s, "dynamic launch 1");
	for (int i = 2; i <= 50; i++) {
		char what[64];
		snprintf(what, sizeof(what), "dynamic launch %d", i);
		unsigned char *again = render_checked(&dev, &scene, &s, what);
		expect_same_image(first, again, s.width, s.height, what);
		free(again);
	}
	free(first);
	scene_free(&scene);
	device_close(&dev);
}

/* The scene read from __global memory gives the image the __local copy gives. */
Test(kernels, global_scene_matches_local, .timeout = 600)
{
	struct device dev;
	struct scene scene;

	open_device(&dev);
	load(&scene, "scenes/paper60.json");
	struct render_settings s = settings_for("dynamic", 61, 47, 8, 8, scene.max_depth);
	unsigned char *local = render_checked(&dev, &scene, &s, "__local scene");
	s.force_global_scene = 1;
	unsigned char *global = render_checked(&dev, &scene, &s, "__global scene");
	expect_same_image(local, global, s.width, s.height, "__global scene");
	free(local);
	free(global);
	scene_free(&scene);
	device_close(&dev);
}

/* --accel bvh gives brute force's image, byte for byte, in every kernel and
 * with the scene (and so the BVH) in __local or __global memory: the same
 * sphere test, ties to the lower index, boxes padded beyond rounding
 * (docs/bvh.md). The wavefront adds a pixel's rays in no fixed order
 * (atomics), so its image may differ from the stack walk's, with either
 * --accel, by 1/255 at most (wavefront_matches_the_stack_walk).
 * every_kernel_global: the __global scene in every kernel too, not only in
 * dynamic and the wavefront (the single-pass kernels read the scene through
 * the same code; each program costs about half a second to build in make
 * test, so make test leaves the others to kernels_slow). */
static void check_bvh_matches_brute_force_in(const char *path, int width, int height,
					     int every_kernel_global)
{
	static const char *const kernels[] = {"serial",	 "naive",      "cyclic",
					      "dynamic", "persistent", "wavefront"};
	struct device dev;
	struct scene scene;
	char what[256];

	open_device(&dev);
	load(&scene, path);
	struct render_settings s = settings_for("dynamic", width, height, 8, 8, scene.max_depth);
	s.accel = ACCEL_NONE;
	snprintf(what, sizeof(what), "%s --accel none", path);
	unsigned char *want = render_checked(&dev, &scene, &s, what);
	for (size_t k = 0; k < sizeof(kernels) / sizeof(kernels[0]); k++) {
		for (int global = 0; global < 2; global++) {
			if (global && !every_kernel_global && strcmp(kernels[k], "dynamic") != 0 &&
			    strcmp(kernels[k], "wavefront") != 0)
				continue;
			s = settings_for(kernels[k], width, height, 8, 8, scene.max_depth);
			s.force_global_scene = global;
			snprintf(what, sizeof(what), "%s %s --accel bvh, scene in %s", path,
				 kernels[k], global ? "__global" : "__local if it fits");
			unsigned char *got = render_checked(&dev, &scene, &s, what);
			if (s.kernel->multi_pass)
				for (size_t i = 0; i < (size_t)width * height * 3; i++)
					cr_assert_leq(abs(got[i] - want[i]), 1,
						      "%s: byte %zu is %u, brute force %u", what, i,
						      got[i], want[i]);
			else
				expect_same_image(want, got, width, height, what);
			free(got);
		}
	}
	free(want);
	scene_free(&scene);
	device_close(&dev);
}

static void check_bvh_matches_brute_force(const char *path, int width, int height)
{
	check_bvh_matches_brute_force_in(path, width, height, 0);
}

Test(kernels, bvh_matches_brute_force_paper60, .timeout = 600)
{
	check_bvh_matches_brute_force("scenes/paper60.json", 97, 61);
}

Test(kernels_slow, bvh_matches_brute_force_small_scenes, .timeout = 600)
{
	check_bvh_matches_brute_force_in("scenes/two_balls.json", 64, 48, 1);
	check_bvh_matches_brute_force_in("scenes/tir.json", 64, 48, 1);
	check_bvh_matches_brute_force_in("scenes/empty.json", 32, 24, 1);
	check_bvh_matches_brute_force_in("test/scenes/mirror_corridor.json", 24, 16, 1);
}

/* 40 pairs of coincident spheres, the red ones first in the file and the blue
 * ones after: brute force shows them red (equal distances go to the lower
 * index), and so must the BVH, whose leaf order puts 18 of the pairs blue
 * first on the device (host/layout/scene_block.c). Comparing device indices there
 * turns 298 bytes blue. */
Test(kernels, bvh_keeps_the_scene_order_for_equal_distances, .timeout = 600)
{
	check_bvh_matches_brute_force("test/scenes/coincident_spheres.json", 64, 48);
}

/* 300 random balls (tools/genscene.py --balls 300 --seed 11): a deep tree. */
Test(kernels, bvh_matches_brute_force_random300, .timeout = 600)
{
	check_bvh_matches_brute_force("test/scenes/random300.json", 160, 120);
}

/* Spheres and triangles in one hierarchy: the closed glass and mirror meshes
 * (rays inside them, ties between a mesh's triangles along shared edges). */
Test(kernels, bvh_matches_brute_force_meshes, .timeout = 900)
{
	check_bvh_matches_brute_force("test/meshes/mesh_scene.json", 96, 72);
	check_bvh_matches_brute_force("scenes/glass_mesh.json", 80, 60);
}

Test(kernels_slow, bvh_matches_brute_force_every_kernel_in_global_memory, .timeout = 900)
{
	check_bvh_matches_brute_force_in("scenes/paper60.json", 97, 61, 1);
	check_bvh_matches_brute_force_in("test/meshes/mesh_scene.json", 96, 72, 1);
	check_bvh_matches_brute_force_in("scenes/glass_mesh.json", 80, 60, 1);
}

/* Triangles flat in axis planes, a ray in the floor's plane and the middle
 * row and column of pixels with exactly zero direction components, from an
 * eye off 0 (the slab test's ∞ − ∞ case: traverse.cl, BOX_MIN_DIR), mirrored
 * by the floor. */
Test(kernels_slow, bvh_matches_brute_force_flat_triangles, .timeout = 600)
{
	check_bvh_matches_brute_force("test/scenes/flat_triangles.json", 33, 25);
}

/* One diffuse sphere of radius 1 at the origin, C = (0.8, 0.6, 0.4), ka 0.5,
 * kd 0.7, ks 0.3, shininess 2, ambient (0.1, 0.2, 0.3); one light at (3,0,5)
 * of colour (1, 0.5, 0.25); camera at (0,0,5) looking at the origin. The
 * centre pixel of a 3x3 image looks straight down the axis: it hits
 * p = (0,0,1), n = (0,0,1); L = (0.6,0,0.8), n.L = 0.8; L - d = (0.6,0,1.8),
 * (n.H)^2 = 1.8^2/3.6 = 0.9. Colour = ka C ambient + kd (n.L) C Lc +
 * ks (n.H)^2 Lc = (0.758, 0.363, 0.1835) (see test_reference.c for the sums). */
Test(kernels, analytic_centre_pixel)
{
	static const char json[] =
		"{\"format\": \"rtcl-scene\", \"version\": 1,"
		" \"image\": {\"width\": 3, \"height\": 3},"
		" \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 45},"
		" \"background\": [0.9, 0.9, 0.9], \"ambient\": [0.1, 0.2, 0.3],"
		" \"lights\": [{\"position\": [3, 0, 5], \"color\": [1, 0.5, 0.25]}],"
		" \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1, \"material\":"
		"   {\"color\": [0.8, 0.6, 0.4], \"ambient\": 0.5, \"diffuse\": 0.7,"
		"    \"specular\": 0.3, \"shininess\": 2}}]}";
	static const char *const kernels[] = {"serial", "naive", "cyclic", "dynamic", "persistent"};
	const double want[3] = {0.758, 0.363, 0.1835};
	struct device dev;
	struct scene scene;

	open_device(&dev);
	cr_assert_eq(scene_load_string(&scene, json, "analytic", err, sizeof(err)), 0, "%s", err);
	for (int k = 0; k < 5; k++) {
		struct render_settings s = settings_for(kernels[k], 3, 3, 2, 2, 5);
		struct render_result res;
		cr_assert_eq(render(&dev, &scene, &s, &res, err, sizeof(err)), 0, "%s", err);
		for (int c = 0; c < 3; c++)
			cr_expect_float_eq(res.rgb[3 * 4 + c], want[c], 2e-6,
					   "%s: centre pixel channel %d is %.7f, by hand %.7f",
					   kernels[k], c, res.rgb[3 * 4 + c], want[c]);
		render_result_free(&res);
	}
	scene_free(&scene);
	device_close(&dev);
}

/* max_depth 64, the largest SCENE.md allows, between two mirrors facing each
 * other: every ray bounces to the last level, so the ray stack (sized from the
 * depth at build time) is used to its full depth. */
Test(kernels, depth_64_between_mirrors, .timeout = 600)
{
	static const char *const kernels[] = {"naive", "cyclic", "dynamic", "persistent"};
	struct device dev;
	struct scene scene;

	open_device(&dev);
	load(&scene, "test/scenes/mirror_corridor.json");
	cr_assert_eq(scene.max_depth, 64);
	struct render_settings s = settings_for("serial", 24, 16, 1, 1, scene.max_depth);
	unsigned char *want = render_checked(&dev, &scene, &s, "serial, depth 64");
	for (int k = 0; k < 4; k++) {
		s = settings_for(kernels[k], 24, 16, 8, 8, scene.max_depth);
		unsigned char *got = render_checked(&dev, &scene, &s, kernels[k]);
		expect_same_image(want, got, 24, 16, kernels[k]);
		free(got);
	}
	free(want);
	scene_free(&scene);
	device_close(&dev);
}

Test(kernels, depth_64_matches_reference, .timeout = 600)
{
	check_against_reference("test/scenes/mirror_corridor.json", 48, 32);
}

/* The wavefront kernel adds a pixel's contributions in whatever order its rays
 * are traced, so its float sums may differ from the stack walk's in the last
 * bits (docs/wavefront.md): at most 1/255 on at most 0.01% of the pixels, over
 * every shipped scene, the awkward sizes and the work-group shapes. */
/* The wavefront against serial on the sample scenes at `size_count` of the
 * sizes: each pixel within 1/255, and at most 0.01 % of them off at all. */
static void check_wavefront_matches_the_stack_walk(int size_count)
{
	static const char *const scenes[] = {"scenes/paper60.json", "scenes/two_balls.json",
					     "scenes/tir.json", "scenes/empty.json"};
	static const int sizes[][2] = {{61, 47}, {161, 97}, {160, 96}, {400, 300}};
	static const int shapes[][2] = {{1, 1}, {8, 8}, {16, 4}, {32, 1}};
	struct device dev;
	size_t pixels = 0, differing = 0;

	open_device(&dev);
	for (int i = 0; i < 4; i++) {
		struct scene scene;
		load(&scene, scenes[i]);
		for (int z = 0; z < size_count; z++) {
			int w = sizes[z][0], h = sizes[z][1];
			char what[256];
			struct render_settings s =
				settings_for("serial", w, h, 1, 1, scene.max_depth);
			snprintf(what, sizeof(what), "%s serial %dx%d", scenes[i], w, h);
			unsigned char *want = render_checked(&dev, &scene, &s, what);
			for (int p = 0; p < 4; p++) {
				s = settings_for("wavefront", w, h, shapes[p][0], shapes[p][1],
						 scene.max_depth);
				snprintf(what, sizeof(what), "%s wavefront %dx%d -w %dx%d",
					 scenes[i], w, h, shapes[p][0], shapes[p][1]);
				unsigned char *got = render_checked(&dev, &scene, &s, what);
				for (size_t k = 0; k < (size_t)w * h; k++) {
					int worst = 0;
					for (int c = 0; c < 3; c++) {
						int d = abs(got[3 * k + c] - want[3 * k + c]);
						worst = d > worst ? d : worst;
					}
					cr_assert_leq(worst, 1, "%s: pixel %zu off by %d/255", what,
						      k, worst);
					differing += worst > 0;
				}
				pixels += (size_t)w * h;
				free(got);
			}
			free(want);
		}
		scene_free(&scene);
	}
	fprintf(stderr, "wavefront check: %zu of %zu pixels (%.4f%%) differ from serial by 1/255\n",
		differing, pixels, 100.0 * differing / pixels);
	cr_expect_leq(100.0 * differing / pixels, 0.01);
	device_close(&dev);
}

/* make test: the three small sizes (0.55 M pixels compared); the 400x300
 * one, three times that again, in kernels_slow. */
Test(kernels, wavefront_matches_the_stack_walk, .timeout = 900)
{
	check_wavefront_matches_the_stack_walk(3);
}

Test(kernels_slow, wavefront_matches_the_stack_walk_at_400x300, .timeout = 900)
{
	check_wavefront_matches_the_stack_walk(4);
}

/* A render as pieces (renderer.h): the image, per-pixel flops and write
 * counts read back after the pieces ran. */
struct pieces_result {
	unsigned char *bytes;
	uint64_t *pixel_flops;
	uint32_t *write_counts;
};

/* Renders the pieces pieces[0..count) with `kernel` in the order given and
 * checks that nothing outside the image was written. */
static struct pieces_result render_pieces(struct device *dev, const struct scene *scene,
					  const struct render_settings *s,
					  const struct rt_piece *pieces, int count,
					  const char *what)
{
	struct renderer r;
	struct render_result res;
	struct pieces_result out;
	size_t pixels = (size_t)s->width * s->height;

	cr_assert_eq(renderer_open(&r, dev, scene, s, &res, err, sizeof(err)), 0, "%s: %s", what,
		     err);
	for (int i = 0; i < count; i++) {
		struct piece_result pr;
		cr_assert_eq(renderer_piece(&r, &pieces[i], &pr, err, sizeof(err)), 0,
			     "%s: piece %d: %s", what, i, err);
		cr_assert_geq(pr.launches, 1, "%s: piece %d", what, i);
	}
	cr_assert_eq(renderer_read_back(&r, err, sizeof(err)), 0, "%s: %s", what, err);
	renderer_close(&r);
	cr_assert(res.guards_intact, "%s: wrote outside the image", what);
	out.bytes = malloc(pixels * 3);
	cr_assert_not_null(out.bytes);
	for (size_t i = 0; i < pixels * 3; i++)
		out.bytes[i] = image_to_8bit(res.rgb[i]);
	out.pixel_flops = res.pixel_flops;
	out.write_counts = res.write_counts;
	res.pixel_flops = NULL;
	res.write_counts = NULL;
	render_result_free(&res);
	return out;
}

static void pieces_free(struct pieces_result *p)
{
	free(p->bytes);
	free(p->pixel_flops);
	free(p->write_counts);
}

/* Cuts the w x h image into 4 tiles of odd sizes (split at x = sx, y = sy) or
 * into row bands of `band` rows, each over samples [begin, end) of n. Returns
 * the number of pieces. */
static int tile_pieces(struct rt_piece *out, int w, int h, int sx, int sy, int begin, int end,
		       int n)
{
	int xs[3] = {0, sx, w}, ys[3] = {0, sy, h}, count = 0;

	for (int j = 0; j < 2; j++)
		for (int i = 0; i < 2; i++)
			out[count++] = (struct rt_piece){.x0 = xs[i],
							 .y0 = ys[j],
							 .width = xs[i + 1] - xs[i],
							 .height = ys[j + 1] - ys[j],
							 .sample_begin = begin,
							 .sample_end = end,
							 .samples = n};
	return count;
}

static int band_pieces(struct rt_piece *out, int w, int h, int band, int begin, int end, int n)
{
	int count = 0;

	for (int y = 0; y < h; y += band)
		out[count++] = (struct rt_piece){.y0 = y,
						 .width = w,
						 .height = h - y < band ? h - y : band,
						 .sample_begin = begin,
						 .sample_end = end,
						 .samples = n};
	return count;
}

/* Every kernel, rendering the image as 4 odd tiles, as row bands (given
 * bottom band first, to show the order does not matter) and as bands of
 * split rows interleaved (--row-order interleave:3: bands of 4 rows dealt to
 * 3 classes, so a piece of 10 split rows ends inside a band), and with several
 * samples as tiles over the first half of the samples then bands over the
 * rest, gives the serial kernel's whole-image render: the same bytes (the
 * wavefront within its documented 1/255), the same flops per pixel, and every
 * pixel written once per piece that covers it. */
static void check_pieces(const char *path, int w, int h, int samples)
{
	static const char *const kernels[] = {"serial",	 "naive",      "cyclic",
					      "dynamic", "persistent", "wavefront"};
	struct device dev;
	struct scene scene;
	struct rt_piece pieces[64];

	open_device(&dev);
	load(&scene, path);
	struct render_settings s = settings_for("serial", w, h, 1, 1, scene.max_depth);
	s.samples = samples;
	s.count_flops = 1;
	struct pieces_result want = render_pieces(
		&dev, &scene, &s, (struct rt_piece[]){renderer_whole_image(&s, 0, samples)}, 1,
		"serial, whole image");
	for (int k = 0; k < 6; k++) {
		for (int layout = 0; layout < 4; layout++) {
			char what[256];
			if (layout == 2 && samples == 1)
				continue;
			int count = layout == 1 || layout == 3
					    ? band_pieces(pieces, w, h, 10, 0, samples, samples)
					    : tile_pieces(pieces, w, h, 23, 17, 0, samples, samples);
			for (int i = 0; layout == 3 && i < count; i++)
				renderer_interleave_rows(&pieces[i], h, 4, 3);
			uint32_t writes = 1;
			if (layout == 2) { /* tiles for the first half of the samples, bands
					      for the rest */
				int half = samples / 2;
				for (int i = 0; i < count; i++)
					pieces[i].sample_end = half;
				count += band_pieces(pieces + count, w, h, 10, half, samples,
						     samples);
				writes = 2;
			}
			if (layout == 1) /* bottom band first */
				for (int i = 0; i < count / 2; i++) {
					struct rt_piece t = pieces[i];
					pieces[i] = pieces[count - 1 - i];
					pieces[count - 1 - i] = t;
				}
			s = settings_for(kernels[k], w, h, 8, 4, scene.max_depth);
			s.samples = samples;
			s.count_flops = 1;
			snprintf(what, sizeof(what), "%s %s %dx%d spp %d as %d %s", path,
				 kernels[k], w, h, samples, count,
				 layout == 3   ? "interleaved row bands"
				 : layout == 2 ? "tiles, then bands"
				 : layout      ? "row bands"
					       : "tiles");
			struct pieces_result got =
				render_pieces(&dev, &scene, &s, pieces, count, what);
			for (size_t i = 0; i < (size_t)w * h; i++) {
				cr_assert_eq(got.write_counts[i], writes,
					     "%s: pixel %zu written %u times", what, i,
					     got.write_counts[i]);
				cr_assert_eq(got.pixel_flops[i], want.pixel_flops[i],
					     "%s: pixel %zu counts %llu flops, serial %llu", what,
					     i, (unsigned long long)got.pixel_flops[i],
					     (unsigned long long)want.pixel_flops[i]);
				for (int c = 0; c < 3; c++) {
					int d = abs(got.bytes[3 * i + c] - want.bytes[3 * i + c]);
					cr_assert_leq(d, k == 5 ? 1 : 0,
						      "%s: pixel %zu channel %d off by %d/255",
						      what, i, c, d);
				}
			}
			pieces_free(&got);
		}
	}
	pieces_free(&want);
	scene_free(&scene);
	device_close(&dev);
}

Test(kernels, pieces_give_the_whole_image, .timeout = 600)
{
	check_pieces("scenes/paper60.json", 61, 47, 1);
}

/* Antialiased (RENDERING.md, "Samples per pixel"): 4 samples, pieces that
 * split both the image and the samples. */
Test(kernels, pieces_give_the_whole_image_at_4_spp, .timeout = 600)
{
	check_pieces("scenes/two_balls.json", 37, 29, 4);
}

/* A piece of split rows (--row-order interleave) writes exactly the image rows
 * rt_piece_row gives it, with the pixels the whole image has there: every
 * kernel, one piece alone (all the pieces together would hide a kernel that
 * ignored the map: they cover every row either way). The settings are
 * check_pieces's, so the programs are the ones it built. */
Test(kernels, interleaved_pieces_write_their_own_rows, .timeout = 600)
{
	static const char *const kernels[] = {"serial",	 "naive",      "cyclic",
					      "dynamic", "persistent", "wavefront"};
	const int w = 61, h = 47;
	struct device dev;
	struct scene scene;
	struct rt_piece pieces[8];

	open_device(&dev);
	load(&scene, "scenes/paper60.json");
	struct render_settings s = settings_for("serial", w, h, 1, 1, scene.max_depth);
	s.samples = 1;
	s.count_flops = 1;
	struct pieces_result want = render_pieces(
		&dev, &scene, &s, (struct rt_piece[]){renderer_whole_image(&s, 0, 1)}, 1,
		"serial, whole image");
	band_pieces(pieces, w, h, 10, 0, 1, 1);
	/* split rows 10..19: image rows 26-27, 36-39 and 4-7 */
	renderer_interleave_rows(&pieces[1], h, 4, 3);
	for (int k = 0; k < 6; k++) {
		char what[128];
		int mine[47] = {0};
		for (int v = pieces[1].y0; v < pieces[1].y0 + pieces[1].height; v++)
			mine[rt_piece_row(&pieces[1], v)] = 1;
		cr_assert_eq(mine[12], 0); /* split row 12 is not image row 12 */
		s = settings_for(kernels[k], w, h, 8, 4, scene.max_depth);
		s.samples = 1;
		s.count_flops = 1;
		snprintf(what, sizeof(what), "%s, split rows 10..19 interleaved", kernels[k]);
		struct pieces_result got = render_pieces(&dev, &scene, &s, &pieces[1], 1, what);
		for (int y = 0; y < h; y++)
			for (int x = 0; x < w; x++) {
				size_t i = (size_t)y * w + x;
				cr_assert_eq(got.write_counts[i], (uint32_t)mine[y],
					     "%s: pixel (%d, %d) written %u times", what, x, y,
					     got.write_counts[i]);
				for (int c = 0; mine[y] && c < 3; c++)
					cr_assert_leq(abs(got.bytes[3 * i + c] - want.bytes[3 * i + c]),
						      k == 5 ? 1 : 0, "%s: pixel (%d, %d)", what, x,
						      y);
			}
		pieces_free(&got);
	}
	pieces_free(&want);
	scene_free(&scene);
	device_close(&dev);
}

/* Every kernel at 7 samples per pixel, in one pass and in passes of 3, 3 and
 * 1 samples: the same bytes as the serial kernel in one pass (the wavefront
 * within its 1/255), the same flops per pixel, each pixel written once per
 * pass. */
Test(kernels, passes_give_the_image_of_one_pass, .timeout = 600)
{
	static const char *const kernels[] = {"serial",	 "naive",      "cyclic",
					      "dynamic", "persistent", "wavefront"};
	struct device dev;
	struct scene scene;
	size_t pixels = 45 * 31;

	open_device(&dev);
	load(&scene, "scenes/paper60.json");
	struct render_settings s = settings_for("serial", 45, 31, 1, 1, scene.max_depth);
	s.samples = 7;
	unsigned char *want = render_checked(&dev, &scene, &s, "serial, one pass of 7 samples");
	for (int k = 0; k < 6; k++) {
		char what[128];
		s = settings_for(kernels[k], 45, 31, 8, 8, scene.max_depth);
		s.samples = 7;
		s.samples_per_pass = 3;
		cr_assert_eq(render_pass_samples(&s), 3);
		snprintf(what, sizeof(what), "%s, 7 samples in passes of 3", kernels[k]);
		unsigned char *got = render_checked(&dev, &scene, &s, what);
		for (size_t i = 0; i < pixels * 3; i++)
			cr_assert_leq(abs(got[i] - want[i]), k == 5 ? 1 : 0,
				      "%s: pixel %zu channel %zu is %u, serial gave %u", what,
				      i / 3, i % 3, got[i], want[i]);
		free(got);
	}
	free(want);
	scene_free(&scene);
	device_close(&dev);
}

/* Path regeneration and the fetch schemes of the persistent kernel
 * (cl/persistent.cl) on a path-traced box with glass and a conductor, its
 * samples in passes of 2: every pixel written once a pass, nothing outside
 * the image, the dynamic kernel's image. The sweep: every scheme, batches of
 * 1 and 7, work-groups of one item (a block of one fetch), a row of 32 and
 * 8x8, persistent groups fewer than the chunks and more. */
static void check_regenerated(int sweep)
{
	static const char *const fetches[] = {"item", "group", "subgroup"};
	static const int shapes[][2] = {{8, 8}, {1, 1}, {32, 1}};
	struct device dev;
	struct scene scene;
	int w = 29, h = 19;

	open_device(&dev);
	load(&scene, "test/scenes/path_box.json");
	struct render_settings s = settings_for("dynamic", w, h, 8, 8, scene.max_depth);
	s.samples = 3;
	unsigned char *want = render_checked(&dev, &scene, &s, "dynamic");
	for (int f = 0; f < 3; f++) {
		if (!sweep && f != 1)
			continue;
		for (int c = 0; c < (sweep ? 7 : 1); c++) {
			char what[128];
			int shape = c < 3 ? c : 0;
			s = settings_for("persistent", w, h, shapes[shape][0], shapes[shape][1],
					 scene.max_depth);
			s.samples = 3;
			s.samples_per_pass = 2;
			s.fetch = f == 0 ? FETCH_ITEM : f == 1 ? FETCH_GROUP : FETCH_SUBGROUP;
			s.regenerate = c != 6;
			s.batch = c == 3 ? 7 : 1;
			s.groups[0] = c == 4 ? 3 : c == 5 ? 40 : 0;
			s.groups[1] = c == 4 ? 2 : c == 5 ? 30 : 0;
			snprintf(what, sizeof(what),
				 "persistent%s --fetch %s -w %dx%d --batch %d --groups %dx%d",
				 s.regenerate ? " --regenerate" : "", fetches[f], s.workgroup[0],
				 s.workgroup[1], s.batch, s.groups[0], s.groups[1]);
			unsigned char *got = render_checked(&dev, &scene, &s, what);
			expect_same_image(want, got, w, h, what);
			free(got);
		}
	}
	free(want);
	scene_free(&scene);
	device_close(&dev);
}

Test(kernels, regenerated_paths_write_every_pixel_once, .timeout = 600)
{
	check_regenerated(0);
}

Test(kernels_slow, regenerated_paths_every_fetch_scheme, .timeout = 900)
{
	check_regenerated(1);
}

/* The pass's sum in registers (devices without 64-bit atomics;
 * cl/sample.cl) gives the sums added in place their image, over passes. */
Test(kernels_slow, sums_in_registers_give_the_image_of_sums_in_place, .timeout = 600)
{
	struct device dev;
	struct scene scene;

	open_device(&dev);
	load(&scene, "scenes/paper60.json");
	struct render_settings s = settings_for("dynamic", 45, 31, 8, 8, scene.max_depth);
	s.samples = 7;
	s.samples_per_pass = 3;
	unsigned char *want = render_checked(&dev, &scene, &s, "dynamic, sums in place");
	setenv("RTCL_BUILD_OPTIONS", "-DRTCL_SUM_IN_REGISTERS", 1);
	unsigned char *got = render_checked(&dev, &scene, &s, "dynamic, sums in registers");
	unsetenv("RTCL_BUILD_OPTIONS");
	cr_assert_eq(memcmp(got, want, (size_t)45 * 31 * 3), 0,
		     "the sums in registers give another image");
	free(got);
	free(want);
	scene_free(&scene);
	device_close(&dev);
}

/* renderer_read_rows: a piece's pixels only, straight from the device, at
 * their places in the image or packed row after row; here a rectangle of
 * split rows under a row map (image rows 4-7, 26-27, 36-39 of split rows
 * 10..19) that starts at column 5, for dynamic and the wavefront's own
 * buffers. Each must equal the whole image read back, and nothing else may
 * be written. */
Test(kernels, read_rows_reads_a_piece_in_place_and_packed)
{
	static const char *const kernels[] = {"dynamic", "wavefront"};
	const int w = 29, h = 47;
	struct device dev;
	struct scene scene;

	open_device(&dev);
	load(&scene, "scenes/paper60.json");
	struct rt_piece piece = {.x0 = 5, .y0 = 10, .width = 19, .height = 10};
	renderer_interleave_rows(&piece, h, 4, 3);
	for (int k = 0; k < 2; k++) {
		struct render_settings s = settings_for(kernels[k], w, h, 8, 4, 5);
		struct renderer r;
		struct render_result res;
		struct piece_result out;
		struct rt_piece whole = renderer_whole_image(&s, 0, 1);
		size_t floats = 3 * (size_t)w * h;
		float *placed = malloc(floats * sizeof(float));
		float *packed = malloc(3 * (size_t)piece.width * piece.height * sizeof(float));
		cr_assert(placed && packed);
		for (size_t i = 0; i < floats; i++)
			placed[i] = -1;
		piece.samples = piece.sample_end = 1;
		cr_assert_eq(renderer_open(&r, &dev, &scene, &s, &res, err, sizeof(err)), 0, "%s",
			     err);
		cr_assert_eq(renderer_all_samples(&r, &whole, &out, err, sizeof(err)), 0, "%s", err);
		cr_assert_eq(renderer_read_rows(&r, &piece, placed, 0, err, sizeof(err)), 0, "%s",
			     err);
		cr_assert_eq(renderer_read_rows(&r, &piece, packed, 1, err, sizeof(err)), 0, "%s",
			     err);
		cr_assert_eq(renderer_read_back(&r, err, sizeof(err)), 0, "%s", err);
		renderer_close(&r);
		for (int y = 0, rows = 0; y < h; y++) {
			int v = -1;
			for (int j = piece.y0; j < piece.y0 + piece.height; j++)
				if (rt_piece_row(&piece, j) == y)
					v = j;
			rows += v >= 0;
			for (int x = 0; x < w; x++)
				for (int c = 0; c < 3; c++) {
					size_t i = 3 * ((size_t)y * w + x) + c;
					int inside = v >= 0 && x >= piece.x0 &&
						     x < piece.x0 + piece.width;
					cr_assert_eq(placed[i], inside ? res.rgb[i] : -1.0f,
						     "%s: pixel (%d, %d)", kernels[k], x, y);
					if (inside)
						cr_assert_eq(packed[3 * ((size_t)(v - piece.y0) *
									 piece.width +
								 x - piece.x0) +
								c],
							     res.rgb[i], "%s: packed pixel (%d, %d)",
							     kernels[k], x, y);
				}
			if (y == h - 1)
				cr_assert_eq(rows, piece.height);
		}
		render_result_free(&res);
		free(placed);
		free(packed);
	}
	scene_free(&scene);
	device_close(&dev);
}

/* --queues (renderer.h): the columns in parts, one per queue, launches
 * alternating. Every kernel that uses them, on 2 to 4 queues, gives the
 * same floats as on one, with every pixel written once per pass and
 * nothing outside the image; widths of 8 work-groups and more, of 2 (fewer
 * parts than queues) and of 1 (one part: the plain passes); 7 samples in
 * passes of 3, so that the parts' last launches take fewer samples. */
Test(kernels, queues_give_the_same_image)
{
	static const char *const kernels[] = {"naive", "cyclic", "dynamic", "persistent"};
	static const int sizes[][2] = {{61, 23}, {13, 9}, {7, 5}};
	struct device dev;
	struct scene scene;

	open_device(&dev);
	load(&scene, "scenes/paper60.json");
	for (int z = 0; z < 3; z++) {
		int w = sizes[z][0], h = sizes[z][1];
		for (int k = 0; k < 4; k++) {
			struct render_settings s = settings_for(kernels[k], w, h, 8, 8, 5);
			struct render_result one;
			s.samples = 7;
			s.samples_per_pass = 3;
			s.queues = 1;
			cr_assert_eq(renderer_queues(&s, &dev), 1);
			cr_assert_eq(render(&dev, &scene, &s, &one, err, sizeof(err)), 0, "%s", err);
			for (int q = 2; q <= RENDER_MAX_QUEUES; q++) {
				char what[128];
				struct render_result res;
				snprintf(what, sizeof(what), "%s %dx%d on %d queues", kernels[k], w, h,
					 q);
				s.queues = q;
				cr_assert_eq(renderer_queues(&s, &dev), q, "%s", what);
				cr_assert_eq(render(&dev, &scene, &s, &res, err, sizeof(err)), 0,
					     "%s: %s", what, err);
				cr_assert(res.guards_intact, "%s: wrote outside the image", what);
				cr_assert_eq(res.passes, 3, "%s", what);
				for (int i = 0; i < w * h; i++)
					cr_assert_eq(res.write_counts[i], 3u,
						     "%s: pixel (%d, %d) written %u times", what,
						     i % w, i / w, res.write_counts[i]);
				cr_assert(memcmp(one.rgb, res.rgb, image_float_bytes(w, h)) == 0,
					  "%s: the image differs from one queue's", what);
				cr_assert_gt(res.kernel_ms_median, 0, "%s", what);
				render_result_free(&res);
			}
			render_result_free(&one);
		}
	}
	scene_free(&scene);
	device_close(&dev);
}

/* By default (no --queues) a GPU takes two queues for a whole image of
 * several passes, four for a share of the image (a piece of several
 * devices), and one for a single pass, whose launch then keeps the kernel's
 * schedule over the whole image; --queues applies to either. (A PoCL
 * device that says it is a GPU.) */
Test(kernels, a_gpu_takes_two_queues_for_several_passes_only)
{
	struct device dev;
	struct scene scene;
	struct render_result res;

	open_device(&dev);
	dev.is_gpu = 1;
	load(&scene, "scenes/paper60.json");
	struct render_settings s = settings_for("dynamic", 40, 24, 8, 8, 5);
	s.samples = 4;
	cr_assert_eq(render(&dev, &scene, &s, &res, err, sizeof(err)), 0, "%s", err);
	cr_assert_eq(res.passes, 1);
	cr_assert_eq(res.queues, 1, "one pass: one launch");
	render_result_free(&res);
	s.samples_per_pass = 2;
	cr_assert_eq(render(&dev, &scene, &s, &res, err, sizeof(err)), 0, "%s", err);
	cr_assert_eq(res.passes, 2);
	cr_assert_eq(res.queues, RENDER_GPU_QUEUES_WHOLE, "the whole image");
	render_result_free(&res);
	struct renderer r;
	struct piece_result out;
	struct rt_piece share = renderer_rows(&s, 0, 16, 0, 4); /* 16 of the 24 rows */
	cr_assert_eq(renderer_open(&r, &dev, &scene, &s, &res, err, sizeof(err)), 0, "%s", err);
	cr_assert_eq(renderer_all_samples(&r, &share, &out, err, sizeof(err)), 0, "%s", err);
	renderer_close(&r);
	cr_assert_eq(res.queues, RENDER_GPU_QUEUES_SHARE, "a share of the image");
	cr_assert_eq(out.launches, 2 * RENDER_GPU_QUEUES_SHARE);
	render_result_free(&res);
	s.samples_per_pass = 0;
	s.queues = 3;
	cr_assert_eq(render(&dev, &scene, &s, &res, err, sizeof(err)), 0, "%s", err);
	cr_assert_eq(res.queues, 3, "--queues 3 on one pass");
	render_result_free(&res);
	scene_free(&scene);
	device_close(&dev);
}

/* A piece's kernel time on several queues: the time any of its launches
 * ran, overlaps counted once, in any order of the spans. */
Test(kernels, busy_time_is_the_union_of_the_launches)
{
	struct launch_span spans[] = {{8000000, 9000000}, {0, 4000000}, {8200000, 8500000},
				      {2000000, 6000000}, {6000000, 6000000}};

	cr_assert_float_eq(launch_busy_ms(spans, 5), 7.0, 1e-9);
	cr_assert_float_eq(launch_busy_ms(spans, 0), 0.0, 1e-9);
}

/* Which renders use several queues: a GPU by default, a CPU when asked;
 * never serial, wavefront, or the counting and recording builds. */
Test(kernels, queues_where_they_apply)
{
	struct device cpu = {.is_gpu = 0}, gpu = {.is_gpu = 1};
	struct render_settings s = settings_for("dynamic", 8, 8, 8, 8, 5);

	cr_assert_eq(renderer_queues(&s, &gpu), RENDER_GPU_QUEUES_SHARE);
	cr_assert_eq(renderer_queues(&s, &cpu), 1);
	s.queues = 3;
	cr_assert_eq(renderer_queues(&s, &cpu), 3);
	s.count_flops = 1;
	cr_assert_eq(renderer_queues(&s, &gpu), 1);
	s.count_flops = 0;
	s.record_schedule = 1;
	cr_assert_eq(renderer_queues(&s, &gpu), 1);
	static const char *const one[] = {"serial", "wavefront"};
	for (int k = 0; k < 2; k++) {
		s = settings_for(one[k], 8, 8, 8, 8, 5);
		s.queues = 2;
		cr_assert_eq(renderer_queues(&s, &gpu), 1, "%s", one[k]);
	}
}

Test(kernels, matches_reference_at_16_spp_paper60, .timeout = 600)
{
	check_kernel_against_reference_spp("scenes/paper60.json", "dynamic", 120, 90, -1, 16);
}

Test(kernels, wavefront_matches_reference_at_4_spp_tir, .timeout = 600)
{
	check_kernel_against_reference_spp("scenes/tir.json", "wavefront", 80, 60, -1, 4);
}

/* With N samples every pixel costs N samples: in the empty scene every ray
 * misses, so a sample costs what the centre ray costs (F1 flops) plus the 2
 * of its position and the 3 scalings of its colour to fixed point, and the
 * pixel the 3 products of its mean: N (F1 + 2 + 3) + 3, counted the same by
 * every kernel. */
static void check_flops_count_every_sample(const char *const *kernels, int kernel_count)
{
	static const int counts[] = {2, 5, 16};
	struct device dev;
	struct scene scene;
	struct render_result res;

	open_device(&dev);
	load(&scene, "scenes/empty.json");
	struct render_settings s = settings_for("serial", 13, 9, 1, 1, scene.max_depth);
	s.count_flops = 1;
	cr_assert_eq(render(&dev, &scene, &s, &res, err, sizeof(err)), 0, "%s", err);
	uint64_t one = res.pixel_flops[0];
	cr_assert_gt(one, 0);
	for (int i = 0; i < 13 * 9; i++)
		cr_assert_eq(res.pixel_flops[i], one);
	render_result_free(&res);
	for (int k = 0; k < kernel_count; k++)
		for (int c = 0; c < 3; c++) {
			int n = counts[c];
			uint64_t want = (uint64_t)n * (one + 2 + 3) + 3;
			s = settings_for(kernels[k], 13, 9, 4, 4, scene.max_depth);
			s.count_flops = 1;
			s.samples = n;
			s.samples_per_pass = 3;
			cr_assert_eq(render(&dev, &scene, &s, &res, err, sizeof(err)), 0, "%s",
				     err);
			for (int i = 0; i < 13 * 9; i++)
				cr_assert_eq(res.pixel_flops[i], want,
					     "%s at %d spp: pixel %d counts %llu, want %llu",
					     kernels[k], n, i,
					     (unsigned long long)res.pixel_flops[i],
					     (unsigned long long)want);
			cr_assert_eq(res.total_flops, want * 13 * 9, "%s at %d spp", kernels[k], n);
			render_result_free(&res);
		}
	scene_free(&scene);
	device_close(&dev);
}

/* dynamic and the wavefront (its own sample loop) in make test; the others,
 * twelve more programs, in make test-long. */
Test(kernels, flops_count_every_sample, .timeout = 600)
{
	static const char *const kernels[] = {"dynamic", "wavefront"};
	check_flops_count_every_sample(kernels, 2);
}

Test(kernels_slow, flops_count_every_sample_other_kernels, .timeout = 600)
{
	static const char *const kernels[] = {"serial", "naive", "cyclic", "persistent"};
	check_flops_count_every_sample(kernels, 4);
}

/* --schedule-map (docs/RENDERING.md): the instrumented build gives the same
 * image; every pixel is started once (the tickets are a permutation); every
 * group and item lies inside the NDRange; serial starts the pixels row by
 * row with its one work-item; naive's pixel (x, y) is group (x / wx, y / wy)
 * and item (x % wx, y % wy); with the samples in passes, the first pass's
 * schedule is kept. */
static void check_schedule_map(struct device *dev, const struct scene *scene, const char *kernel,
			       int samples_per_pass)
{
	const int w = 37, h = 21, wx = 8, wy = 4, samples = 4;
	struct render_settings s = settings_for(kernel, w, h, wx, wy, 5);
	struct render_result plain, mapped;
	size_t pixels = (size_t)w * h;

	s.check_writes = 0;
	s.samples = samples;
	s.samples_per_pass = samples_per_pass;
	cr_assert_eq(render(dev, scene, &s, &plain, err, sizeof(err)), 0, "%s", err);
	s.record_schedule = 1;
	cr_assert_eq(render(dev, scene, &s, &mapped, err, sizeof(err)), 0, "%s", err);
	cr_assert_not_null(mapped.schedule);
	cr_assert(memcmp(plain.rgb, mapped.rgb, image_float_bytes(w, h)) == 0,
		  "%s: the instrumented image differs", kernel);
	unsigned char *seen = calloc(pixels, 1);
	size_t groups = (size_t)mapped.groups[0] * mapped.groups[1];
	size_t items = mapped.local_size[0] * mapped.local_size[1];
	for (size_t p = 0; p < pixels; p++) {
		const uint32_t *word = mapped.schedule + RT_SCHEDULE_WORDS * p;
		uint32_t ticket = word[RT_SCHEDULE_TICKET];
		cr_assert_lt(ticket, pixels, "%s: pixel %zu has ticket %u", kernel, p, ticket);
		cr_assert_eq(seen[ticket]++, 0, "%s: ticket %u given twice", kernel, ticket);
		cr_assert_lt(word[RT_SCHEDULE_GROUP], groups, "%s: pixel %zu", kernel, p);
		cr_assert_lt(word[RT_SCHEDULE_ITEM], items, "%s: pixel %zu", kernel, p);
		int x = (int)(p % w), y = (int)(p / w);
		if (strcmp(kernel, "serial") == 0) {
			cr_assert_eq(ticket, p, "serial: pixel %zu started %u-th", p, ticket);
			cr_assert_eq(word[RT_SCHEDULE_GROUP] + word[RT_SCHEDULE_ITEM], 0);
		} else if (strcmp(kernel, "naive") == 0) {
			cr_assert_eq(word[RT_SCHEDULE_GROUP],
				     (uint32_t)((y / wy) * mapped.groups[0] + x / wx), "naive (%d, %d)", x,
				     y);
			cr_assert_eq(word[RT_SCHEDULE_ITEM], (uint32_t)((y % wy) * wx + x % wx),
				     "naive (%d, %d)", x, y);
		}
	}
	free(seen);
	render_result_free(&plain);
	render_result_free(&mapped);
}

Test(kernels, schedule_map_covers_every_pixel_once, .timeout = 600)
{
	static const char *const kernels[] = {"serial", "naive", "cyclic", "dynamic", "persistent"};
	struct device dev;
	struct scene scene;

	open_device(&dev);
	load(&scene, "scenes/two_balls.json");
	for (size_t k = 0; k < sizeof(kernels) / sizeof(kernels[0]); k++)
		check_schedule_map(&dev, &scene, kernels[k], 0);
	check_schedule_map(&dev, &scene, "naive", 1); /* four passes */
	scene_free(&scene);
	device_close(&dev);
}
