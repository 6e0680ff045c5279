/* Issue 27's camera, lights and materials (docs/RENDERING.md, "The thin
 * lens", "Light samples", "Fresnel"), on tiny images: every kernel gives the
 * same image, close to the CPU reference, and the images show what the
 * features are for (the focus plane sharp and the rest blurred, penumbrae).
 */
#include <criterion/criterion.h>

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "device/device.h"
#include "output/image.h"
#include "render/reference.h"
#include "render/render.h"
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

static void load_string(struct scene *scene, const char *json)
{
	cr_assert_eq(scene_load_string(scene, json, "test.json", err, sizeof(err)), 0, "%s", err);
}

static struct render_settings settings_for(const char *kernel, int width, int height, int max_depth,
					   int samples)
{
	struct render_settings s;

	memset(&s, 0, sizeof(s));
	s.kernel = render_find_kernel(kernel);
	cr_assert_not_null(s.kernel, "no kernel %s", kernel);
	s.workgroup[0] = s.workgroup[1] = 8;
	s.width = width;
	s.height = height;
	s.max_depth = max_depth;
	s.samples = samples;
	s.repeat = 1;
	s.check_writes = 1;
	s.accel = ACCEL_BVH;
	return s;
}

/* The 8-bit image of a kernel, each pixel checked written once per pass. */
static unsigned char *render_8bit(struct device *dev, const struct scene *scene,
				  const struct render_settings *s, const char *what)
{
	struct render_result res;
	size_t pixels = (size_t)s->width * s->height;

	cr_assert_eq(render(dev, scene, s, &res, err, sizeof(err)), 0, "%s: %s", what, err);
	cr_assert(res.guards_intact, "%s: wrote outside the image", what);
	for (size_t i = 0; i < pixels; i++)
		cr_assert_eq(res.write_counts[i], (uint32_t)res.passes, "%s: pixel %zu", what, i);
	unsigned char *bytes = malloc(pixels * 3);
	cr_assert_not_null(bytes);
	for (size_t i = 0; i < pixels * 3; i++)
		bytes[i] = image_to_8bit(res.rgb[i]);
	render_result_free(&res);
	return bytes;
}

/* The reference's linear image. */
static float *reference_image(const struct scene *scene, int width, int height, int max_depth,
			      int samples)
{
	float *rgb = malloc((size_t)width * height * 3 * sizeof(float));

	cr_assert_not_null(rgb);
	cr_assert_eq(reference_render_samples(scene, width, height, max_depth, samples, rgb), 0);
	return rgb;
}

/* Every kernel the same bytes as serial (the wavefront, which adds a pixel's
 * rays in no fixed order, within 1/255), or with every_kernel false only the
 * dynamic and the wavefront (the stack walk's and the wavefront's paths; the
 * studio scene, which uses every feature at once, checks all of them, so that
 * make test compiles each kernel's program once more, not three times), and
 * serial close to the reference:
 * PSNR >= 40 dB, at most 0.5 % of the pixels off by more than 2/255 (the
 * tests of test_kernels.c allow 0.1 % on larger images; here one pixel of
 * 1200 is 0.08 %). */
static void check_kernels_and_reference(const struct scene *scene, const char *what, int width,
					int height, int samples, bool every_kernel)
{
	static const char *const every[] = {"naive", "cyclic", "dynamic", "persistent",
					    "wavefront"};
	static const char *const two[] = {"dynamic", "wavefront"};
	const char *const *kernels = every_kernel ? every : two;
	size_t kernel_count = every_kernel ? sizeof(every) / sizeof(every[0]) : 2;
	size_t pixels = (size_t)width * height;
	char name[256];
	struct device dev;

	open_device(&dev);
	struct render_settings s = settings_for("serial", width, height, scene->max_depth, samples);
	unsigned char *want = render_8bit(&dev, scene, &s, what);
	for (size_t k = 0; k < kernel_count; k++) {
		int slack = strcmp(kernels[k], "wavefront") == 0;
		snprintf(name, sizeof(name), "%s, %s", what, kernels[k]);
		s = settings_for(kernels[k], width, height, scene->max_depth, samples);
		unsigned char *got = render_8bit(&dev, scene, &s, name);
		for (size_t i = 0; i < pixels * 3; i++)
			cr_assert_leq(abs(got[i] - want[i]), slack,
				      "%s: pixel (%zu, %zu) channel %zu is %u, serial gave %u",
				      name, i / 3 % width, i / 3 / width, i % 3, got[i], want[i]);
		free(got);
	}

	float *ref = reference_image(scene, width, height, scene->max_depth, samples);
	double squared = 0;
	size_t off = 0;
	for (size_t i = 0; i < pixels; i++) {
		int worst = 0;
		for (int c = 0; c < 3; c++) {
			int d = abs((int)want[3 * i + c] - (int)image_to_8bit(ref[3 * i + c]));
			squared += (d / 255.0) * (d / 255.0);
			worst = d > worst ? d : worst;
		}
		off += worst > 2;
	}
	double mse = squared / (pixels * 3);
	double psnr = mse > 0 ? 10 * log10(1 / mse) : INFINITY;
	fprintf(stderr, "reference check: %s: PSNR %.1f dB, %zu of %zu pixels off by > 2/255\n",
		what, psnr, off, pixels);
	cr_expect_geq(psnr, 40.0, "%s: PSNR %.2f dB", what, psnr);
	cr_expect_leq(100.0 * off / pixels, 0.5, "%s: %zu pixels off by more than 2/255", what,
		      off);
	free(ref);
	free(want);
	device_close(&dev);
}

