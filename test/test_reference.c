/* Unit tests for the CPU reference renderer (host/render/reference.cpp).
 *
 * Every expected value is worked out by hand from ../shared/docs/RENDERING.md,
 * with the arithmetic in the comments, so that these tests check the
 * reference against the spec rather than against itself.
 */
#include <criterion/criterion.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/reference.h"

#define MAX_MATERIALS 16
#define MAX_SPHERES 16
#define MAX_PLANES 4
#define MAX_LIGHTS 4

/* A scene built by hand: struct scene points into the arrays beside it, so a
 * test_scene must stay where it was initialised (never copied). */
struct test_scene {
	struct scene scene;
	struct scene_material materials[MAX_MATERIALS];
	struct scene_sphere spheres[MAX_SPHERES];
	struct scene_plane planes[MAX_PLANES];
	struct scene_light lights[MAX_LIGHTS];
};

static void set3(double out[3], double x, double y, double z)
{
	out[0] = x;
	out[1] = y;
	out[2] = z;
}

/* An empty scene: black background, no ambient light, epsilon 1e-4, camera
 * at (0,0,5) looking at the origin with a 45 degree field of view. */
static void scene_init(struct test_scene *ts)
{
	memset(ts, 0, sizeof(*ts));
	ts->scene.source = "test (hand-built)";
	ts->scene.width = 3;
	ts->scene.height = 3;
	set3(ts->scene.camera.eye, 0, 0, 5);
	set3(ts->scene.camera.look_at, 0, 0, 0);
	set3(ts->scene.camera.up, 0, 1, 0);
	ts->scene.camera.fov = 45;
	ts->scene.max_depth = 5;
	ts->scene.epsilon = 1e-4;
	ts->scene.materials = ts->materials;
	ts->scene.spheres = ts->spheres;
	ts->scene.planes = ts->planes;
	ts->scene.lights = ts->lights;
}

static void set_camera(struct test_scene *ts, double ex, double ey, double ez, double lx, double ly,
		       double lz, double ux, double uy, double uz, double fov)
{
	set3(ts->scene.camera.eye, ex, ey, ez);
	set3(ts->scene.camera.look_at, lx, ly, lz);
	set3(ts->scene.camera.up, ux, uy, uz);
	ts->scene.camera.fov = fov;
}

/* Adds a material with colour (r,g,b); returns its index. */
static int add_material(struct test_scene *ts, double r, double g, double b, double ka, double kd,
			double ks, double shininess, double kr, double kt, double ior)
{
	cr_assert_lt(ts->scene.material_count, MAX_MATERIALS);
	struct scene_material *m = &ts->materials[ts->scene.material_count];
	set3(m->color, r, g, b);
	m->ambient = ka;
	m->diffuse = kd;
	m->specular = ks;
	m->shininess = shininess;
	m->reflect = kr;
	m->transmit = kt;
	m->ior = ior;
	return ts->scene.material_count++;
}

static void add_sphere(struct test_scene *ts, double x, double y, double z, double radius,
		       int material)
{
	cr_assert_lt(ts->scene.sphere_count, MAX_SPHERES);
	struct scene_sphere *s = &ts->spheres[ts->scene.sphere_count++];
	set3(s->center, x, y, z);
	s->radius = radius;
	s->material = material;
}

/* Adds a plane through (px,py,pz) with unit normal (nx,ny,nz); returns it so
 * that a test can give it a checker. */
static struct scene_plane *add_plane(struct test_scene *ts, double px, double py, double pz,
				     double nx, double ny, double nz, int material)
{
	cr_assert_lt(ts->scene.plane_count, MAX_PLANES);
	struct scene_plane *p = &ts->planes[ts->scene.plane_count++];
	set3(p->point, px, py, pz);
	set3(p->normal, nx, ny, nz);
	p->material = material;
	return p;
}

static void add_light(struct test_scene *ts, double x, double y, double z, double r, double g,
		      double b)
{
	cr_assert_lt(ts->scene.light_count, MAX_LIGHTS);
	struct scene_light *l = &ts->lights[ts->scene.light_count++];
	set3(l->position, x, y, z);
	set3(l->color, r, g, b);
}

/* Renders the whole image and returns pixel (x, y). */
static void render_pixel(const struct test_scene *ts, int width, int height, int max_depth, int x,
			 int y, float out[3])
{
	float *rgb = malloc(sizeof(float) * 3 * (size_t)width * (size_t)height);
	cr_assert_not_null(rgb);
	int rc = reference_render(&ts->scene, width, height, max_depth, rgb);
	cr_assert_eq(rc, 0, "reference_render returned %d", rc);
	memcpy(out, rgb + 3 * ((size_t)y * (size_t)width + (size_t)x), 3 * sizeof(float));
	free(rgb);
}

