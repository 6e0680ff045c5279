/* CPU reference renderer (see reference.h).
 *
 * Each numbered step of RENDERING.md's trace() is marked below with its
 * number, so the two can be read side by side. Clarity comes before speed:
 * the only optimisation is converting the scene once into GLM vectors
 * (reference_scene.cpp). The path integrator is reference_path.cpp.
 */
#include "render/reference.h"

#include "render/reference_path.h"
#include "render/reference_scene.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <new>
#include <vector>

namespace
{

using namespace reference;

/* RENDERING.md's trace(): the Whitted integrator. */
class tracer : public scene_geometry
{
      public:
	/* The scene relative to origin (the eye): see scene_geometry. May
	 * throw std::bad_alloc. */
	tracer(const struct scene &sc, int max_depth_, const dvec3 &origin)
	    : scene_geometry(sc, origin), max_depth(max_depth_)
	{
	}

	dvec3 trace(const dvec3 &o, const dvec3 &d, int depth, const sample_id &sample) const;

      private:
	dvec3 local_color(const material &m, const dvec3 &c, const dvec3 &p, const dvec3 &n,
			  const dvec3 &n_face, const dvec3 &d, int depth,
			  const sample_id &sample) const;
	bool light_point(const light &li, int index, const dvec3 &p, int depth,
			 const sample_id &sample, dvec3 *point) const;
	void secondary_colors(const material &m, const dvec3 &c, const dvec3 &p, const dvec3 &n,
			      const dvec3 &n_face, const dvec3 &d, bool inside, int depth,
			      const sample_id &sample, dvec3 *reflected, dvec3 *refracted) const;

	int max_depth;
};

dvec3 tracer::trace(const dvec3 &o, const dvec3 &d, int depth, const sample_id &sample) const
{
	/* 1. */
	hit h;
	if (!nearest_hit(o, d, &h))
		return background;

	/* 2. */
	surface s = surface_at(h, o, d);
	const dvec3 &p = s.p, &n_face = s.n_face, &n = s.n;
	const material &m = materials[s.material];

	/* 3. */
	dvec3 c = base_color(h, p);

	/* 4. */
	dvec3 color = local_color(m, c, p, n, n_face, d, depth, sample);

	/* 5. (in the order of the sums before this function was split) */
	if (depth < max_depth) {
		dvec3 reflected, refracted;
		secondary_colors(m, c, p, n, n_face, d, s.inside, depth, sample, &reflected,
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
	dvec2 st = sample_pair(sample, pair);
	dvec2 disk = concentric_disk(st.x, st.y);
	dvec3 b1, b2;
	frame_across(w, &b1, &b2);
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
				double f =
					r0 * r0 + (1.0 - r0 * r0) * std::pow(1.0 - cos_thin, 5.0);
				reflect_weight += f * m.kt;
				transmit_weight = (1.0 - f) * m.kt;
			}
			dvec3 T = glm::normalize(eta * (d + cos_i * n) - std::sqrt(k) * n);
			*refracted =
				transmit_weight * trace(p - epsilon * n_face, T, depth + 1, sample);
		}
	}
	if (reflect_weight > 0.0) {
		dvec3 R = glm::normalize(d - 2.0 * glm::dot(d, n) * n);
		*reflected = reflect_weight * trace(p + epsilon * n_face, R, depth + 1, sample);
		if (m.fresnel == SCENE_FRESNEL_CONDUCTOR) /* tinted by C head-on */
			*reflected *= c + (1.0 - c) * std::pow(1.0 - -glm::dot(d, n), 5.0);
	}
}

/* RENDERING.md "Camera and pixels", "The thin lens": adds sample k of n of
 * every pixel, radiance(o, d, sample) of its primary ray, to sums (3 doubles
 * a pixel). The camera works relative to the eye, as the integrators' scene
 * does (scene_geometry): the eye is at 0 there. */
template <typename Radiance>
void add_sample(const struct scene *scene, int width, int height, int k, int n, double *sums,
		const Radiance &radiance)
{
	const camera cam(scene->camera, width, height, to_dvec3(scene->camera.eye));

	for (int y = 0; y < height; y++) {
		for (int x = 0; x < width; x++) {
			const sample_id sample = {x, y, k, n};
			dvec3 o, d;
			cam.primary_ray(sample, &o, &d);
			dvec3 c = radiance(o, d, sample);
			double *sum = sums + 3 * ((size_t)y * (size_t)width + (size_t)x);
			sum[0] += c.r;
			sum[1] += c.g;
			sum[2] += c.b;
		}
	}
}

/* Adds samples first ... last - 1 of n of every pixel to sums by the
 * scene's integrator, over the image one sample at a time (each pixel's
 * samples added in order), its scene relative to the eye. May throw
 * std::bad_alloc. */
void add_samples(const struct scene *scene, int width, int height, int max_depth, int first,
		 int last, int n, double *sums)
{
	const dvec3 origin = to_dvec3(scene->camera.eye);

	if (scene->integrator == SCENE_INTEGRATOR_PATH) {
		const path_tracer pt(*scene, max_depth, origin);
		for (int k = first; k < last; k++)
			add_sample(scene, width, height, k, n, sums,
				   [&pt](const dvec3 &o, const dvec3 &d, const sample_id &s) {
					   return pt.radiance(o, d, s);
				   });
	} else {
		const tracer tr(*scene, max_depth, origin);
		for (int k = first; k < last; k++)
			add_sample(scene, width, height, k, n, sums,
				   [&tr](const dvec3 &o, const dvec3 &d, const sample_id &s) {
					   return tr.trace(o, d, 0, s);
				   });
	}
}

} // namespace

int reference_render(const struct scene *scene, int width, int height, int max_depth, float *rgb)
{
	return reference_render_samples(scene, width, height, max_depth, 1, rgb);
}

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
		add_samples(scene, width, height, max_depth, k, k + 1, samples, sums);
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
		std::vector<double> sums(values, 0.0);
		/* Sample by sample over the image, each pixel's samples added in
		 * order: the mean of a pixel's samples, as render_reference's
		 * passes take it. */
		add_samples(scene, width, height, max_depth, 0, samples, samples, sums.data());
		reference_mean(sums.data(), values, samples, rgb);
	} catch (const std::bad_alloc &) {
		return -1;
	}
	return 0;
}
