/* The CPU reference's scene, ray queries and sample sequence (see
 * reference_scene.h). Each rule cites the RENDERING.md section it follows.
 */
#include "render/reference_scene.h"

#include "render/reference.h"

#include <algorithm>
#include <cmath>

namespace reference
{

namespace
{

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
	if (tex.t->is_linear) /* numbers, not colours: metallic-roughness */
		return glm::dvec4(c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, c[3] / 255.0);
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
	int i0 = wrap_index(i, tex.width, tex.wrap_s),
	    i1 = wrap_index(i + 1, tex.width, tex.wrap_s);
	int j0 = wrap_index(j, tex.height, tex.wrap_t),
	    j1 = wrap_index(j + 1, tex.height, tex.wrap_t);
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

/* RENDERING.md, "Textures": the texture coordinates at barycentric (u, v). */
dvec2 triangle_uv(const triangle &tri, double u, double v)
{
	return (1.0 - u - v) * tri.uv[0] + u * tri.uv[1] + v * tri.uv[2];
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

} // namespace

/* Every position is taken relative to origin (the camera's eye), in
 * double, as the host does for the device (RENDERING.md, "Coordinates on the
 * device"): in world coordinates a unit sphere at x = 1e13 has points 2^-9
 * apart, and p + epsilon·n (1e-4) is p itself, so its shadow rays started on
 * the sphere and it shadowed itself (issue 39 finding 8). Both integrators
 * work here: the path tracer's emitters and lights are these objects. */
scene_geometry::scene_geometry(const struct scene &sc, const dvec3 &origin_)
    : background(to_dvec3(sc.background)), ambient(to_dvec3(sc.ambient)), epsilon(sc.epsilon),
      origin(origin_)
{
	for (int i = 0; i < sc.material_count; i++) {
		const scene_material &m = sc.materials[i];
		materials.push_back({to_dvec3(m.color), m.ambient, m.diffuse, m.specular,
				     m.shininess, m.reflect, m.transmit, m.ior, m.fresnel,
				     m.texture - 1, m.alpha_texture - 1, m.alpha_cutoff,
				     m.alpha_scale, m.bsdf, to_dvec3(m.emission),
				     m.metallic_roughness_texture - 1, m.emissive_texture - 1,
				     m.normal_texture - 1});
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
		planes.push_back({to_dvec3(p.point) - origin, normal, p.material,
				  p.has_checker != 0, p.checker_size, to_dvec3(p.checker_color),
				  largest_axis(normal)});
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
				  l.directional != 0, -to_dvec3(l.direction), glm::radians(l.angle),
				  std::tan(glm::radians(l.angle))});
	}
}

/* Step 1. Spheres are tested first, then triangles, then planes, each in
 * scene order, and only a strictly smaller t replaces a hit, so an exact tie
 * goes to the object listed first. Returns false when nothing is hit. */
bool scene_geometry::nearest_hit(const dvec3 &o, const dvec3 &d, hit *out) const
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

/* Whether any object (transparent ones too) lies on the ray at 0 < t <
 * distance, but `skip` (a sphere or a triangle of the scene, or null). */
bool scene_geometry::blocked(const dvec3 &o, const dvec3 &d, double distance,
			     const void *skip) const
{
	for (const sphere &s : spheres) {
		double t = intersect_sphere(s, o, d);
		if (t > 0.0 && t < distance && &s != skip)
			return true;
	}
	for (const triangle &tri : triangles) {
		double u, v, t = intersect_triangle(tri, o, d, &u, &v);
		if (t > 0.0 && t < distance && &tri != skip && !cut_out(tri, u, v))
			return true;
	}
	for (const plane &p : planes) {
		double t = intersect_plane(p, o, d);
		if (t > 0.0 && t < distance)
			return true;
	}
	return false;
}

/* RENDERING.md, "Alpha cut-out": whether the triangle's material leaves it
 * out at barycentric (u, v). */
bool scene_geometry::cut_out(const triangle &tri, double u, double v) const
{
	const material &m = materials[tri.material];

	if (!(m.alpha_cutoff > 0))
		return false;
	double alpha = m.alpha_scale;
	if (m.alpha_texture >= 0)
		alpha *= lookup(textures[m.alpha_texture], triangle_uv(tri, u, v)).a;
	return alpha < m.alpha_cutoff;
}
/* RENDERING.md "Textures": the base colour texture's RGB at a triangle hit,
 * 1 elsewhere. */
dvec3 scene_geometry::texture_rgb(const hit &h) const
{
	if (!h.tri)
		return dvec3(1.0);
	const material &m = materials[h.tri->material];
	if (m.texture < 0)
		return dvec3(1.0);
	return dvec3(lookup(textures[m.texture], triangle_uv(*h.tri, h.u, h.v)));
}

glm::dvec4 scene_geometry::texture_at(int index, const triangle &tri, double u, double v) const
{
	return lookup(textures[index], triangle_uv(tri, u, v));
}

/* Trace step 3: whether p is on an odd square of a checkered plane: drop
 * the world axis of the normal's largest |component|, the other two in x,
 * y, z order are (s, t). */
bool scene_geometry::odd_checker_square(const hit &h, const dvec3 &p) const
{
	if (!h.plane || !h.plane->has_checker)
		return false;
	const plane &pl = *h.plane;
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
	return std::fmod(std::fabs(cells), 2.0) == 1.0;
}

/* Step 3: the material colour (times its texture on a triangle), or the
 * checker colour on the odd squares of a checkered plane. */