static void expect_rgb(const float got[3], double r, double g, double b, double tolerance,
		       const char *what)
{
	/* The output is float, so compare with the expected value rounded to float:
	 * a tolerance of 0 then asks for the exact float. */
	const float expected[3] = {(float)r, (float)g, (float)b};
	for (int c = 0; c < 3; c++)
		cr_expect(fabs((double)got[c] - (double)expected[c]) <= tolerance,
			  "%s: channel %d is %.9g, expected %.9g (tolerance %g)", what, c,
			  (double)got[c], (double)expected[c], tolerance);
}

/* ---- (a) one diffuse sphere, worked out by hand ---- */

/* Sphere of radius 1 at the origin; C = (0.8, 0.6, 0.4), ka 0.5, kd 0.7,
 * ks 0.3, shininess 2. Ambient (0.1, 0.2, 0.3). Camera at (0,0,5) looking at
 * the origin, 3x3 image. */
static int analytic_scene(struct test_scene *ts, double shininess)
{
	scene_init(ts);
	set3(ts->scene.ambient, 0.1, 0.2, 0.3);
	set3(ts->scene.background, 0.9, 0.9, 0.9);
	int diffuse = add_material(ts, 0.8, 0.6, 0.4, 0.5, 0.7, 0.3, shininess, 0, 0, 1.5);
	add_sphere(ts, 0, 0, 0, 1, diffuse);
	add_light(ts, 3, 0, 5, 1, 0.5, 0.25);
	return diffuse;
}

Test(reference, analytic_diffuse_sphere)
{
	struct test_scene ts;
	analytic_scene(&ts, 2);

	/* Centre pixel (1,1) of 3x3: 2(1+0.5)/3 - 1 = 0 and 1 - 2(1+0.5)/3 = 0,
	 * so the ray is exactly f = (0,0,-1) from the eye (0,0,5).
	 * Hit: o - c = (0,0,5), b = -5, c = 25 - 1 = 24, disc = 1, t = 5 - 1 = 4,
	 *   p = (0,0,1), n_g = (0,0,1), dot(n_g, d) = -1: outside, n = (0,0,1).
	 * Light at (3,0,5): light - p = (3,0,4), length 5, L = (0.6, 0, 0.8);
	 *   the shadow ray leaves the sphere outwards and meets nothing.
	 *   n.L = 0.8.
	 *   L - d = (0.6, 0, 1.8), |L - d| = sqrt(3.6), n.H = 1.8 / sqrt(3.6),
	 *   (n.H)^2 = 3.24 / 3.6 = 0.9.
	 * Colour = ka C (x) ambient + kd (n.L) C (x) Lc + ks (n.H)^2 Lc:
	 *   r: 0.5*0.8*0.1 + 0.7*0.8*0.8*1.00 + 0.3*0.9*1.00 = 0.04 + 0.448 + 0.27   = 0.758
	 *   g: 0.5*0.6*0.2 + 0.7*0.8*0.6*0.50 + 0.3*0.9*0.50 = 0.06 + 0.168 + 0.135  = 0.363
	 *   b: 0.5*0.4*0.3 + 0.7*0.8*0.4*0.25 + 0.3*0.9*0.25 = 0.06 + 0.056 + 0.0675 = 0.1835
	 * The sphere is not reflective or transparent, so max_depth changes nothing. */
	float px[3];
	render_pixel(&ts, 3, 3, 0, 1, 1, px);
	expect_rgb(px, 0.758, 0.363, 0.1835, 1e-6, "centre pixel, max_depth 0");
	render_pixel(&ts, 3, 3, 5, 1, 1, px);
	expect_rgb(px, 0.758, 0.363, 0.1835, 1e-6, "centre pixel, max_depth 5");

	/* 101x101 has its centre pixel (50,50) on the axis too. */
	render_pixel(&ts, 101, 101, 5, 50, 50, px);
	expect_rgb(px, 0.758, 0.363, 0.1835, 1e-6, "centre pixel of 101x101");
}

Test(reference, shininess_zero_gives_full_specular)
{
	struct test_scene ts;
	analytic_scene(&ts, 0);

	/* As above, but (n.H)^0 = 1, so the specular term is ks Lc = 0.3 Lc:
	 *   r: 0.04 + 0.448 + 0.3*1.00 = 0.788
	 *   g: 0.06 + 0.168 + 0.3*0.50 = 0.378
	 *   b: 0.06 + 0.056 + 0.3*0.25 = 0.191 */
	float px[3];
	render_pixel(&ts, 3, 3, 5, 1, 1, px);
	expect_rgb(px, 0.788, 0.378, 0.191, 1e-6, "shininess 0");
}

