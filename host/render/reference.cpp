/* CPU reference renderer (see reference.h).
 *
 * Each numbered step of RENDERING.md's trace() is marked below with its
 * number, so the two can be read side by side. Clarity comes before speed:
 * the only optimisation is converting the scene once into GLM vectors.
 */
#include "render/reference.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <new>
#include <vector>

namespace
{

using glm::dvec3;

dvec3 to_dvec3(const double v[3])
{
	return dvec3(v[0], v[1], v[2]);
}

struct material {
	dvec3 color;
	double ka, kd, ks, shininess, kr, kt, ior;
	int fresnel;	     /* SCENE_FRESNEL_* */
	int texture;	     /* an index into the textures, or -1 */
	int alpha_texture;   /* the cut-out's, or -1 */
	double alpha_cutoff; /* > 0: a cut-out */
	double alpha_scale;
};

/* A texture as RENDERING.md ("Textures") reads it. */
struct texture {
	const struct scene_texture *t;
	int width, height, wrap_s, wrap_t;
};

struct sphere {
	dvec3 center;
	double radius;
	double radius_sq;
	int material;
};

struct plane {
	dvec3 point;
	dvec3 normal;
	int material;
	bool has_checker;
	double checker_size;
	dvec3 checker_color;
	int dropped_axis; /* world axis left out of the checker coordinates */
};

struct triangle {
	dvec3 v0, v1, v2;
	dvec3 n_g;	 /* unit geometric normal, (v1 - v0) x (v2 - v0) normalised */
	dvec3 normal[3]; /* unit shading normals at the vertices */
	bool smooth;
	int material;
	glm::dvec2 uv[3]; /* texture coordinates at the vertices */
};

struct light {
	dvec3 position; /* a point or sphere light's centre */
	dvec3 color;
	double radius;	  /* a sphere light's; 0: a point light */
	bool directional; /* then: */
	dvec3 toward;	  /* the unit direction towards the light */
	double tan_angle; /* tan of its angular radius */
};

/* A point of the unit disk for dimension pair `pair` of sample k of pixel
 * (x, y) out of n (defined with the samples, below). */
glm::dvec2 sample_disk(int x, int y, int k, int n, int pair);

/* The sample being traced: sample k of n of pixel (x, y), whose further
 * pairs place the light samples (RENDERING.md, "Light samples"). */
struct sample_id {
	int x, y, k, n;
};

/* The nearest hit of a ray: exactly one of sphere, triangle and plane is
 * set; u and v are the barycentric coordinates of v1 and v2 on a triangle. */
struct hit {
	double t;
	const struct sphere *sphere;
	const struct plane *plane;
	const struct triangle *tri;
	double u, v;
};

/* The axis along which `n` has its largest |component|; ties go to the
 * earlier axis (x before y before z). */
int largest_axis(const dvec3 &n)
{
	int axis = 0;
	if (std::fabs(n.y) > std::fabs(n[axis]))
		axis = 1;
	if (std::fabs(n.z) > std::fabs(n[axis]))
		axis = 2;
	return axis;
}

/* RENDERING.md, "Textures": E^-1, the sRGB curve's inverse. */
double srgb_to_linear(double x)
{
	return x <= 0.04045 ? x / 12.92 : std::pow((x + 0.055) / 1.055, 2.4);
}

/* Index k of an axis of n texels under a wrap mode. */
int wrap_index(long long k, int n, int mode)
{
	if (mode == SCENE_WRAP_CLAMP)
		return (int)std::min<long long>(std::max<long long>(k, 0), n - 1);
	if (mode == SCENE_WRAP_MIRROR) {
		long long m = ((k % (2LL * n)) + 2LL * n) % (2LL * n);
		return (int)(m < n ? m : 2LL * n - 1 - m);
	}
	return (int)(((k % n) + n) % n);
}

/* Texel (i, j), rows top first, linear RGBA. */
glm::dvec4 texel(const texture &tex, int i, int j)
{
	size_t at = 4 * ((size_t)j * (size_t)tex.width + (size_t)i);

	if (tex.t->is_float) {
		const float *f = (const float *)tex.t->texels + at;
		return glm::dvec4(f[0], f[1], f[2], f[3]);
	}
	const unsigned char *c = (const unsigned char *)tex.t->texels + at;
	return glm::dvec4(srgb_to_linear(c[0] / 255.0), srgb_to_linear(c[1] / 255.0),
			  srgb_to_linear(c[2] / 255.0), c[3] / 255.0);
}

/* The bilinear lookup at uv, texel centres at half-integers. */
glm::dvec4 lookup(const texture &tex, const glm::dvec2 &uv)
{
	const double limit = 16777216.0; /* 2^24 */
	double x = std::clamp(uv.x * tex.width - 0.5, -limit, limit);
	double y = std::clamp((1.0 - uv.y) * tex.height - 0.5, -limit, limit);
	double fi = std::floor(x), fj = std::floor(y), fx = x - fi, fy = y - fj;
	long long i = (long long)fi, j = (long long)fj;
	int i0 = wrap_index(i, tex.width, tex.wrap_s), i1 = wrap_index(i + 1, tex.width, tex.wrap_s);
	int j0 = wrap_index(j, tex.height, tex.wrap_t), j1 = wrap_index(j + 1, tex.height, tex.wrap_t);
	glm::dvec4 top = glm::mix(texel(tex, i0, j0), texel(tex, i1, j0), fx);
	glm::dvec4 bottom = glm::mix(texel(tex, i0, j1), texel(tex, i1, j1), fx);
	return glm::mix(top, bottom, fy);
}

/* Returns the smallest t > 0 where the ray meets the sphere (the far root
 * when the origin is inside), or 0 if there is none. d is unit length. */
double intersect_sphere(const sphere &s, const dvec3 &o, const dvec3 &d)
{
	dvec3 oc = o - s.center;
	double b = glm::dot(oc, d);
	double c = glm::dot(oc, oc) - s.radius_sq;
	double disc = b * b - c;
	if (disc < 0.0)
		return 0.0;
	double root = std::sqrt(disc);
	double t_near = -b - root;
	double t_far = -b + root;
	if (t_near > 0.0)
		return t_near;
	if (t_far > 0.0)
		return t_far;
	return 0.0;
}

/* Returns t > 0 where the ray meets the plane, or 0 if it does not (a ray
 * parallel to the plane misses it). */
double intersect_plane(const plane &p, const dvec3 &o, const dvec3 &d)
{
	double denom = glm::dot(p.normal, d);
	if (denom == 0.0)
		return 0.0;
	double t = glm::dot(p.point - o, p.normal) / denom;
	return t > 0.0 ? t : 0.0;
}

/* Returns t > 0 where the ray meets the triangle (either side), or 0 if it
 * does not, with the barycentric coordinates of v1 and v2 in *u and *v:
 * Moller and Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection"
 * (1997), the textbook form in double. A ray in the triangle's plane misses. */
double intersect_triangle(const triangle &tri, const dvec3 &o, const dvec3 &d, double *u, double *v)
{
	dvec3 e1 = tri.v1 - tri.v0, e2 = tri.v2 - tri.v0;
	dvec3 pv = glm::cross(d, e2);
	double det = glm::dot(e1, pv);
	if (det == 0.0)
		return 0.0;
	dvec3 s = o - tri.v0;
	*u = glm::dot(s, pv) / det;
	if (*u < 0.0 || *u > 1.0)
		return 0.0;
	dvec3 q = glm::cross(s, e1);
	*v = glm::dot(d, q) / det;
	if (*v < 0.0 || *u + *v > 1.0)
		return 0.0;
	double t = glm::dot(e2, q) / det;
	return t > 0.0 ? t : 0.0;
}

class tracer
{
      public:
	/* The scene relative to origin (the eye): see the constructor. May
	 * throw std::bad_alloc. */
	tracer(const struct scene &sc, int max_depth, const dvec3 &origin);