/* RENDERING.md, "More dimensions": each pair j >= 1 of N = 16 samples is a
 * (0,4,2)-net, one point in each of the 4 x 4 cells, like the pixel
 * positions; and the pairs differ from each other and from pixel to pixel. */
Test(lens_lights, sample_pairs_are_stratified_and_differ)
{
	for (int pair = 1; pair < 6; pair++) {
		int cells[16] = {0};
		double first[2], other[2];
		for (int k = 0; k < 16; k++) {
			double st[2];
			reference_sample_pair(3, 5, k, 16, pair, st);
			cr_assert(st[0] >= 0 && st[0] < 1 && st[1] >= 0 && st[1] < 1);
			cells[(int)(st[0] * 4) * 4 + (int)(st[1] * 4)]++;
		}
		for (int c = 0; c < 16; c++)
			cr_assert_eq(cells[c], 1, "pair %d: cell %d holds %d points", pair, c,
				     cells[c]);
		reference_sample_pair(3, 5, 0, 16, pair, first);
		reference_sample_pair(3, 5, 0, 16, pair + 1, other);
		cr_assert(first[0] != other[0] || first[1] != other[1], "pairs %d, %d", pair,
			  pair + 1);
		reference_sample_pair(4, 5, 0, 16, pair, other);
		cr_assert(first[0] != other[0] || first[1] != other[1], "pixels (3,5), (4,5)");
	}
}

/* A lens focused on the red ball of two_balls.json. */
static void load_thin_lens(struct scene *scene)
{
	load(scene, "scenes/two_balls.json");
	scene->camera.aperture = 0.25;
	scene->camera.focus_distance = 7.7;
}

Test(lens_lights, thin_lens_same_in_the_walk_and_wavefront_and_near_the_reference, .timeout = 600)
{
	struct scene scene;

	load_thin_lens(&scene);
	check_kernels_and_reference(&scene, "two_balls, aperture 0.25", 40, 30, 3, false);
	scene_free(&scene);
}

/* The mean squared difference between horizontal neighbours over rows
 * y0..y1 and columns x0..x1 of the reference's image: how sharp its edges
 * are there (a blur spreads a step over several pixels, which keeps the sum
 * of the differences but lowers the sum of their squares). */
static double sharpness(const float *rgb, int width, int x0, int x1, int y0, int y1)
{
	double sum = 0;

	for (int y = y0; y <= y1; y++)
		for (int x = x0; x < x1; x++)
			for (int c = 0; c < 3; c++)
				sum += pow(rgb[3 * (y * width + x + 1) + c] -
						   rgb[3 * (y * width + x) + c],
					   2);
	return sum / ((double)(y1 - y0 + 1) * (x1 - x0));
}

/* Two white balls on black, one 6 units from the eye (on the image's right:
 * looking along +z with y up, -x is to the right) and one 30 (left): focused on the near one, the
 * near one's edges stay sharp and the far one's blur; focused on the far one, the other way round.
 */