dvec3 scene_geometry::base_color(const hit &h, const dvec3 &p) const
{
	if (h.sphere)
		return materials[h.sphere->material].color;
	if (h.tri)
		return materials[h.tri->material].color * texture_rgb(h);
	if (odd_checker_square(h, p))
		return h.plane->checker_color;
	return materials[h.plane->material].color;
}

/* Step 2. */
surface scene_geometry::surface_at(const hit &h, const dvec3 &o, const dvec3 &d) const
{
	surface s;
	s.p = o + h.t * d;
	/* RENDERING.md's (p - center)/radius, which is unit length only while p
	 * lies on the sphere. From an origin far from a small sphere (a ray coming
	 * back from the wall of a sphere of radius 1e18), b*b - c in
	 * intersect_sphere cancels to noise and p can miss the surface by orders
	 * of magnitude more than the radius; a normal of length 1e10 then makes
	 * pow(n.H, shininess) inf. Normalising gives the same n on the surface. */
	s.n_g = h.sphere ? glm::normalize(s.p - h.sphere->center)
		: h.tri	 ? h.tri->n_g
			 : h.plane->normal;
	s.inside = glm::dot(s.n_g, d) > 0.0;
	s.n_face = s.inside ? -s.n_g : s.n_g;
	s.n = h.tri ? shading_normal(*h.tri, h.u, h.v, s.n_face) : s.n_face;
	s.material = h.sphere ? h.sphere->material : h.tri ? h.tri->material : h.plane->material;
	s.object = h.sphere ? (const void *)h.sphere : (const void *)h.tri;
	return s;
}

camera::camera(const struct scene_camera &cam, int width_, int height_, const dvec3 &origin)
    : eye(to_dvec3(cam.eye) - origin), aperture(cam.aperture), focus_distance(cam.focus_distance),
      width(width_), height(height_)
{
	/* The view's directions from the world's points (one rounding each). */
	f = glm::normalize(to_dvec3(cam.look_at) - to_dvec3(cam.eye));
	r = glm::normalize(glm::cross(f, to_dvec3(cam.up)));
	u = glm::cross(r, f);
	h = std::tan(glm::radians(cam.fov) / 2.0);
	a = (double)width / (double)height;
}

void camera::primary_ray(const sample_id &sample, dvec3 *o, dvec3 *d) const
{
	double uv[2];
	reference_sample_position(sample.x, sample.y, sample.k, sample.n, uv);
	double sx = (2.0 * (sample.x + uv[0]) / width - 1.0) * a * h;
	double sy = (1.0 - 2.0 * (sample.y + uv[1]) / height) * h;
	dvec3 q = f + sx * r + sy * u;
	if (aperture > 0) {
		/* RENDERING.md, "The thin lens" */
		dvec2 st = sample_pair(sample, 1);
		dvec2 lens = concentric_disk(st.x, st.y);
		dvec3 on_lens = aperture * lens.x * r + aperture * lens.y * u;
		*o = eye + on_lens;
		*d = glm::normalize(focus_distance * q - on_lens);
		return;
	}
	*o = eye;
	*d = glm::normalize(q);
}

/* RENDERING.md, "More dimensions": pair j >= 1 of sample k is the sequence's
 * point permute(k) scrambled by the pair's own hashes. */
void sample_pair_bits(const sample_id &sample, int pair, uint32_t bits[2])
{
	uint32_t scramble_u = sample_hash(sample_hash((uint32_t)sample.x) ^ (uint32_t)sample.y);
	uint32_t seed = sample_hash(scramble_u ^ sample_hash((uint32_t)pair));
	uint32_t a = sample_hash(seed), b = sample_hash(a);
	uint32_t i = permute((uint32_t)sample.k, (uint32_t)sample.n, seed);

	bits[0] = (sobol_point(i, 0) ^ a) >> 8;
	bits[1] = (sobol_point(i, 1) ^ b) >> 8;
}

dvec2 sample_pair(const sample_id &sample, int pair)
{
	uint32_t bits[2];

	sample_pair_bits(sample, pair, bits);
	return dvec2(std::ldexp((double)bits[0], -24), std::ldexp((double)bits[1], -24));
}

/* RENDERING.md's concentric mapping of [0, 1)^2 onto the unit disk. */
dvec2 concentric_disk(double s, double t)
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
void frame_across(const dvec3 &w, dvec3 *b1, dvec3 *b2)
{
	double sign = std::copysign(1.0, w.z);
	double e = -1.0 / (sign + w.z);
	double g = w.x * w.y * e;
	*b1 = dvec3(1.0 + sign * w.x * w.x * e, sign * g, -sign * w.x);
	*b2 = dvec3(g, sign + w.y * w.y * e, -w.y);
}

} // namespace reference

/* reference.h's: the sample sequence for tests and the camera. */
extern "C" void reference_sample_pair(int x, int y, int k, int n, int pair, double st[2])
{
	reference::dvec2 v = reference::sample_pair({x, y, k, n}, pair);
	st[0] = v.x;
	st[1] = v.y;
}

extern "C" void reference_sample_position(int x, int y, int k, int n, double uv[2])
{
	using reference::sample_hash;
	using reference::sobol_point;

	if (n == 1) {
		uv[0] = uv[1] = 0.5;
		return;
	}
	uint32_t scramble_u = sample_hash(sample_hash((uint32_t)x) ^ (uint32_t)y);
	uint32_t scramble_v = sample_hash(scramble_u);
	uv[0] = std::ldexp((double)((sobol_point((uint32_t)k, 0) ^ scramble_u) >> 8), -24);
	uv[1] = std::ldexp((double)((sobol_point((uint32_t)k, 1) ^ scramble_v) >> 8), -24);
}