Test(reference, transparent_sphere_casts_shadow)
{
	struct test_scene ts;
	analytic_scene(&ts, 2);

	/* A fully transparent sphere halfway between p = (0,0,1) and the light
	 * (3,0,5), centred on (1.5,0,3), away from the primary ray (the z axis,
	 * 1.5 from its centre). It blocks the light, leaving the ambient term:
	 *   ka C (x) ambient = (0.04, 0.06, 0.06). */
	int glass = add_material(&ts, 1, 1, 1, 0, 0, 0, 32, 0, 1, 1.5);
	add_sphere(&ts, 1.5, 0, 3, 0.5, glass);

	float px[3];
	render_pixel(&ts, 3, 3, 0, 1, 1, px);
	expect_rgb(px, 0.04, 0.06, 0.06, 1e-6, "shadowed centre pixel");
}

Test(reference, blocker_beyond_light_casts_no_shadow)
{
	struct test_scene ts;
	analytic_scene(&ts, 2);

	/* An opaque sphere beyond the light, on the far side from p = (0,0,1):
	 * centre (4.5,0,7) lies on the line p + s (0.6,0,0.8) at s = 7.5 > 5, so
	 * it only meets the shadow ray at t > distance and does not block it. */
	int opaque = add_material(&ts, 1, 1, 1, 0, 0, 0, 32, 0, 0, 1.5);
	add_sphere(&ts, 4.5, 0, 7, 1, opaque);

	float px[3];
	render_pixel(&ts, 3, 3, 0, 1, 1, px);
	expect_rgb(px, 0.758, 0.363, 0.1835, 1e-6, "blocker beyond the light");
}

/* ---- (b) rays that hit nothing ---- */

Test(reference, miss_returns_background_exactly)
{
	struct test_scene ts;
	scene_init(&ts);
	set3(ts.scene.background, 0.05, 0.07, 0.12);
	set3(ts.scene.ambient, 1, 1, 1);
	int m = add_material(&ts, 1, 1, 1, 1, 0.7, 0.3, 32, 0.5, 0.5, 1.5);
	add_sphere(&ts, 0, 0, 0, 1, m);
	add_light(&ts, 0, 10, 0, 1, 1, 1);
	/* Looking away from the sphere: every ray misses. */
	set_camera(&ts, 0, 0, 5, 0, 0, 10, 0, 1, 0, 60);

	const int width = 7, height = 5;
	float rgb[3 * 7 * 5];
	cr_assert_eq(reference_render(&ts.scene, width, height, 5, rgb), 0);
	for (int i = 0; i < width * height; i++) {
		cr_expect_eq(rgb[3 * i + 0], (float)0.05, "pixel %d red %.9g", i, rgb[3 * i]);
		cr_expect_eq(rgb[3 * i + 1], (float)0.07, "pixel %d green %.9g", i, rgb[3 * i + 1]);
		cr_expect_eq(rgb[3 * i + 2], (float)0.12, "pixel %d blue %.9g", i, rgb[3 * i + 2]);
	}
}

Test(reference, empty_scene_is_background)
{
	struct test_scene ts;
	scene_init(&ts);
	set3(ts.scene.background, 0.25, 0.5, 1.5); /* unclamped: 1.5 stays 1.5 */

	float rgb[3 * 2 * 3];
	cr_assert_eq(reference_render(&ts.scene, 2, 3, 5, rgb), 0);
	for (int i = 0; i < 2 * 3; i++)
		expect_rgb(rgb + 3 * i, 0.25, 0.5, 1.5, 0, "empty scene");
}

Test(reference, parallel_ray_misses_plane)
{
	struct test_scene ts;
	scene_init(&ts);
	set3(ts.scene.background, 0.3, 0.2, 0.1);
	set3(ts.scene.ambient, 1, 1, 1);
	int m = add_material(&ts, 1, 1, 1, 1, 0, 0, 32, 0, 0, 1.5);
	/* The plane y = 0 contains the ray: dot(n, d) = 0 is a miss. */
	add_plane(&ts, 0, 0, 0, 0, 1, 0, m);
	set_camera(&ts, 0, 0, 5, 0, 0, 0, 0, 1, 0, 45);

	float px[3];
	render_pixel(&ts, 1, 1, 5, 0, 0, px);
	expect_rgb(px, 0.3, 0.2, 0.1, 0, "ray in the plane");
}

Test(reference, invalid_arguments_are_refused)
{
	struct test_scene ts;
	scene_init(&ts);
	float rgb[3];
	cr_expect_eq(reference_render(NULL, 1, 1, 0, rgb), -1);
	cr_expect_eq(reference_render(&ts.scene, 1, 1, 0, NULL), -1);
	cr_expect_eq(reference_render(&ts.scene, 0, 1, 0, rgb), -1);
	cr_expect_eq(reference_render(&ts.scene, 1, 0, 0, rgb), -1);
	cr_expect_eq(reference_render(&ts.scene, 1, 1, -1, rgb), -1);
}

