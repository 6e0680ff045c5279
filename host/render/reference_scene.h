/* The CPU reference's scene (C++ only): the scene in double-precision GLM
 * vectors, its ray queries, and the pixel's sample sequence, shared by the
 * Whitted tracer (reference.cpp) and the path tracer (reference_path.cpp).
 * Everything here follows docs/RENDERING.md and is written independently of
 * the OpenCL code in cl/.
 */
#ifndef RTCL_REFERENCE_SCENE_H
#define RTCL_REFERENCE_SCENE_H

#include "scene/scene.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace reference
{

using glm::dvec2;
using glm::dvec3;

inline dvec3 to_dvec3(const double v[3])
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
	struct scene_bsdf bsdf; /* the path integrator's (SCENE_BSDF_NONE: mapped) */
	dvec3 emission;
	int metallic_roughness_texture; /* a model's principled material's, or -1 */
	int emissive_texture;		/* or -1 */
	int normal_texture;		/* or -1 */
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
	dvec2 uv[3]; /* texture coordinates at the vertices */
};

struct light {
	dvec3 position; /* a point or sphere light's centre */
	dvec3 color;
	double radius;	  /* a sphere light's; 0: a point light */
	bool directional; /* then: */
	dvec3 toward;	  /* the unit direction towards the light */
	double angle;	  /* its angular radius, radians */
	double tan_angle; /* tan of it */
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

/* RENDERING.md trace step 2 at a hit: the point, the geometric normal, the
 * side the ray came from and the shading normal. */
struct surface {
	dvec3 p;
	dvec3 n_g;
	bool inside; /* dot(n_g, d) > 0: the ray meets the back side */
	dvec3 n_face;
	dvec3 n;
	int material;
	const void *object; /* the sphere or triangle hit; null for a plane */
};

/* The scene as the reference renders it, in double, every position
 * relative to `origin` (the eye; see the constructor): a point p here is the
 * world's p + origin. Directions (normals, directional lights, the
 * environment's) are the world's. */
class scene_geometry
{
      public:
	/* May throw std::bad_alloc. */
	scene_geometry(const struct scene &sc, const dvec3 &origin);

	/* Trace step 1 (cut-outs included); false when nothing is hit. */
	bool nearest_hit(const dvec3 &o, const dvec3 &d, hit *out) const;
	/* Whether any object (transparent ones too, not a cut-out) but
	 * `skip` (a sphere or triangle of this scene) lies on the ray at
	 * 0 < t < distance. */
	bool blocked(const dvec3 &o, const dvec3 &d, double distance,
		     const void *skip = nullptr) const;
	/* Trace step 2 at hit h of the ray (o, d). */
	surface surface_at(const hit &h, const dvec3 &o, const dvec3 &d) const;
	/* Trace step 3: the base colour C at hit h, point p (relative to
	 * origin, as every point here). */
	dvec3 base_color(const hit &h, const dvec3 &p) const;
	/* RENDERING.md "Textures" and "The BSDFs": the base colour texture's
	 * RGB at a triangle hit (1 without), and whether the hit is on an odd
	 * square of a checkered plane. */
	dvec3 texture_rgb(const hit &h) const;
	/* Texture `index` at barycentric (u, v) of a triangle: RGBA, linear. */
	glm::dvec4 texture_at(int index, const triangle &tri, double u, double v) const;
	bool odd_checker_square(const hit &h, const dvec3 &p) const;

	std::vector<material> materials;
	std::vector<sphere> spheres;
	std::vector<triangle> triangles;
	std::vector<plane> planes;
	std::vector<light> lights;
	std::vector<texture> textures;
	dvec3 background;
	dvec3 ambient;
	double epsilon;
	dvec3 origin; /* the world point at this scene's 0 */

      private:
	bool cut_out(const triangle &tri, double u, double v) const;
};

/* The sample being traced: sample k of n of pixel (x, y). */
struct sample_id {
	int x, y, k, n;
};

/* RENDERING.md "Camera and pixels" and "The thin lens": the primary rays of
 * a width x height image, their origins relative to `origin` as
 * scene_geometry's points. */
class camera
{
      public:
	camera(const struct scene_camera &cam, int width, int height, const dvec3 &origin);
	/* Sample k of pixel (x, y)'s ray: origin o, unit direction d. */
	void primary_ray(const sample_id &sample, dvec3 *o, dvec3 *d) const;

      private:
	dvec3 eye, f, r, u;
	double h, a;
	double aperture, focus_distance;
	int width, height;
};

/* Pair `pair` (>= 1) of the sample, RENDERING.md "More dimensions": the two
 * 24-bit integers, and the coordinates in [0, 1)^2 they scale to exactly. */
void sample_pair_bits(const sample_id &sample, int pair, uint32_t bits[2]);
dvec2 sample_pair(const sample_id &sample, int pair);

/* RENDERING.md "The thin lens": the concentric mapping onto the unit disk. */
dvec2 concentric_disk(double s, double t);

/* RENDERING.md "Light samples": Duff et al.'s frame (b1, b2) across unit w. */
void frame_across(const dvec3 &w, dvec3 *b1, dvec3 *b2);

} // namespace reference

#endif