	dvec3 trace(const dvec3 &o, const dvec3 &d, int depth, const sample_id &sample) const;

      private:
	bool nearest_hit(const dvec3 &o, const dvec3 &d, hit *out) const;
	bool cut_out(const triangle &tri, double u, double v) const;
	bool blocked(const dvec3 &o, const dvec3 &d, double distance) const;
	dvec3 base_color(const hit &h, const dvec3 &p) const;
	dvec3 local_color(const material &m, const dvec3 &c, const dvec3 &p, const dvec3 &n,
			  const dvec3 &n_face, const dvec3 &d, int depth,
			  const sample_id &sample) const;
	bool light_point(const light &li, int index, const dvec3 &p, int depth,
			 const sample_id &sample, dvec3 *point) const;
	void secondary_colors(const material &m, const dvec3 &c, const dvec3 &p, const dvec3 &n,
			      const dvec3 &n_face, const dvec3 &d, bool inside, int depth,
			      const sample_id &sample, dvec3 *reflected, dvec3 *refracted) const;

	std::vector<material> materials;
	std::vector<sphere> spheres;
	std::vector<triangle> triangles;
	std::vector<plane> planes;
	std::vector<light> lights;
	std::vector<texture> textures;
	dvec3 background;
	dvec3 ambient;
	double epsilon;
	int max_depth;
	dvec3 origin; /* the world point at this tracer's 0 */
};

/* Every position is taken relative to origin (the camera's eye), in
 * double, as the host does for the device (RENDERING.md, "Coordinates on the
 * device"): in world coordinates a unit sphere at x = 1e13 has points 2^-9
 * apart, and p + epsilon·n (1e-4) is p itself, so its shadow rays started on
 * the sphere and it shadowed itself (issue 39 finding 8). */
tracer::tracer(const struct scene &sc, int max_depth_, const dvec3 &origin_)
    : background(to_dvec3(sc.background)), ambient(to_dvec3(sc.ambient)), epsilon(sc.epsilon),
      max_depth(max_depth_), origin(origin_)
{
	for (int i = 0; i < sc.material_count; i++) {
		const scene_material &m = sc.materials[i];
		materials.push_back({to_dvec3(m.color), m.ambient, m.diffuse, m.specular,
				     m.shininess, m.reflect, m.transmit, m.ior, m.fresnel,
				     m.texture - 1, m.alpha_texture - 1, m.alpha_cutoff,
				     m.alpha_scale});
	}
	for (int i = 0; i < sc.texture_count; i++) {
		const scene_texture &t = sc.textures[i];
		textures.push_back({&t, t.width, t.height, t.wrap_s, t.wrap_t});
	}
	for (int i = 0; i < sc.sphere_count; i++) {
		const scene_sphere &s = sc.spheres[i];
		spheres.push_back(
			{to_dvec3(s.center) - origin, s.radius, s.radius * s.radius, s.material});
	}
	for (int i = 0; i < sc.plane_count; i++) {
		const scene_plane &p = sc.planes[i];
		dvec3 normal = to_dvec3(p.normal);
		planes.push_back({to_dvec3(p.point) - origin, normal, p.material, p.has_checker != 0,
				  p.checker_size, to_dvec3(p.checker_color), largest_axis(normal)});
	}
	for (int i = 0; i < sc.triangle_count; i++) {
		const scene_triangle &t = sc.triangles[i];
		dvec3 v0 = to_dvec3(t.v[0]) - origin, v1 = to_dvec3(t.v[1]) - origin,
		      v2 = to_dvec3(t.v[2]) - origin;
		triangles.push_back(
			{v0,
			 v1,
			 v2,
			 glm::normalize(glm::cross(v1 - v0, v2 - v0)),
			 {to_dvec3(t.normal[0]), to_dvec3(t.normal[1]), to_dvec3(t.normal[2])},
			 t.smooth != 0,
			 t.material,
			 {}});
		if (sc.triangle_uvs)
			for (int k = 0; k < 3; k++)
				triangles.back().uv[k] = glm::dvec2(sc.triangle_uvs[i].uv[k][0],
								    sc.triangle_uvs[i].uv[k][1]);
	}
	for (int i = 0; i < sc.light_count; i++) {
		const scene_light &l = sc.lights[i];
		lights.push_back({to_dvec3(l.position) - origin, to_dvec3(l.color), l.radius,
				  l.directional != 0, -to_dvec3(l.direction),
				  std::tan(glm::radians(l.angle))});
	}
}

/* Step 1. Spheres are tested first, then triangles, then planes, each in
 * scene order, and only a strictly smaller t replaces a hit, so an exact tie
 * goes to the object listed first. Returns false when nothing is hit. */
bool tracer::nearest_hit(const dvec3 &o, const dvec3 &d, hit *out) const
{
	hit best = {0.0, nullptr, nullptr, nullptr, 0.0, 0.0};
	for (const sphere &s : spheres) {
		double t = intersect_sphere(s, o, d);
		if (t > 0.0 && (best.t == 0.0 || t < best.t))
			best = {t, &s, nullptr, nullptr, 0.0, 0.0};
	}
	for (const triangle &tri : triangles) {
		double u, v, t = intersect_triangle(tri, o, d, &u, &v);
		if (t > 0.0 && (best.t == 0.0 || t < best.t) && !cut_out(tri, u, v))
			best = {t, nullptr, nullptr, &tri, u, v};
	}
	for (const plane &p : planes) {
		double t = intersect_plane(p, o, d);
		if (t > 0.0 && (best.t == 0.0 || t < best.t))
			best = {t, nullptr, &p, nullptr, 0.0, 0.0};
	}
	*out = best;
	return best.t > 0.0;
}

/* Whether any object (transparent ones too) lies on the ray at 0 < t < distance. */
bool tracer::blocked(const dvec3 &o, const dvec3 &d, double distance) const
{
	for (const sphere &s : spheres) {
		double t = intersect_sphere(s, o, d);
		if (t > 0.0 && t < distance)
			return true;
	}
	for (const triangle &tri : triangles) {
		double u, v, t = intersect_triangle(tri, o, d, &u, &v);
		if (t > 0.0 && t < distance && !cut_out(tri, u, v))
			return true;
	}
	for (const plane &p : planes) {
		double t = intersect_plane(p, o, d);
		if (t > 0.0 && t < distance)
			return true;
	}
	return false;
}

/* RENDERING.md, "Textures": the texture coordinates at barycentric (u, v). */
glm::dvec2 triangle_uv(const triangle &tri, double u, double v)
{
	return (1.0 - u - v) * tri.uv[0] + u * tri.uv[1] + v * tri.uv[2];
}

/* RENDERING.md, "Alpha cut-out": whether the triangle's material leaves it
 * out at barycentric (u, v). */
bool tracer::cut_out(const triangle &tri, double u, double v) const
{
	const material &m = materials[tri.material];

	if (!(m.alpha_cutoff > 0))
		return false;
	double alpha = m.alpha_scale;
	if (m.alpha_texture >= 0)
		alpha *= lookup(textures[m.alpha_texture], triangle_uv(tri, u, v)).a;
	return alpha < m.alpha_cutoff;
}

/* Step 3: the material colour (times its texture on a triangle), or the
 * checker colour on the odd squares of a checkered plane. */
dvec3 tracer::base_color(const hit &h, const dvec3 &p) const
{
	if (h.sphere)
		return materials[h.sphere->material].color;
	if (h.tri) {
		const material &m = materials[h.tri->material];
		if (m.texture < 0)
			return m.color;
		return m.color * dvec3(lookup(textures[m.texture], triangle_uv(*h.tri, h.u, h.v)));
	}

	const plane &pl = *h.plane;
	if (!pl.has_checker)
		return materials[pl.material].color;

	/* The squares lie where the world has them. */
	dvec3 w = p + origin;
	double s, t;
	switch (pl.dropped_axis) {
	case 0:
		s = w.y, t = w.z;
		break;
	case 1:
		s = w.x, t = w.z;
		break;
	default:
		s = w.x, t = w.y;
		break;
	}
	/* Both floors are whole numbers, so their sum is exact (below 2^53) and
	 * fmod gives its parity without any integer overflow. */
	double cells = std::floor(s / pl.checker_size) + std::floor(t / pl.checker_size);
	bool odd = std::fmod(std::fabs(cells), 2.0) == 1.0;
	return odd ? pl.checker_color : materials[pl.material].color;
}

/* RENDERING.md step 2 on a triangle: the shading normal, interpolated from
 * the vertex normals at the barycentric (u, v) of the hit, and turned to the
 * side of the surface the ray is on (n_face, the geometric normal facing the
 * ray). A flat triangle's is n_face itself. */
dvec3 shading_normal(const triangle &tri, double u, double v, const dvec3 &n_face)
{
	if (!tri.smooth)
		return n_face;
	dvec3 n = (1.0 - u - v) * tri.normal[0] + u * tri.normal[1] + v * tri.normal[2];
	if (n == dvec3(0.0))
		return n_face;
	n = glm::normalize(n);
	return glm::dot(n, n_face) < 0.0 ? -n : n;
}

dvec3 tracer::trace(const dvec3 &o, const dvec3 &d, int depth, const sample_id &sample) const
{
	/* 1. */
	hit h;
	if (!nearest_hit(o, d, &h))
		return background;

	/* 2. */
	dvec3 p = o + h.t * d;
	/* RENDERING.md's (p - center)/radius, which is unit length only while p
	 * lies on the sphere. From an origin far from a small sphere (a ray coming
	 * back from the wall of a sphere of radius 1e18), b*b - c in
	 * intersect_sphere cancels to noise and p can miss the surface by orders
	 * of magnitude more than the radius; a normal of length 1e10 then makes
	 * pow(n.H, shininess) inf. Normalising gives the same n on the surface. */
	dvec3 n_g = h.sphere ? glm::normalize(p - h.sphere->center)
		    : h.tri  ? h.tri->n_g
			     : h.plane->normal;
	bool inside = glm::dot(n_g, d) > 0.0;
	dvec3 n_face = inside ? -n_g : n_g;
	dvec3 n = h.tri ? shading_normal(*h.tri, h.u, h.v, n_face) : n_face;
	int material_index = h.sphere ? h.sphere->material
			     : h.tri  ? h.tri->material
				      : h.plane->material;
	const material &m = materials[material_index];

	/* 3. */
	dvec3 c = base_color(h, p);

	/* 4. */
	dvec3 color = local_color(m, c, p, n, n_face, d, depth, sample);

	/* 5. (in the order of the sums before this function was split) */
	if (depth < max_depth) {
		dvec3 reflected, refracted;
		secondary_colors(m, c, p, n, n_face, d, inside, depth, sample, &reflected,
				 &refracted);
		color += reflected;
		color += refracted;
	}

	/* 6. */
	return color;
}

/* RENDERING.md, "Light samples": the offset size*(a*b1 + b*b2) of the
 * sample's point on the disk across unit w, (a, b) from the pair of light
 * `index` at this depth. */
dvec3 disk_offset(const dvec3 &w, double size, int pair, const sample_id &sample)
{
	glm::dvec2 disk = sample_disk(sample.x, sample.y, sample.k, sample.n, pair);
	double sign = std::copysign(1.0, w.z);
	double e = -1.0 / (sign + w.z);
	double g = w.x * w.y * e;
	dvec3 b1(1.0 + sign * w.x * w.x * e, sign * g, -sign * w.x);
	dvec3 b2(g, sign + w.y * w.y * e, -w.y);
	return size * disk.x * b1 + size * disk.y * b2;
}

/* The point of light li that the sample's shadow ray from p goes to: the
 * position itself for a point light, a point of the disk of a sphere light
 * facing p; for a directional light, p plus the sampled unit direction
 * towards it. Returns false when the light adds nothing (p at a sphere
 * light's centre). */
bool tracer::light_point(const light &li, int index, const dvec3 &p, int depth,
			 const sample_id &sample, dvec3 *point) const
{
	int pair = 2 + depth * (int)lights.size() + index;

	if (li.directional) {
		dvec3 L = li.toward;
		if (li.tan_angle > 0)
			L = glm::normalize(L + disk_offset(L, li.tan_angle, pair, sample));
		*point = p + L;
		return true;
	}
	*point = li.position;
	if (li.radius > 0) {
		if (li.position == p)
			return false;
		*point += disk_offset(glm::normalize(li.position - p), li.radius, pair, sample);
	}
	return true;
}

/* RENDERING.md trace step 4: ambient, then each light not in shadow. */
dvec3 tracer::local_color(const material &m, const dvec3 &c, const dvec3 &p, const dvec3 &n,
			  const dvec3 &n_face, const dvec3 &d, int depth,
			  const sample_id &sample) const
{
	dvec3 color = m.ka * c * ambient;
	/* Off the surface along the geometric normal (n itself but on a smooth
	 * triangle), so that the shadow ray starts on the ray's side of it. */
	dvec3 shadow_origin = p + epsilon * n_face;
	for (size_t i = 0; i < lights.size(); i++) {
		const light &li = lights[i];
		dvec3 point;
		if (!light_point(li, (int)i, p, depth, sample, &point))
			continue;
		if (li.directional) {
			/* No distance: anything along the way shadows p. */
			if (blocked(shadow_origin, point - p, HUGE_VAL))
				continue;
		} else {
			/* The shadow ray runs from shadow_origin straight to the
			 * light, and t is measured along it, so "distance" is from
			 * shadow_origin. */
			dvec3 to_light = point - shadow_origin;
			double distance = glm::length(to_light);
			if (distance > 0.0 && blocked(shadow_origin, to_light / distance, distance))
				continue;
		}

		dvec3 surface_to_light = point - p;
		if (surface_to_light == dvec3(0.0))
			continue; /* light exactly at p: L is undefined */
		dvec3 L = glm::normalize(surface_to_light);
		color += m.kd * std::max(0.0, glm::dot(n, L)) * c * li.color;

		dvec3 half = L - d;
		if (half != dvec3(0.0)) { /* L == d: no half vector, no specular term */
			dvec3 H = glm::normalize(half);
			color += m.ks * std::pow(std::max(0.0, glm::dot(n, H)), m.shininess) *
				 li.color;
		}
	}
	return color;
}

/* RENDERING.md trace step 5: the colours of the reflected and refracted
 * rays, weighted (zero where there is none).
 *
 * R and T are unit vectors in exact arithmetic, but trace() needs
 * |d| = 1 to the last bit: intersect_sphere solves t^2 + 2bt + c = 0,
 * which holds only for a unit d. Unnormalised, the rounding error of |d|
 * grew about 16-fold per bounce (1e-16 at the camera, 0.3 at depth 13 of
 * two_balls.json), hits landed off the surfaces, the normals
 * (p - center)/radius lost unit length and the colours went to inf past
 * depth 20. Normalising each new direction keeps the error at 1 ulp. */
void tracer::secondary_colors(const material &m, const dvec3 &c, const dvec3 &p, const dvec3 &n,
			      const dvec3 &n_face, const dvec3 &d, bool inside, int depth,
			      const sample_id &sample, dvec3 *reflected, dvec3 *refracted) const
{
	double reflect_weight = m.kr, transmit_weight = m.kt;

	*reflected = *refracted = dvec3(0.0);
	if (m.kt > 0.0) {
		double eta = inside ? m.ior : 1.0 / m.ior;
		double cos_i = -glm::dot(d, n);
		double k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
		if (k < 0.0) {
			reflect_weight += m.kt; /* total internal reflection */
		} else {
			/* RENDERING.md's T = eta*d + (eta*c - sqrt(k))*n, grouped
			 * as eta*(d + c*n) - sqrt(k)*n: d + c*n is d's part along
			 * the surface, of length sin(i), so no two large terms
			 * cancel (with ior 1e18 at normal incidence the written
			 * order gives 1e18*d - 1e18*d = 0, and no direction). */
			if (m.fresnel == SCENE_FRESNEL_DIELECTRIC) {
				/* RENDERING.md, "Fresnel": the cosine on the thinner side */
				double r0 = (m.ior - 1.0) / (m.ior + 1.0);
				double cos_thin = eta > 1.0 ? std::sqrt(k) : cos_i;
				double f = r0 * r0 + (1.0 - r0 * r0) * std::pow(1.0 - cos_thin, 5.0);
				reflect_weight += f * m.kt;
				transmit_weight = (1.0 - f) * m.kt;
			}
			dvec3 T = glm::normalize(eta * (d + cos_i * n) - std::sqrt(k) * n);
			*refracted = transmit_weight * trace(p - epsilon * n_face, T, depth + 1, sample);
		}
	}
	if (reflect_weight > 0.0) {
		dvec3 R = glm::normalize(d - 2.0 * glm::dot(d, n) * n);
		*reflected = reflect_weight * trace(p + epsilon * n_face, R, depth + 1, sample);
		if (m.fresnel == SCENE_FRESNEL_CONDUCTOR) /* tinted by C head-on */
			*reflected *= c + (1.0 - c) * std::pow(1.0 - -glm::dot(d, n), 5.0);
	}
}

/* RENDERING.md's hash of a pixel's coordinates: lowbias32. */
uint32_t sample_hash(uint32_t v)
{
	v = (v ^ (v >> 16)) * 0x7feb352du;
	v = (v ^ (v >> 15)) * 0x846ca68bu;
	return v ^ (v >> 16);
}

/* The Sobol' points as RENDERING.md writes them, through the generator
 * matrices rather than direction numbers: dimension 0's is the identity (the
 * radical inverse), dimension 1's has binomial(i, j) mod 2 in row j, column i
 * (the Pascal matrix), so output bit j (of weight 2^-(j+1)) is the XOR of the
 * bits i >= j of k with odd binomial(i, j), that is with (i & j) == j. */
uint32_t sobol_point(uint32_t k, int dimension)
{
	uint32_t r = 0;

	for (int j = 0; j < 32; j++) {
		uint32_t bit = 0;
		for (int i = j; i < 32; i++)
			if ((k >> i) & 1u)
				bit ^= dimension == 0 ? (uint32_t)(i == j)
						      : (uint32_t)((i & j) == j);
		r |= bit << (31 - j);
	}
	return r;
}

/* Kensler's permute of RENDERING.md ("More dimensions"): where i goes in a
 * hashed permutation of 0 ... n-1 seeded by p. */
uint32_t permute(uint32_t i, uint32_t n, uint32_t p)
{
	uint32_t w = n - 1;

	for (int shift = 1; shift <= 16; shift *= 2)
		w |= w >> shift;
	do {
		i ^= p;
		i *= 0xe170893du;
		i ^= p >> 16;
		i ^= (i & w) >> 4;
		i ^= p >> 8;
		i *= 0x0929eb3fu;
		i ^= p >> 23;
		i ^= (i & w) >> 1;
		i *= 1u | p >> 27;
		i *= 0x6935fa69u;
		i ^= (i & w) >> 11;
		i *= 0x74dcb303u;
		i ^= (i & w) >> 2;
		i *= 0x9e501cc3u;
		i ^= (i & w) >> 2;
		i *= 0xc860a3dfu;
		i &= w;
		i ^= i >> 5;
	} while (i >= n);
	return (i + p) % n;
}

/* RENDERING.md's concentric mapping of [0, 1)^2 onto the unit disk. */
glm::dvec2 concentric_disk(double s, double t)
{
	double x = 2.0 * s - 1.0, y = 2.0 * t - 1.0;

	if (x == 0.0 && y == 0.0)
		return glm::dvec2(0.0);
	if (std::fabs(x) > std::fabs(y)) {
		double phi = M_PI / 4.0 * (y / x);
		return glm::dvec2(x * std::cos(phi), x * std::sin(phi));
	}
	double phi = M_PI / 2.0 - M_PI / 4.0 * (x / y);
	return glm::dvec2(y * std::cos(phi), y * std::sin(phi));
}

glm::dvec2 sample_disk(int x, int y, int k, int n, int pair)
{
	double st[2];

	reference_sample_pair(x, y, k, n, pair, st);
	return concentric_disk(st[0], st[1]);
}

} // namespace