/* ---- (c) reflection ---- */

Test(reference, mirror_sphere_reflects_background)
{
	struct test_scene ts;
	scene_init(&ts);
	set3(ts.scene.background, 0.2, 0.4, 0.6);
	set3(ts.scene.ambient, 0.1, 0.1, 0.1);
	/* C = (0.5,0.5,1), ka 0.2, kd 0.6, ks 0.4, shininess 8, kr 0.5. */
	int mirror = add_material(&ts, 0.5, 0.5, 1, 0.2, 0.6, 0.4, 8, 0.5, 0, 1.5);
	add_sphere(&ts, 0, 0, 0, 1, mirror);
	add_light(&ts, 0, 0, 10, 0.5, 0.5, 0.5);

	/* Centre ray d = (0,0,-1) hits p = (0,0,1), n = (0,0,1).
	 * Light (0,0,10): L = (0,0,1), n.L = 1; L - d = (0,0,2), H = (0,0,1),
	 *   (n.H)^8 = 1.
	 * Local = 0.2 C*0.1 + 0.6*1 C*0.5 + 0.4*1*0.5 = 0.32 C + 0.2
	 *       = (0.36, 0.36, 0.52).
	 * R = d - 2 (d.n) n = (0,0,-1) + 2 (0,0,1) = (0,0,1): from
	 *   (0,0,1+eps) it meets nothing (the eye is not an object), so adds
	 *   kr * background = 0.5 (0.2,0.4,0.6) = (0.1,0.2,0.3).
	 * Pixel = (0.46, 0.56, 0.82); with max_depth 0 only the local colour. */
	float px[3];
	render_pixel(&ts, 3, 3, 1, 1, 1, px);
	expect_rgb(px, 0.46, 0.56, 0.82, 1e-6, "mirror sphere, max_depth 1");
	render_pixel(&ts, 3, 3, 0, 1, 1, px);
	expect_rgb(px, 0.36, 0.36, 0.52, 1e-6, "mirror sphere, max_depth 0");
}

Test(reference, mirror_plane_reflects_sphere)
{
	struct test_scene ts;
	scene_init(&ts);
	set3(ts.scene.background, 0.9, 0.9, 0.9);
	set3(ts.scene.ambient, 1, 1, 1);
	/* A pure mirror floor y = 0 (kr 0.5, nothing else) and a sphere whose
	 * colour is its ambient term: ka 1, C (0.2,0.4,0.6), ambient 1. */
	int mirror = add_material(&ts, 1, 1, 1, 0, 0, 0, 32, 0.5, 0, 1.5);
	int flat = add_material(&ts, 0.2, 0.4, 0.6, 1, 0, 0, 32, 0, 0, 1.5);
	add_plane(&ts, 0, 0, 0, 0, 1, 0, mirror);
	add_sphere(&ts, 0, 2, -3, 0.5, flat);
	set_camera(&ts, 0, 1, 0, 0, 0, -1, 0, 1, 0, 45);

	/* 1x1 image: the ray is f = (0,-1,-1)/sqrt2 from (0,1,0).
	 * Plane: t = dot((0,0,0) - (0,1,0), (0,1,0)) / (-1/sqrt2) = sqrt2,
	 *   p = (0,0,-1), n = (0,1,0). Local colour 0 (ka = kd = ks = 0).
	 * R = d - 2 (d.n) n = (0,1,-1)/sqrt2; from (0,eps,-1) it passes
	 *   within eps of (0,2,-3), the sphere's centre, so it hits the sphere,
	 *   whose colour is 1 * C * 1 = (0.2,0.4,0.6).
	 * Pixel = 0.5 (0.2,0.4,0.6) = (0.1,0.2,0.3). A miss would give 0.45. */
	float px[3];
	render_pixel(&ts, 1, 1, 1, 0, 0, px);
	expect_rgb(px, 0.1, 0.2, 0.3, 1e-6, "mirror floor");
	render_pixel(&ts, 1, 1, 0, 0, 0, px);
	expect_rgb(px, 0, 0, 0, 1e-6, "mirror floor, max_depth 0");
}

/* ---- (d) refraction and total internal reflection ---- */

/* A glass sphere of radius 1 at the origin that only transmits: C = 1,
 * ka 0.25, kd = ks = kr = 0, kt and ior as given. Ambient 0.2 makes every
 * surface's local colour 0.25 * 0.2 = 0.05; there are no lights. */