Test(lens_lights, thin_lens_keeps_the_focus_plane_sharp_and_blurs_the_rest, .timeout = 300)
{
	static const char *const json =
		"{\"format\": \"rtcl-scene\", \"version\": 1,"
		" \"camera\": {\"eye\": [0, 0, 0], \"look_at\": [0, 0, 1], \"fov\": 40},"
		" \"background\": [0, 0, 0], \"ambient\": [1, 1, 1], \"max_depth\": 0,"
		" \"spheres\": ["
		"  {\"center\": [-0.9, 0, 6], \"radius\": 0.6, \"material\": {\"diffuse\": 0}},"
		"  {\"center\": [4.5, 0, 30], \"radius\": 3, \"material\": {\"diffuse\": 0}}]}";
	const int w = 64, h = 32, n = 16;
	struct scene scene;

	load_string(&scene, json);
	float *pinhole = reference_image(&scene, w, h, 0, n);
	double near_pin = sharpness(pinhole, w, 32, 63, 8, 23);
	double far_pin = sharpness(pinhole, w, 0, 31, 8, 23);
	scene.camera.aperture = 0.3;
	for (int focus = 0; focus < 2; focus++) {
		scene.camera.focus_distance = focus ? 30 : 6;
		float *lens = reference_image(&scene, w, h, 0, n);
		double near = sharpness(lens, w, 32, 63, 8, 23) / near_pin;
		double far = sharpness(lens, w, 0, 31, 8, 23) / far_pin;
		fprintf(stderr, "focus %d: sharpness against the pinhole: near %.2f, far %.2f\n",
			focus ? 30 : 6, near, far);
		cr_expect_gt(focus ? far : near, 0.75, "focused at %d, in focus", focus ? 30 : 6);
		cr_expect_lt(focus ? near : far, 0.5, "focused at %d, out of focus",
			     focus ? 30 : 6);
		free(lens);
	}
	free(pinhole);
	scene_free(&scene);
}

/* --mpi ranks compare scene digests: the new fields are in them. */
Test(lens_lights, scene_digest_covers_the_new_fields)
{
	struct scene scene;

	load(&scene, "scenes/two_balls.json");
	unsigned long long plain = scene_digest(&scene);
	scene.camera.aperture = 0.1;
	unsigned long long lens = scene_digest(&scene);
	cr_assert_neq(lens, plain, "camera.aperture");
	scene.camera.focus_distance *= 2;
	unsigned long long focus = scene_digest(&scene);
	cr_assert_neq(focus, lens, "camera.focus_distance");
	scene.lights[0].radius = 1;
	unsigned long long radius = scene_digest(&scene);
	cr_assert_neq(radius, focus, "lights[0].radius");
	scene.lights[0].directional = 1;
	unsigned long long directional = scene_digest(&scene);
	cr_assert_neq(directional, radius, "lights[0].direction");
	scene.materials[0].fresnel = SCENE_FRESNEL_DIELECTRIC;
	cr_assert_neq(scene_digest(&scene), directional, "materials[0].fresnel");
	scene_free(&scene);
}

/* two_balls.json with its key light a sphere of radius 1.5 and its fill
 * light the sun, 4 degrees across. */
static void load_soft_lights(struct scene *scene)
{
	load(scene, "scenes/two_balls.json");
	scene->lights[0].radius = 1.5;
	scene->lights[1].directional = 1;
	scene->lights[1].direction[0] = -0.4082482904638631;
	scene->lights[1].direction[1] = -0.8164965809277261;
	scene->lights[1].direction[2] = 0.4082482904638631;
	scene->lights[1].angle = 4;
}

Test(lens_lights, soft_lights_same_in_the_walk_and_wavefront_and_near_the_reference, .timeout = 600)
{
	struct scene scene;

	load_soft_lights(&scene);
	check_kernels_and_reference(&scene, "two_balls, sphere and sun lights", 40, 30, 3, false);
	scene_free(&scene);
}

/* The pixels of a white floor, lit from above past a red ball, whose green
 * (the floor's only: the ball has none) lies strictly between 20 % and 90 %
 * of the floor's without the ball: the penumbra (the umbra keeps the ambient
 * 0.05, about 5 %). */
static int penumbra_pixels(struct scene *scene, int width, int height, int samples)
{
	float *shadowed = reference_image(scene, width, height, 0, samples);
	int count = scene->sphere_count, penumbra = 0;

	scene->sphere_count = 0;
	float *lit = reference_image(scene, width, height, 0, samples);
	scene->sphere_count = count;
	for (int i = 0; i < width * height; i++) {
		const float *s = shadowed + 3 * i, *l = lit + 3 * i;
		if (s[0] != s[1])
			continue; /* the ball */
		double share = s[1] / l[1];
		penumbra += share > 0.2 && share < 0.9;
	}
	free(lit);
	free(shadowed);
	return penumbra;
}