extern "C" void reference_sample_pair(int x, int y, int k, int n, int pair, double st[2])
{
	uint32_t scramble_u = sample_hash(sample_hash((uint32_t)x) ^ (uint32_t)y);
	uint32_t seed = sample_hash(scramble_u ^ sample_hash((uint32_t)pair));
	uint32_t a = sample_hash(seed), b = sample_hash(a);
	uint32_t i = permute((uint32_t)k, (uint32_t)n, seed);

	st[0] = std::ldexp((double)((sobol_point(i, 0) ^ a) >> 8), -24);
	st[1] = std::ldexp((double)((sobol_point(i, 1) ^ b) >> 8), -24);
}

extern "C" void reference_sample_position(int x, int y, int k, int n, double uv[2])
{
	if (n == 1) {
		uv[0] = uv[1] = 0.5;
		return;
	}
	uint32_t scramble_u = sample_hash(sample_hash((uint32_t)x) ^ (uint32_t)y);
	uint32_t scramble_v = sample_hash(scramble_u);
	uv[0] = std::ldexp((double)((sobol_point((uint32_t)k, 0) ^ scramble_u) >> 8), -24);
	uv[1] = std::ldexp((double)((sobol_point((uint32_t)k, 1) ^ scramble_v) >> 8), -24);
}