static void glass_scene(struct test_scene *ts, double kr, double kt)
{
	scene_init(ts);
	set3(ts->scene.background, 0.3, 0.5, 0.7);
	set3(ts->scene.ambient, 0.2, 0.2, 0.2);
	int glass = add_material(ts, 1, 1, 1, 0.25, 0, 0, 32, kr, kt, 1.5);
	add_sphere(ts, 0, 0, 0, 1, glass);
}

Test(reference, refraction_through_sphere_at_normal_incidence)
{
	struct test_scene ts;
	glass_scene(&ts, 0, 0.5);

	/* From (0,0,5) the centre ray d = (0,0,-1) enters at (0,0,1):
	 *   outside, eta = 1/1.5, c = 1, k = 1 - eta^2 * 0 = 1,
	 *   T = eta d + (eta - 1) n = (0,0,-eta) + (0,0,eta - 1) = (0,0,-1).
	 * From (0,0,1-eps) it meets the sphere from inside at its far root,
	 *   (0,0,-1): inside, n = (0,0,1), eta = 1.5, c = 1, k = 1, T = d again,
	 *   and from (0,0,-1-eps) it leaves to the background.
	 * With local colour l = 0.05 and kt = 0.5:
	 *   max_depth 0: l                        = 0.05
	 *   max_depth 1: l + kt l                 = 0.075
	 *   max_depth 2: l + kt (l + kt bg)       = 0.075 + 0.25 bg
	 *              = (0.15, 0.2, 0.25) */
	float px[3];
	render_pixel(&ts, 3, 3, 0, 1, 1, px);
	expect_rgb(px, 0.05, 0.05, 0.05, 1e-6, "glass, max_depth 0");
	render_pixel(&ts, 3, 3, 1, 1, 1, px);
	expect_rgb(px, 0.075, 0.075, 0.075, 1e-6, "glass, max_depth 1");
	render_pixel(&ts, 3, 3, 2, 1, 1, px);
	expect_rgb(px, 0.15, 0.2, 0.25, 1e-6, "glass, max_depth 2");
}

/* Seeded xorshift64, so that a failure can be reproduced. */
static double random_unit(uint64_t *state)
{
	*state ^= *state << 13;
	*state ^= *state >> 7;
	*state ^= *state << 17;
	return (double)(*state >> 11) / 9007199254740992.0; /* [0, 1) */
}

Test(reference, total_internal_reflection_property)
{
	/* The eye sits inside the glass sphere at (0,y,0), looking along +z
	 * (1x1 image, so d = (0,0,1)). The ray meets the sphere from inside at
	 * its far root p = (0, y, sqrt(1 - y^2)): inside, n = -p,
	 * c = -d.n = sqrt(1 - y^2), eta = ior = 1.5,
	 * k = 1 - 2.25 (1 - c^2) = 1 - 2.25 y^2, so TIR exactly when y > 2/3.
	 * With kr = 0, kt = 1, max_depth 1 and local colour l = 0.05:
	 *   TIR: the weight kt moves to the reflection ray, which stays inside
	 *        and meets the sphere again: l + 1 * l = 0.1;
	 *   otherwise: T leaves the sphere and meets nothing: l + 1 * bg.
	 * Dropping the TIR rule (or keeping only kr) would give l = 0.05, and
	 * refracting anyway would take the root of a negative number. */
	struct test_scene ts;
	glass_scene(&ts, 0, 1);

	uint64_t seed = 0x5eed2009u;
	int tir_cases = 0, refract_cases = 0;
	for (int i = 0; i < 200; i++) {
		double y = 0.99 * random_unit(&seed);
		if (fabs(y - 2.0 / 3.0) < 1e-3)
			continue;
		set_camera(&ts, 0, y, 0, 0, y, 1, 0, 1, 0, 45);

		float px[3];
		render_pixel(&ts, 1, 1, 1, 0, 0, px);
		char what[64];
		if (y > 2.0 / 3.0) {
			snprintf(what, sizeof(what), "TIR at y = %.17g", y);
			expect_rgb(px, 0.1, 0.1, 0.1, 1e-6, what);
			tir_cases++;
		} else {
			snprintf(what, sizeof(what), "refraction at y = %.17g", y);
			expect_rgb(px, 0.35, 0.55, 0.75, 1e-6, what);
			refract_cases++;
		}
	}
	cr_assert_gt(tir_cases, 20);
	cr_assert_gt(refract_cases, 20);
}

Test(reference, total_internal_reflection_adds_to_kr)
{
	/* As in the property test at y = 0.9 (k = 1 - 2.25 * 0.81 < 0), with
	 * kr = 0.25 and kt = 0.5: reflection weight 0.75, pixel l + 0.75 l =
	 * 0.0875. */
	struct test_scene ts;
	glass_scene(&ts, 0.25, 0.5);
	set_camera(&ts, 0, 0.9, 0, 0, 0.9, 1, 0, 1, 0, 45);

	float px[3];
	render_pixel(&ts, 1, 1, 1, 0, 0, px);
	expect_rgb(px, 0.0875, 0.0875, 0.0875, 1e-6, "TIR with kr 0.25, kt 0.5");
}

