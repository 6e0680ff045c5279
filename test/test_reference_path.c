/* Unit tests of the CPU reference's path integrator (host/render/reference_path.cpp)
 * against values worked out from docs/RENDERING.md "Path tracing" and from
 * radiometry, not from the reference itself: white furnaces, direct light
 * of point, directional and emitting lights in closed form, emitters seen
 * directly, and MIS weights that sum to one.
 */
#include <criterion/criterion.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render/reference.h"

#define MAX_MATERIALS 8
#define MAX_SPHERES 8
#define MAX_PLANES 2
#define MAX_LIGHTS 4
#define MAX_TRIANGLES 4

/* A scene built by hand (struct scene points into the arrays beside it: a
 * path_scene stays where it was initialised). */
struct path_scene {
	struct scene scene;
	struct scene_material materials[MAX_MATERIALS];
	struct scene_sphere spheres[MAX_SPHERES];
	struct scene_plane planes[MAX_PLANES];
	struct scene_light lights[MAX_LIGHTS];
	struct scene_triangle triangles[MAX_TRIANGLES];
};

static void set3(double out[3], double x, double y, double z)
{
	out[0] = x;
	out[1] = y;
	out[2] = z;
}

/* An empty path-traced scene, black background, camera at (0, 0, 5) looking
 * at the origin with `fov` degrees, w x h pixels. */
static void scene_init(struct path_scene *ps, int w, int h, double fov)
{
	memset(ps, 0, sizeof(*ps));
	ps->scene.source = "test (hand-built)";
	ps->scene.width = w;
	ps->scene.height = h;
	ps->scene.integrator = SCENE_INTEGRATOR_PATH;
	set3(ps->scene.camera.eye, 0, 0, 5);
	set3(ps->scene.camera.look_at, 0, 0, 0);
	set3(ps->scene.camera.up, 0, 1, 0);
	ps->scene.camera.fov = fov;
	ps->scene.max_depth = 5;
	ps->scene.epsilon = 1e-4;
	ps->scene.materials = ps->materials;
	ps->scene.spheres = ps->spheres;
	ps->scene.planes = ps->planes;
	ps->scene.lights = ps->lights;
	ps->scene.triangles = ps->triangles;
}

static int add_material(struct path_scene *ps)
{
	cr_assert_lt(ps->scene.material_count, MAX_MATERIALS);
	struct scene_material *m = &ps->materials[ps->scene.material_count];
	set3(m->color, 1, 1, 1);
	m->diffuse = 0.7;
	m->ior = 1.5;
	return ps->scene.material_count++;
}

/* A material of bsdf `type` and colour (r, g, b). */
static int add_bsdf(struct path_scene *ps, int type, double r, double g, double b)
{
	int m = add_material(ps);
	ps->materials[m].bsdf.type = type;
	set3(ps->materials[m].bsdf.color, r, g, b);
	ps->materials[m].bsdf.ior = 1.5;
	return m;
}

static void add_sphere(struct path_scene *ps, double x, double y, double z, double radius,
		       int material)
{
	cr_assert_lt(ps->scene.sphere_count, MAX_SPHERES);
	struct scene_sphere *s = &ps->spheres[ps->scene.sphere_count++];
	set3(s->center, x, y, z);
	s->radius = radius;
	s->material = material;
}

static void add_plane(struct path_scene *ps, double nx, double ny, double nz, int material)
{
	cr_assert_lt(ps->scene.plane_count, MAX_PLANES);
	struct scene_plane *p = &ps->planes[ps->scene.plane_count++];
	set3(p->point, 0, 0, 0);
	set3(p->normal, nx, ny, nz);
	p->material = material;
}

static void add_triangle(struct path_scene *ps, const double v[3][3], int material)
{
	cr_assert_lt(ps->scene.triangle_count, MAX_TRIANGLES);
	struct scene_triangle *t = &ps->triangles[ps->scene.triangle_count++];
	memcpy(t->v, v, sizeof(t->v));
	t->material = material;
}