/* RENDERING.md, "Light samples": a point light casts a hard shadow (a
 * penumbra only where a pixel's samples straddle its edge), a sphere light a
 * soft one, wider with the radius, and so does the sun with an angle. */
Test(lens_lights, sphere_and_sun_lights_cast_penumbrae, .timeout = 300)
{
	static const char *const json =
		"{\"format\": \"rtcl-scene\", \"version\": 1,"
		" \"camera\": {\"eye\": [0, 20, 0], \"look_at\": [0, 0, 0], \"up\": [0, 0, 1],"
		"  \"fov\": 30},"
		" \"ambient\": [0.05, 0.05, 0.05], \"max_depth\": 0,"
		" \"lights\": [{\"position\": [4, 10, 0]}],"
		" \"spheres\": [{\"center\": [0, 3, 0], \"radius\": 1,"
		"  \"material\": {\"color\": [1, 0, 0], \"ambient\": 1, \"specular\": 0}}],"
		" \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0],"
		"  \"material\": {\"diffuse\": 1, \"specular\": 0}}]}";
	const int w = 48, h = 48, n = 16;
	struct scene scene;

	load_string(&scene, json);
	int hard = penumbra_pixels(&scene, w, h, n);
	scene.lights[0].radius = 0.75;
	int soft = penumbra_pixels(&scene, w, h, n);
	scene.lights[0].radius = 1.5;
	int softer = penumbra_pixels(&scene, w, h, n);
	scene.lights[0].radius = 0;
	scene.lights[0].directional = 1;
	scene.lights[0].direction[0] = -0.3713906763541037; /* (-4, -10, 0) */
	scene.lights[0].direction[1] = -0.9284766908852593;
	scene.lights[0].direction[2] = 0;
	int sun = penumbra_pixels(&scene, w, h, n);
	scene.lights[0].angle = 8;
	int wide_sun = penumbra_pixels(&scene, w, h, n);
	fprintf(stderr, "penumbra pixels: point %d, radius 0.75 %d, 1.5 %d; sun %d, 8 degrees %d\n",
		hard, soft, softer, sun, wide_sun);
	cr_expect_gt(soft, 2 * hard);
	cr_expect_gt(softer, soft);
	cr_expect_gt(wide_sun, 2 * sun + 5);
	scene_free(&scene);
}

/* scenes/studio.json, the shipped scene of all three: a lens, sphere and
 * sun lights, a Fresnel dielectric and a Fresnel conductor. */
Test(lens_lights, studio_same_in_every_kernel_and_near_the_reference, .timeout = 600)
{
	struct scene scene;

	load(&scene, "scenes/studio.json");
	check_kernels_and_reference(&scene, "studio", 40, 25, 2, true);
	scene_free(&scene);
}

/* RENDERING.md, "Fresnel", on a glass floor (kr 0, kt 1, ior 1.5) over a
 * black one, under a white sky, at depth 1: a pixel is the weight of its
 * reflected ray, what the sky gives, since the refracted ray meets black.
 * Without Fresnel that is 0; with it, F: about F0 = 0.04 looking steeply
 * down, more towards the horizon. A mirror floor (kr 1) that is a Fresnel
 * conductor of colour (1, 0.5, 0.2) reflects the sky tinted by its colour
 * looking down, and whiter towards the horizon. */