/* ---- camera: which pixel looks where ---- */

Test(reference, pixel_directions_follow_the_camera_formula)
{
	/* 4x2 image, fov 90 (h = 1), a = 2; eye at the origin looking along -z
	 * with up y, so f = (0,0,-1), r = normalize(f x up) = (1,0,0),
	 * u = r x f = (0,1,0), and pixel (x,y) looks along
	 *   (sx, sy, -1), sx = (2(x+0.5)/4 - 1) * 2, sy = 1 - 2(y+0.5)/2.
	 * One small sphere per pixel, 10 units along that direction, each with
	 * its own colour (ka 1, ambient 1): every pixel must see its own. */
	struct test_scene ts;
	scene_init(&ts);
	set3(ts.scene.ambient, 1, 1, 1);
	set_camera(&ts, 0, 0, 0, 0, 0, -1, 0, 1, 0, 90);

	const int width = 4, height = 2;
	for (int y = 0; y < height; y++) {
		for (int x = 0; x < width; x++) {
			double sx = (2.0 * (x + 0.5) / width - 1.0) * 2.0;
			double sy = 1.0 - 2.0 * (y + 0.5) / height;
			double len = sqrt(sx * sx + sy * sy + 1.0);
			int m = add_material(&ts, 0.1 * (x + 1), 0.1 * (y + 1), 0.5, 1, 0, 0, 32, 0,
					     0, 1.5);
			add_sphere(&ts, 10 * sx / len, 10 * sy / len, -10 / len, 0.3, m);
		}
	}

	float rgb[3 * 4 * 2];
	cr_assert_eq(reference_render(&ts.scene, width, height, 0, rgb), 0);
	for (int y = 0; y < height; y++) {
		for (int x = 0; x < width; x++) {
			char what[32];
			snprintf(what, sizeof(what), "pixel (%d,%d)", x, y);
			expect_rgb(rgb + 3 * (y * width + x), 0.1 * (x + 1), 0.1 * (y + 1), 0.5,
				   1e-6, what);
		}
	}
}

/* ---- checkerboard ---- */

/* A plane through the origin with unit normal n, material colour 0.9 and
 * checker colour 0.2 (size 2), shown as its ambient term; the camera sits 5
 * units along n above the plane point `at` and looks straight at it. */
static double checker_at(double nx, double ny, double nz, double ax, double ay, double az,
			 double upx, double upy, double upz)
{
	struct test_scene ts;
	scene_init(&ts);
	set3(ts.scene.ambient, 1, 1, 1);
	int m = add_material(&ts, 0.9, 0.9, 0.9, 1, 0, 0, 32, 0, 0, 1.5);
	struct scene_plane *p = add_plane(&ts, 0, 0, 0, nx, ny, nz, m);
	p->has_checker = 1;
	p->checker_size = 2;
	set3(p->checker_color, 0.2, 0.2, 0.2);
	set_camera(&ts, ax + 5 * nx, ay + 5 * ny, az + 5 * nz, ax, ay, az, upx, upy, upz, 45);

	float px[3];
	render_pixel(&ts, 1, 1, 0, 0, 0, px);
	cr_assert(px[0] == px[1] && px[1] == px[2], "grey expected, got %g %g %g", px[0], px[1],
		  px[2]);
	return px[0];
}

#define BASE ((float)0.9)
#define CHECK ((float)0.2)

Test(reference, checker_on_floor)
{
	/* Normal (0,1,0): drop y, (s,t) = (x,z), size 2. */
	/* (0.5, 0.5): floor 0 + 0 = 0, even. */
	cr_expect_eq(checker_at(0, 1, 0, 0.5, 0, 0.5, 0, 0, -1), BASE);
	/* (2.5, 0.5): 1 + 0 = 1, odd. */
	cr_expect_eq(checker_at(0, 1, 0, 2.5, 0, 0.5, 0, 0, -1), CHECK);
	/* (-0.5, 0.5): -1 + 0 = -1, odd (not -1 % 2 == -1 "even"). */
	cr_expect_eq(checker_at(0, 1, 0, -0.5, 0, 0.5, 0, 0, -1), CHECK);
	/* (-0.5, -0.5): -1 + -1 = -2, even. */
	cr_expect_eq(checker_at(0, 1, 0, -0.5, 0, -0.5, 0, 0, -1), BASE);
	/* (-2.5, 0.5): floor(-1.25) = -2, even (truncation would give -1). */
	cr_expect_eq(checker_at(0, 1, 0, -2.5, 0, 0.5, 0, 0, -1), BASE);
}