/* The mean colour of the pixels in [x0, x1) x [y0, y1) at n samples each. */
static void render_mean(const struct path_scene *ps, int max_depth, int n, int x0, int y0, int x1,
			int y1, double out[3])
{
	int w = ps->scene.width, h = ps->scene.height;
	float *rgb = malloc(sizeof(float) * 3 * (size_t)w * (size_t)h);
	cr_assert_not_null(rgb);
	cr_assert_eq(reference_render_samples(&ps->scene, w, h, max_depth, n, rgb), 0);
	out[0] = out[1] = out[2] = 0;
	for (int y = y0; y < y1; y++)
		for (int x = x0; x < x1; x++)
			for (int c = 0; c < 3; c++)
				out[c] += rgb[3 * (y * w + x) + c] / ((x1 - x0) * (y1 - y0));
	free(rgb);
}

static void expect_near(const double got[3], double r, double g, double b, double relative,
			const char *what)
{
	const double want[3] = {r, g, b};
	for (int c = 0; c < 3; c++)
		cr_expect(fabs(got[c] - want[c]) <= relative * want[c] + 1e-12,
			  "%s: channel %d is %.6f, expected %.6f (within %g %%)", what, c, got[c],
			  want[c], 100 * relative);
}

/* A uniform environment of radiance 1 and a sphere of radius 1 at the
 * origin, of the material furnace_material sets up, filling the middle of an
 * 8x8 image. */
static void furnace(struct path_scene *ps, void (*furnace_material)(struct path_scene *, int))
{
	scene_init(ps, 8, 8, 10);
	set3(ps->scene.background, 1, 1, 1);
	int m = add_material(ps);
	furnace_material(ps, m);
	add_sphere(ps, 0, 0, 0, 1, m);
}

static void diffuse_rho(struct path_scene *ps, int m)
{
	ps->materials[m].bsdf.type = SCENE_BSDF_DIFFUSE;
	set3(ps->materials[m].bsdf.color, 0.2, 0.5, 0.9);
}

static void mapped_diffuse_and_mirror(struct path_scene *ps, int m)
{
	set3(ps->materials[m].color, 1, 0.5, 0.25);
	ps->materials[m].diffuse = 0.8;
	ps->materials[m].reflect = 0.25;
}

static void smooth_glass(struct path_scene *ps, int m)
{
	ps->materials[m].bsdf.type = SCENE_BSDF_DIELECTRIC;
	ps->materials[m].bsdf.ior = 1.5;
}

/* White furnace: a convex diffuse sphere of albedo rho under a uniform
 * environment of radiance 1 reflects exactly rho (every reflected ray leaves
 * to the environment): NEE of the environment and the BSDF ray, weighted by
 * MIS, must add up to it at every depth. */
Test(reference_path, white_furnace_diffuse_sphere_gives_its_albedo)
{
	struct path_scene ps;
	furnace(&ps, diffuse_rho);
	double got[3];
	render_mean(&ps, 0, 256, 2, 2, 6, 6, got);
	expect_near(got, 0.2, 0.5, 0.9, 0.01, "max_depth 0");
	render_mean(&ps, 4, 256, 2, 2, 6, 6, got);
	expect_near(got, 0.2, 0.5, 0.9, 0.01, "max_depth 4");
}

/* The mapped BSDF (no "bsdf"): a diffuse lobe of rho = kd C with
 * probability 1 - kr and a white mirror of probability kr reflect
 * (1 - kr) rho + kr of a furnace. */
Test(reference_path, white_furnace_mapped_material_mixes_diffuse_and_mirror)
{
	struct path_scene ps;
	furnace(&ps, mapped_diffuse_and_mirror);
	double got[3];
	render_mean(&ps, 2, 256, 2, 2, 6, 6, got);
	expect_near(got, 0.75 * 0.8 + 0.25, 0.75 * 0.4 + 0.25, 0.75 * 0.2 + 0.25, 0.01,
		    "kd 0.8, kr 0.25");
}

/* Smooth glass in a furnace: reflection weighs 1 and refraction 1/eta^2 in
 * and back out, so every path that leaves gives exactly 1; at depth 32 so
 * few are cut short, Russian roulette keeping the mean. */
Test(reference_path, white_furnace_smooth_glass_sphere_is_invisible)
{
	struct path_scene ps;
	furnace(&ps, smooth_glass);
	double got[3];
	render_mean(&ps, 32, 64, 2, 2, 6, 6, got);
	expect_near(got, 1, 1, 1, 0.01, "ior 1.5");
}