int reference_render(const struct scene *scene, int width, int height, int max_depth, float *rgb)
{
	return reference_render_samples(scene, width, height, max_depth, 1, rgb);
}

namespace
{

/* Adds sample k of n of every pixel to sums (3 doubles a pixel). */
void add_sample(const tracer &tr, const scene_camera &cam, int width, int height, int k, int n,
		double *sums)
{
	/* The tracer works relative to the eye (its origin, tracer's
	 * constructor): the eye is at 0 there. */
	const dvec3 eye(0.0);
	dvec3 f = glm::normalize(to_dvec3(cam.look_at) - to_dvec3(cam.eye));
	dvec3 r = glm::normalize(glm::cross(f, to_dvec3(cam.up)));
	dvec3 u = glm::cross(r, f);
	double h = std::tan(glm::radians(cam.fov) / 2.0);
	double a = (double)width / (double)height;

	for (int y = 0; y < height; y++) {
		for (int x = 0; x < width; x++) {
			const sample_id sample = {x, y, k, n};
			double uv[2];
			dvec3 c;
			reference_sample_position(x, y, k, n, uv);
			double sx = (2.0 * (x + uv[0]) / width - 1.0) * a * h;
			double sy = (1.0 - 2.0 * (y + uv[1]) / height) * h;
			dvec3 q = f + sx * r + sy * u;
			if (cam.aperture > 0) {
				/* RENDERING.md, "The thin lens" */
				glm::dvec2 lens = sample_disk(x, y, k, n, 1);
				dvec3 on_lens =
					cam.aperture * lens.x * r + cam.aperture * lens.y * u;
				dvec3 dir = glm::normalize(cam.focus_distance * q - on_lens);
				c = tr.trace(eye + on_lens, dir, 0, sample);
			} else {
				c = tr.trace(eye, glm::normalize(q), 0, sample);
			}
			double *sum = sums + 3 * ((size_t)y * (size_t)width + (size_t)x);
			sum[0] += c.r;
			sum[1] += c.g;
			sum[2] += c.b;
		}
	}
}

} // namespace