Test(reference, checker_drops_largest_absolute_component)
{
	/* Normal (0.6,-0.8,0): |y| is largest although y < x, so drop y.
	 * At (2.4, 1.8, 0.5) (0.6*2.4 - 0.8*1.8 = 0): (s,t) = (2.4, 0.5),
	 * 1 + 0 odd. Dropping x instead would give (1.8, 0.5), even. */
	cr_expect_eq(checker_at(0.6, -0.8, 0, 2.4, 1.8, 0.5, 0, 0, 1), CHECK);
}

Test(reference, checker_tie_drops_x_first)
{
	/* Normal (1,1,0)/sqrt2: |x| = |y|, the tie drops x, so (s,t) = (y,z).
	 *   at (1,-1,0.5): (-1, 0.5): -1 + 0 = -1, odd;
	 *   at (1,-1,2.5): (-1, 2.5): -1 + 1 = 0, even.
	 * Dropping y would give even, odd; dropping z odd, odd. */
	const double c = sqrt(0.5);
	cr_expect_eq(checker_at(c, c, 0, 1, -1, 0.5, 0, 0, 1), CHECK);
	cr_expect_eq(checker_at(c, c, 0, 1, -1, 2.5, 0, 0, 1), BASE);
}

Test(reference, plane_seen_from_behind_uses_flipped_normal)
{
	/* The floor y = 0 seen from below: n_g = (0,1,0), d = (0,1,0), inside,
	 * n = (0,-1,0). A light below at (0,-5,0) lights it fully through the
	 * flipped normal: p = (0,0,0), L = (0,-1,0), n.L = 1,
	 * L - d = (0,-2,0), H = (0,-1,0), n.H = 1.
	 * Colour = kd * 1 * C + ks * 1 = 0.7*0.5 + 0.3 = 0.65 (ka = 0).
	 * The shadow ray starts at p + eps n = (0,-eps,0), below the plane. */
	struct test_scene ts;
	scene_init(&ts);
	int m = add_material(&ts, 0.5, 0.5, 0.5, 0, 0.7, 0.3, 16, 0, 0, 1.5);
	add_plane(&ts, 0, 0, 0, 0, 1, 0, m);
	add_light(&ts, 0, -5, 0, 1, 1, 1);
	set_camera(&ts, 0, -3, 0, 0, 0, 0, 0, 0, 1, 45);

	float px[3];
	render_pixel(&ts, 1, 1, 0, 0, 0, px);
	expect_rgb(px, 0.65, 0.65, 0.65, 1e-6, "floor from below");
}

/* ---- deep ray trees and extreme accepted values stay finite ---- */

/* An upper bound on any pixel, from RENDERING.md alone: a local colour is at
 * most Lmax = max over materials of ka max(C) max(ambient) + sum over lights
 * of (kd max(C) + ks) max(Lc) (the cosines are at most 1), or the
 * background; a ray's children carry at most w = max(kr + kt) of its weight
 * (TIR moves kt to the reflection), so level k of the tree weighs at most w^k
 * and a pixel is at most Lmax (1 + w + ... + w^max_depth). */
static double colour_bound(const struct scene *s, int max_depth)
{
	double light_max = 0, ambient_max = 0, local_max = 0, w = 0, bound = 0, level = 1;

	for (int i = 0; i < s->light_count; i++)
		for (int c = 0; c < 3; c++)
			light_max += s->lights[i].color[c]; /* over lights: >= the sum of maxima */
	for (int c = 0; c < 3; c++) {
		ambient_max = fmax(ambient_max, s->ambient[c]);
		local_max = fmax(local_max, s->background[c]);
	}
	for (int i = 0; i < s->material_count; i++) {
		const struct scene_material *m = &s->materials[i];
		double color_max = 0;
		for (int c = 0; c < 3; c++)
			color_max = fmax(color_max, m->color[c]);
		for (int p = 0; p < s->plane_count; p++)
			for (int c = 0; c < 3; c++)
				color_max = fmax(color_max, s->planes[p].checker_color[c]);
		local_max =
			fmax(local_max, m->ambient * color_max * ambient_max +
						(m->diffuse * color_max + m->specular) * light_max);
		w = fmax(w, m->reflect + m->transmit);
	}
	for (int k = 0; k <= max_depth; k++, level *= w)
		bound += local_max * level;
	return bound;
}

/* Renders at max_depth and checks every channel is finite and within
 * colour_bound. */