static void rough_copper(struct path_scene *ps, int m)
{
	ps->materials[m].bsdf.type = SCENE_BSDF_CONDUCTOR;
	set3(ps->materials[m].bsdf.color, 0.95, 0.64, 0.54);
	ps->materials[m].bsdf.roughness = 0.5;
}

static void frosted_glass(struct path_scene *ps, int m)
{
	ps->materials[m].bsdf.type = SCENE_BSDF_DIELECTRIC;
	ps->materials[m].bsdf.ior = 1.5;
	ps->materials[m].bsdf.roughness = 0.4;
}

static void principled_mix(struct path_scene *ps, int m)
{
	ps->materials[m].bsdf.type = SCENE_BSDF_PRINCIPLED;
	set3(ps->materials[m].bsdf.color, 0.8, 0.5, 0.3);
	ps->materials[m].bsdf.metallic = 0.3;
	ps->materials[m].bsdf.transmission = 0.4;
	ps->materials[m].bsdf.roughness = 0.5;
	ps->materials[m].bsdf.ior = 1.45;
}

/* Light sampling and BSDF sampling, weighted by MIS, estimate the same
 * integral only where a BSDF's pdf is the density of its sample and its
 * weight is f |cos| / pdf. Two black point lights (G = 3 instead of 1) cut
 * the environment's share of the light samples to a third and so move every
 * MIS weight; the mean stays put only if the BSDF is self-consistent (a pdf
 * 30 % off moves a rough conductor's by 1.4 %). */
static void expect_mis_invariant(void (*furnace_material)(struct path_scene *, int),
				 const char *what)
{
	struct path_scene ps;
	double one[3], two[3];

	furnace(&ps, furnace_material);
	render_mean(&ps, 3, 512, 2, 2, 6, 6, one);
	for (int i = 0; i < 2; i++) {
		struct scene_light *l = &ps.lights[ps.scene.light_count++];
		set3(l->position, 0, 10, i);
	}
	render_mean(&ps, 3, 512, 2, 2, 6, 6, two);
	expect_near(two, one[0], one[1], one[2], 0.01, what);
}

Test(reference_path, mis_keeps_the_mean_of_rough_and_principled_bsdfs)
{
	expect_mis_invariant(rough_copper, "rough conductor");
	expect_mis_invariant(frosted_glass, "rough dielectric");
	expect_mis_invariant(principled_mix, "principled");
	expect_mis_invariant(mapped_diffuse_and_mirror, "mapped");
}

/* An environment map over a diffuse plane facing up (+y, the map's top):
 * the plane's irradiance from row k of the upper half is pi E_k
 * (sin^2 theta_(k+1) - sin^2 theta_k), E_k the row's mean radiance, so
 * L = rho sum_k E_k (sin^2 theta_(k+1) - sin^2 theta_k), whatever the
 * columns and the turn about +y. Texels of radiance 0 are never light
 * samples (weight 0) but still met by BSDF rays; the lower half, behind the
 * plane, is sampled and shadowed. */
Test(reference_path, environment_map_over_a_diffuse_plane_by_rows)
{
	enum { W = 8, H = 6 };
	float rgb[3 * W * H];
	double want = 0;
	for (int k = 0; k < H; k++) {
		double row = 0;
		for (int j = 0; j < W; j++) {
			double e = (j * 7 + k * 3) % 5 == 0 ? 0.0 : 0.25 * (1 + (j * 5 + k) % 4);
			for (int c = 0; c < 3; c++)
				rgb[3 * (k * W + j) + c] = (float)e;
			row += e / W;
		}
		double lo = sin(M_PI * k / H), hi = sin(M_PI * (k + 1) / H);
		if (k < H / 2)
			want += 0.6 * 1.5 * row * (hi * hi - lo * lo); /* rho, scale */
	}
	struct path_scene ps;
	scene_init(&ps, 4, 4, 5);
	set3(ps.scene.camera.eye, 0, 3, -3);
	add_plane(&ps, 0, 1, 0, add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0.6, 0.6, 0.6));
	ps.scene.environment = (struct scene_environment){.file = "map (hand-built)",
							  .scale = 1.5,
							  .rotate = 70,
							  .width = W,
							  .height = H,
							  .rgb = rgb};
	double got[3];
	render_mean(&ps, 0, 1024, 0, 0, 4, 4, got);
	expect_near(got, want, want, want, 0.01, "map");
}