Test(lens_lights, fresnel_reflects_at_grazing_angles_and_tints_metals, .timeout = 300)
{
	static const char *const json =
		"{\"format\": \"rtcl-scene\", \"version\": 1,"
		" \"camera\": {\"eye\": [0, 1, 0], \"look_at\": [0, -1, 2], \"fov\": 60},"
		" \"background\": [1, 1, 1], \"ambient\": [0, 0, 0], \"max_depth\": 1,"
		" \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0], \"material\": {"
		"  \"color\": [1, 0.5, 0.2], \"ambient\": 0, \"diffuse\": 0, \"specular\": 0,"
		"  \"transmit\": 1, \"ior\": 1.5}},"
		"  {\"point\": [0, -1, 0], \"normal\": [0, 1, 0], \"material\": {"
		"  \"ambient\": 0, \"diffuse\": 0, \"specular\": 0}}]}";
	const int w = 9, h = 31;
	struct scene scene;

	load_string(&scene, json);
	/* The bottom row looks steeply down, the top row's rays graze the floor. */
	int steep = 3 * ((h - 1) * w + w / 2), grazing = 3 * (1 * w + w / 2);
	float *plain = reference_image(&scene, w, h, 1, 1);
	cr_assert_float_eq(plain[steep + 1], 0.0f, 1e-6, "no Fresnel: nothing reflected");
	scene.materials[0].fresnel = SCENE_FRESNEL_DIELECTRIC;
	float *glass = reference_image(&scene, w, h, 1, 1);
	fprintf(stderr, "Fresnel glass: steep %g, grazing %g\n", glass[steep + 1],
		glass[grazing + 1]);
	cr_expect(glass[steep + 1] > 0.039f && glass[steep + 1] < 0.1f, "steep: %g",
		  glass[steep + 1]);
	cr_expect_gt(glass[grazing + 1], 2 * glass[steep + 1], "grazing reflects more");

	scene.materials[0].fresnel = SCENE_FRESNEL_CONDUCTOR;
	scene.materials[0].transmit = 0;
	scene.materials[0].reflect = 1;
	float *metal = reference_image(&scene, w, h, 1, 1);
	double tint_steep = metal[steep + 2] / metal[steep];
	double tint_grazing = metal[grazing + 2] / metal[grazing];
	fprintf(stderr, "Fresnel metal: blue/red steep %g, grazing %g\n", tint_steep, tint_grazing);
	cr_expect_float_eq(metal[steep], 1.0f, 1e-6, "red: C is 1");
	cr_expect_lt(tint_steep, 0.5, "tinted head-on");
	cr_expect_gt(tint_grazing, tint_steep + 0.1, "whiter at grazing angles");
	free(plain);
	free(glass);
	free(metal);
	scene_free(&scene);
}

/* What the counting build counts on the 1x1 image of a plane seen from
 * above, every sample's ray hitting it, with one light, at depth 0. */
static uint64_t counted_flops(struct device *dev, const char *json, int samples)
{
	struct scene scene;
	struct render_result res;

	load_string(&scene, json);
	struct render_settings s = settings_for("serial", 1, 1, 0, samples);
	s.count_flops = 1;
	cr_assert_eq(render(dev, &scene, &s, &res, err, sizeof(err)), 0, "%s", err);
	uint64_t flops = res.total_flops;
	render_result_free(&res);
	scene_free(&scene);
	return flops;
}

/* The concentric disk mapping's count for pixel (0, 0)'s sample k of n in
 * pair `pair` (RENDERING.md: 4, then 7, or 8 in the third case, or nothing
 * more at the centre), from the reference's copy of the sequence: the
 * pair's values are multiples of 2^-24, so that 2s - 1 is exact in float and
 * the kernel takes the same case. */
static int disk_flops(int k, int n, int pair)
{
	double st[2];

	reference_sample_pair(0, 0, k, n, pair, st);
	double x = 2 * st[0] - 1, y = 2 * st[1] - 1;
	if (x == 0 && y == 0)
		return 4;
	return fabs(x) > fabs(y) ? 4 + 7 : 4 + 8;
}

#define FLOPS_PLANE_SCENE(CAMERA, LIGHT)                                                           \
	"{\"format\": \"rtcl-scene\", \"version\": 2,"                                             \
	" \"camera\": {\"eye\": [0, 5, 0], \"look_at\": [0, 0, 0], \"up\": [0, 0, 1],"             \
	" \"fov\": 40" CAMERA "}, \"max_depth\": 0, \"lights\": [" LIGHT "],"                      \
	" \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0]}]}"

/* RENDERING.md's flop rules for the lens and the light samples, by
 * difference from the same scene without them: per sample, the lens adds 22
 * and its disk (the pair 2, A·a and A·b 2, the offset 9, F·q 3, minus the
 * offset 3, the origin 3; its normalize replaces the pinhole's); a sphere
 * light adds 41 and its disk over a point light at its centre (w 12, the
 * frame 13, the pair 2, R·a and R·b 2, the point 12); a directional light
 * of angle > 0 adds 25 and its disk (the frame 13, the pair 2, 2, the offset
 * and its sum 12, the normalize 9, less the point light's 13 it does not
 * need). The light's pair at depth 0 is 2, the lens's 1. */