extern "C" void reference_mean(const double *sums, size_t values, int samples, float *rgb)
{
	for (size_t i = 0; i < values; i++)
		rgb[i] = (float)(sums[i] / (double)samples);
}

extern "C" int reference_render_sample(const struct scene *scene, int width, int height,
				       int max_depth, int k, int samples, double *sums)
{
	if (!scene || !sums || width < 1 || height < 1 || max_depth < 0 || samples < 1 || k < 0 ||
	    k >= samples)
		return -1;
	try {
		const tracer tr(*scene, max_depth, to_dvec3(scene->camera.eye));
		add_sample(tr, scene->camera, width, height, k, samples, sums);
	} catch (const std::bad_alloc &) {
		return -1;
	}
	return 0;
}

int reference_render_samples(const struct scene *scene, int width, int height, int max_depth,
			     int samples, float *rgb)
{
	if (!scene || !rgb || width < 1 || height < 1 || max_depth < 0 || samples < 1)
		return -1;

	size_t values = (size_t)width * (size_t)height * 3;
	try {
		const tracer tr(*scene, max_depth, to_dvec3(scene->camera.eye));
		std::vector<double> sums(values, 0.0);
		/* Sample by sample over the image, each pixel's samples added in
		 * order: the mean of a pixel's samples, as render_reference's
		 * passes take it. */
		for (int k = 0; k < samples; k++)
			add_sample(tr, scene->camera, width, height, k, samples, sums.data());
		reference_mean(sums.data(), values, samples, rgb);
	} catch (const std::bad_alloc &) {
		return -1;
	}
	return 0;
}