/* Emitters are seen directly: the primary ray's hit of a front face adds
 * Le at weight 1, the back face nothing. */
Test(reference_path, an_emitter_seen_directly_is_its_emission_from_the_front_only)
{
	struct path_scene ps;
	scene_init(&ps, 3, 3, 20);
	int lamp = add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0, 0, 0);
	set3(ps.materials[lamp].emission, 3, 2, 1);
	/* A big triangle in z = 0 facing +z, towards the camera. */
	const double front[3][3] = {{-5, -5, 0}, {5, -5, 0}, {0, 5, 0}};
	add_triangle(&ps, front, lamp);
	double got[3];
	render_mean(&ps, 3, 1, 1, 1, 2, 2, got);
	expect_near(got, 3, 2, 1, 1e-7, "front");
	const double back[3][3] = {{-5, -5, 0}, {0, 5, 0}, {5, -5, 0}};
	memcpy(ps.triangles[0].v, back, sizeof(back));
	render_mean(&ps, 3, 1, 1, 1, 2, 2, got);
	expect_near(got, 0, 0, 0, 0, "back");
}

/* Inside an emitting sphere (a dome of emission 1 around the camera, lit by
 * a point light), nothing sees the emission, which leaves its outside only:
 * the image is the same as without it (G = 2 instead of 1, the same mean).
 * A point on the dome must not sample the dome as a light: from there the
 * dome's D <= R is decided by rounding. */
Test(reference_path, a_point_on_an_emitting_sphere_does_not_sample_it)
{
	struct path_scene ps;
	scene_init(&ps, 8, 8, 60);
	set3(ps.scene.camera.eye, 0.3, 0.2, 0.1);
	int dome = add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0.9, 0.9, 0.9);
	add_sphere(&ps, 0, 0, 0, 5, dome);
	struct scene_light *l = &ps.lights[ps.scene.light_count++];
	set3(l->position, 0, -1, 2);
	set3(l->color, 1, 1, 1);
	double dark[3], lit[3];
	render_mean(&ps, 0, 256, 0, 0, 8, 8, dark);
	set3(ps.materials[dome].emission, 1, 1, 1);
	render_mean(&ps, 0, 256, 0, 0, 8, 8, lit);
	expect_near(lit, dark[0], dark[1], dark[2], 0.02, "emitting dome");
}

/* A point light of intensity I at height d above a diffuse plane seen head
 * on: L = rho/pi * I/d^2 (a delta light: exact, weight 1). */
Test(reference_path, point_light_over_a_diffuse_plane_in_closed_form)
{
	struct path_scene ps;
	scene_init(&ps, 3, 3, 20);
	add_plane(&ps, 0, 0, 1, add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0.5, 0.25, 1));
	struct scene_light *l = &ps.lights[ps.scene.light_count++];
	set3(l->position, 0, 0, 2);
	set3(l->color, 4, 4, 4);
	double got[3];
	render_mean(&ps, 0, 1, 1, 1, 2, 2, got);
	double e = 4.0 / (2.0 * 2.0); /* I / d^2 */
	expect_near(got, 0.5 / M_PI * e, 0.25 / M_PI * e, 1 / M_PI * e, 1e-6, "point light");
}

/* A sun straight ahead (irradiance E0): L = rho/pi * E0, with angle 0
 * exactly, with an angle a the radiance E0/(pi sin^2 a) over a cone whose
 * cosine-weighted solid angle is pi sin^2 a: the same. */
Test(reference_path, directional_light_over_a_diffuse_plane_in_closed_form)
{
	struct path_scene ps;
	scene_init(&ps, 3, 3, 20);
	add_plane(&ps, 0, 0, 1, add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0.5, 0.5, 0.5));
	struct scene_light *l = &ps.lights[ps.scene.light_count++];
	l->directional = 1;
	set3(l->direction, 0, 0, -1);
	set3(l->color, 2, 2, 2);
	double got[3];
	render_mean(&ps, 0, 1, 1, 1, 2, 2, got);
	expect_near(got, 1 / M_PI, 1 / M_PI, 1 / M_PI, 1e-6, "angle 0");
	l->angle = 5;
	render_mean(&ps, 0, 64, 1, 1, 2, 2, got);
	expect_near(got, 1 / M_PI, 1 / M_PI, 1 / M_PI, 2e-3, "angle 5");
}