static void expect_finite_and_bounded(const struct scene *s, int width, int height, int max_depth,
				      const char *what)
{
	size_t values = 3 * (size_t)width * (size_t)height;
	float *rgb = malloc(sizeof(float) * values);
	cr_assert_not_null(rgb);
	cr_assert_eq(reference_render(s, width, height, max_depth, rgb), 0);
	double bound = colour_bound(s, max_depth);
	size_t bad = 0, first = 0;
	for (size_t i = 0; i < values; i++)
		if (!(isfinite(rgb[i]) && rgb[i] >= 0 && rgb[i] <= bound) && bad++ == 0)
			first = i;
	cr_expect_eq(bad, 0,
		     "%s, max_depth %d: %zu of %zu channels not finite or above the bound %g;"
		     " the first, pixel (%zu, %zu) channel %zu, is %g",
		     what, max_depth, bad, values, bound, first / 3 % (size_t)width,
		     first / 3 / (size_t)width, first % 3, bad ? (double)rgb[first] : 0.0);
	free(rgb);
}

static void load_scene(struct scene *s, const char *path)
{
	char err[1024];
	cr_assert_eq(scene_load_file(s, path, err, sizeof(err)), 0, "%s", err);
}

Test(reference, finite_at_depth_64)
{
	/* Glass balls (kr + kt = 0.8) over a reflective floor: every bounce
	 * feeds the next ray's direction into the intersection tests, which
	 * assume |d| = 1. The reference once let |d| drift (1e-16 at the camera,
	 * 0.3 by depth 13): 4.6e24 at depth 20, inf from depth 24. */
	static const char *const scenes[] = {"scenes/two_balls.json", "scenes/paper60.json"};
	for (int i = 0; i < 2; i++) {
		struct scene s;
		load_scene(&s, scenes[i]);
		expect_finite_and_bounded(&s, 8, 6, 64, scenes[i]);
		scene_free(&s);
	}
}

Test(reference, finite_with_ior_1e18)
{
	/* SCENE.md accepts an ior up to 1e18: eta = 1e18 leaving the glass. */
	struct scene s;
	load_scene(&s, "scenes/two_balls.json");
	for (int i = 0; i < s.material_count; i++)
		s.materials[i].ior = 1e18;
	expect_finite_and_bounded(&s, 8, 6, 16, "two_balls.json with ior 1e18");
	scene_free(&s);
}

Test(reference, finite_with_radius_1e18)
{
	/* The camera inside a mirror sphere of radius 1e18 around a reflective
	 * ball of radius 1: rays come back to the ball from 1e18 away, where
	 * b*b - c of the intersection cancels to noise far above radius^2, so the
	 * hit point can miss the ball's surface by far more than its radius. */
	struct test_scene ts;
	scene_init(&ts);
	set3(ts.scene.background, 0.2, 0.4, 0.6);
	set3(ts.scene.ambient, 0.1, 0.1, 0.1);
	int wall = add_material(&ts, 0.5, 0.5, 0.5, 1, 0.7, 0.3, 32, 0.5, 0, 1.5);
	int ball = add_material(&ts, 1, 0.3, 0.2, 1, 0.7, 0.3, 32, 0.5, 0, 1.5);
	add_sphere(&ts, 0, 0, 0, 1e18, wall);
	add_sphere(&ts, 0, 0, 0, 1, ball);
	add_light(&ts, 3, 3, 5, 1, 1, 1);
	expect_finite_and_bounded(&ts.scene, 16, 12, 5, "inside a sphere of radius 1e18");
	expect_finite_and_bounded(&ts.scene, 16, 12, 64, "inside a sphere of radius 1e18");
}

Test(reference, refraction_with_ior_1e18_at_normal_incidence)
{
	/* As refraction_through_sphere_at_normal_incidence, with ior 1e18 and a
	 * wall behind the sphere, the plane z = -3 facing the camera, C = 0.5,
	 * ka 1, so its local colour is 0.5 * 0.2 = 0.1. Leaving the sphere at
	 * (0,0,-1): n = (0,0,1), d = (0,0,-1), eta = 1e18, c = 1, k = 1,
	 * T = eta d + (eta c - 1) n = (0,0,-1): straight on to the wall. (Written
	 * in that order in double, 1e18 - 1 rounds to 1e18 and T cancels to 0.)
	 *   max_depth 2: l + kt (l + kt wall) = 0.05 + 0.5 (0.05 + 0.05) = 0.1 */
	struct test_scene ts;
	glass_scene(&ts, 0, 0.5);
	ts.materials[0].ior = 1e18;
	int wall = add_material(&ts, 0.5, 0.5, 0.5, 1, 0, 0, 32, 0, 0, 1.5);
	add_plane(&ts, 0, 0, -3, 0, 0, 1, wall);

	float px[3];
	render_pixel(&ts, 3, 3, 2, 1, 1, px);
	expect_rgb(px, 0.1, 0.1, 0.1, 1e-6, "ior 1e18, max_depth 2");
}