Test(lens_lights, lens_and_light_samples_count_by_the_rules, .timeout = 300)
{
	const int n = 8;
	struct device dev;
	uint64_t lens = 0, light = 0;

	for (int k = 0; k < n; k++) {
		lens += 22 + disk_flops(k, n, 1);
		light += disk_flops(k, n, 2);
	}
	open_device(&dev);
	uint64_t point = counted_flops(&dev, FLOPS_PLANE_SCENE("", "{\"position\": [1, 4, 1]}"), n);
	uint64_t with_lens =
		counted_flops(&dev,
			      FLOPS_PLANE_SCENE(", \"aperture\": 0.3, \"focus_distance\": 5",
						"{\"position\": [1, 4, 1]}"),
			      n);
	uint64_t sphere = counted_flops(
		&dev, FLOPS_PLANE_SCENE("", "{\"position\": [1, 4, 1], \"radius\": 0.5}"), n);
	uint64_t sun = counted_flops(
		&dev, FLOPS_PLANE_SCENE("", "{\"direction\": [0.1, -1, 0.2], \"angle\": 5}"), n);
	cr_assert_gt(point, 0);
	cr_expect_eq(with_lens - point, lens, "the lens: %llu more, the rules say %llu",
		     (unsigned long long)(with_lens - point), (unsigned long long)lens);
	cr_expect_eq(sphere - point, 41 * n + light,
		     "a sphere light: %llu more, the rules say %llu",
		     (unsigned long long)(sphere - point), (unsigned long long)(41 * n + light));
	cr_expect_eq(sun - point, 25 * n + light,
		     "a directional light: %llu more, the rules say %llu",
		     (unsigned long long)(sun - point), (unsigned long long)(25 * n + light));
	device_close(&dev);
}

/* The root mean square difference between two linear images. */
static double rms_difference(const float *a, const float *b, size_t values)
{
	double sum = 0;

	for (size_t i = 0; i < values; i++)
		sum += ((double)a[i] - b[i]) * ((double)a[i] - b[i]);
	return sqrt(sum / values);
}

/* Depth of field and soft shadows converge with --spp: the reference's image
 * of a lens focused on the plane and a sphere light over a ball (the
 * penumbra scene above) at 4, 16 and 64 samples comes closer at every step to
 * its image at 1024 samples, and 64 samples are at least 4 times closer than
 * 4 (the error of stratified samples falls at least as 1/sqrt(N)). The
 * kernels give the reference's image within the bounds above (the lens and
 * soft-light tests). */
Test(lens_lights, depth_of_field_and_soft_shadows_converge_with_samples, .timeout = 300)
{
	static const char *const json =
		"{\"format\": \"rtcl-scene\", \"version\": 1,"
		" \"camera\": {\"eye\": [0, 20, 0], \"look_at\": [0, 0, 0], \"up\": [0, 0, 1],"
		"  \"fov\": 30, \"aperture\": 0.6, \"focus_distance\": 20},"
		" \"ambient\": [0.05, 0.05, 0.05], \"max_depth\": 0,"
		" \"lights\": [{\"position\": [4, 10, 0], \"radius\": 1}],"
		" \"spheres\": [{\"center\": [0, 3, 0], \"radius\": 1,"
		"  \"material\": {\"color\": [1, 0, 0], \"ambient\": 1, \"specular\": 0}}],"
		" \"planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 1, 0],"
		"  \"material\": {\"diffuse\": 1, \"specular\": 0}}]}";
	const int w = 16, h = 16;
	const size_t values = (size_t)w * h * 3;
	struct scene scene;

	load_string(&scene, json);
	float *truth = reference_image(&scene, w, h, 0, 1024);
	double error[3];
	for (int i = 0; i < 3; i++) {
		float *rgb = reference_image(&scene, w, h, 0, 4 << (2 * i));
		error[i] = rms_difference(rgb, truth, values);
		free(rgb);
	}
	fprintf(stderr, "RMS error against 1024 samples: 4 %.5f, 16 %.5f, 64 %.5f\n", error[0],
		error[1], error[2]);
	cr_expect_gt(error[0], error[1]);
	cr_expect_gt(error[1], error[2]);
	cr_expect_lt(error[2], error[0] / 4);
	free(truth);
	scene_free(&scene);
}