/* An emitting sphere (radius R, radiance Le) straight above a diffuse plane
 * at distance D gives it irradiance pi Le R^2/D^2, so L = rho Le R^2/D^2:
 * light sampling and BSDF rays, weighted by MIS, converge to it. A sphere
 * light of the same size and intensity I = Le pi R^2 gives the same. */
Test(reference_path, emitting_sphere_and_sphere_light_over_a_diffuse_plane)
{
	struct path_scene ps;
	scene_init(&ps, 3, 3, 0.2);
	set3(ps.scene.camera.eye, 3, 0, 3); /* past the lamp, looking at the origin */
	add_plane(&ps, 0, 0, 1, add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0.8, 0.8, 0.8));
	int lamp = add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0, 0, 0);
	set3(ps.materials[lamp].emission, 5, 5, 5);
	add_sphere(&ps, 0, 0, 2, 0.5, lamp);
	double want = 0.8 * 5 * 0.25 / 4, got[3];
	render_mean(&ps, 0, 1024, 0, 0, 3, 3, got);
	expect_near(got, want, want, want, 0.01, "emitting sphere");

	ps.scene.sphere_count = 0;
	struct scene_light *l = &ps.lights[ps.scene.light_count++];
	set3(l->position, 0, 0, 2);
	set3(l->color, 5 * M_PI * 0.25, 5 * M_PI * 0.25, 5 * M_PI * 0.25);
	l->radius = 0.5;
	render_mean(&ps, 0, 256, 0, 0, 3, 3, got);
	expect_near(got, want, want, want, 0.01, "sphere light");
}

/* An emitting square of half side a at height h above a diffuse plane, Le
 * 1, facing it: the point under its centre gets irradiance pi Le F, F the
 * form factor of four a x a rectangles with a corner above it, each
 * (1/(2 pi)) (2 X/sqrt(1 + X^2) atan(X/sqrt(1 + X^2))), X = a/h; so
 * L = rho Le F. The square reaches 70.5 degrees from the vertical, where the
 * shadow ray, an epsilon off the plane, meets the emitter's plane nearer
 * than dist - 2 epsilon (from 60 degrees on): only the emitter's own
 * triangles may not shadow it. */
Test(reference_path, emitting_square_over_a_diffuse_plane_by_its_form_factor)
{
	struct path_scene ps;
	scene_init(&ps, 3, 3, 0.2);
	set3(ps.scene.camera.eye, 0, 0.5, -0.5); /* under the square, looking at the origin */
	set3(ps.scene.camera.look_at, 0, 0, 0);
	add_plane(&ps, 0, 1, 0, add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0.5, 0.5, 0.5));
	int lamp = add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0, 0, 0);
	set3(ps.materials[lamp].emission, 1, 1, 1);
	const double a[3][3] = {{-2, 1, -2}, {2, 1, -2}, {2, 1, 2}}; /* facing -y */
	const double b[3][3] = {{-2, 1, -2}, {2, 1, 2}, {-2, 1, 2}};
	add_triangle(&ps, a, lamp);
	add_triangle(&ps, b, lamp);
	double x = 2.0 / sqrt(5.0);
	double want = 0.5 * 4 / (2 * M_PI) * 2 * x * atan(x), got[3];
	render_mean(&ps, 0, 1024, 0, 0, 3, 3, got);
	expect_near(got, want, want, want, 0.01, "emitting square");
}

/* RENDERING.md: w_l of a light sample and w_hit of a BSDF ray finding the
 * same light in the same direction sum to one; this holds only where the
 * light pdf of sampling (1/G, P_e, pdf_e) is the one a hit computes. */
Test(reference_path, mis_weights_of_a_light_sample_and_its_bsdf_ray_sum_to_one)
{
	struct path_scene ps;
	scene_init(&ps, 4, 4, 60);
	set3(ps.scene.background, 0.2, 0.3, 0.4); /* the environment group */
	add_plane(&ps, 0, 0, 1, add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0.5, 0.5, 0.5));
	int rough = add_bsdf(&ps, SCENE_BSDF_CONDUCTOR, 0.9, 0.6, 0.3);
	ps.materials[rough].bsdf.roughness = 0.6;
	add_sphere(&ps, -1, 0, 0.5, 0.5, rough);
	int lamp = add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0, 0, 0);
	set3(ps.materials[lamp].emission, 4, 3, 2);
	int dim = add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0, 0, 0);
	set3(ps.materials[dim].emission, 0.5, 1, 0.5);
	add_sphere(&ps, 1, 1, 1.5, 0.4, lamp);
	const double quad[3][3] = {{-1, 1, 2}, {-1, 2, 2}, {1, 1.5, 2.5}};
	add_triangle(&ps, quad, dim);

	int pairs = 0, n = 64;
	for (int y = 0; y < 4; y++)
		for (int x = 0; x < 4; x++)
			for (int k = 0; k < n; k++) {
				double w[2];
				if (reference_path_mis_weights(&ps.scene, x, y, k, n, w))
					continue;
				pairs++;
				/* 1e-3: the BSDF ray starts epsilon off the surface and
				 * meets the emitter epsilon away from the sampled point */
				cr_expect(w[0] >= 0 && w[1] >= 0 && fabs(w[0] + w[1] - 1) < 1e-3,
					  "pixel (%d, %d) sample %d: w_l %.12g + w_hit %.12g", x, y,
					  k, w[0], w[1]);
			}
	cr_expect_gt(pairs, 100, "only %d samples had a pair", pairs);
}

/* RENDERING.md's image is the mean of each pixel's samples; the reference
 * renders it sample by sample over the image (issue 44 item 2: a stopped
 * render keeps its samples), under the path integrator as under Whitted's:
 * reference_render_sample for k = 0 ... n - 1, then reference_mean, gives
 * reference_render_samples' image to the bit, and an emitter, a sphere light
 * and a rough conductor make every sample differ. */
Test(reference_path, sample_by_sample_is_the_same_image)
{
	struct path_scene ps;
	scene_init(&ps, 6, 5, 40);
	add_plane(&ps, 0, 1, 0, add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0.8, 0.6, 0.4));
	ps.planes[0].point[1] = -1;
	int lamp = add_bsdf(&ps, SCENE_BSDF_DIFFUSE, 0, 0, 0);
	set3(ps.materials[lamp].emission, 4, 3, 2);
	add_sphere(&ps, 1, 1, 0, 0.5, lamp);
	int metal = add_bsdf(&ps, SCENE_BSDF_CONDUCTOR, 0.9, 0.7, 0.3);
	ps.materials[metal].bsdf.roughness = 0.3;
	add_sphere(&ps, -0.5, -0.2, 0, 0.8, metal);
	struct scene_light *l = &ps.lights[ps.scene.light_count++];
	set3(l->position, -2, 3, 2);
	set3(l->color, 10, 10, 10);
	l->radius = 0.3;
	set3(ps.scene.background, 0.1, 0.1, 0.2);

	const int w = 6, h = 5, n = 8, depth = 3;
	size_t values = 3 * (size_t)w * (size_t)h;
	float *whole = malloc(values * sizeof(float)), *by_sample = malloc(values * sizeof(float)),
	      *first = malloc(values * sizeof(float));
	double *sums = calloc(values, sizeof(double));
	cr_assert(whole && by_sample && first && sums);
	cr_assert_eq(reference_render_samples(&ps.scene, w, h, depth, n, whole), 0);
	for (int k = 0; k < n; k++) {
		cr_assert_eq(reference_render_sample(&ps.scene, w, h, depth, k, n, sums), 0);
		if (k == 0)
			reference_mean(sums, values, 1, first);
	}
	reference_mean(sums, values, n, by_sample);
	cr_expect_eq(memcmp(whole, by_sample, values * sizeof(float)), 0,
		     "sample by sample differs from the whole render");
	cr_expect_neq(memcmp(whole, first, values * sizeof(float)), 0,
		      "one sample gives the whole image: the scene tests nothing");
	cr_expect_eq(reference_render_sample(&ps.scene, w, h, depth, n, n, sums), -1);
	free(whole);
	free(by_sample);
	free(first);
	free(sums);
}
