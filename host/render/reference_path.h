/* The CPU reference's path integrator (C++ only): RENDERING.md "Path
 * tracing", written from that section alone, in double precision.
 */
#ifndef RTCL_REFERENCE_PATH_H
#define RTCL_REFERENCE_PATH_H

#include "render/reference_scene.h"

#include <vector>

namespace reference
{

/* A BSDF at a hit, its colours taken there (RENDERING.md "The BSDFs"). */
struct bsdf {
	enum kind { DIFFUSE, CONDUCTOR, DIELECTRIC, PRINCIPLED, MAPPED } type;
	dvec3 color;	 /* diffuse and mapped rho, conductor F0, principled base */
	double alpha;	 /* GGX width */
	bool smooth;	 /* conductor, dielectric: alpha < 0.001, delta lobes */
	double eta;	 /* dielectric, principled: eta_t / eta_i for this side */
	double ior;	 /* principled: F0_d's */
	double metallic; /* principled */
	double transmission;
	double kr;		 /* mapped: the mirror's probability */
	dvec3 mirror;		 /* mapped: the mirror's reflectance at wo */
	dvec3 n, n_face, b1, b2; /* the shading normal, its frame, n_face */
};

/* What bsdf sample returns (RENDERING.md "The BSDFs"). */
struct bsdf_sample {
	dvec3 wi;
	dvec3 weight; /* f |wi.n| / pdf */
	double pdf;
	bool delta;
	bool transmitted; /* the lobe taken transmits */
};

/* One light sample of next_event (RENDERING.md "next_event(i)"). */
struct light_sample {
	dvec3 l;	     /* unit, from p */
	dvec3 E;	     /* the radiance (or its equivalent) arriving along l */
	double pdf;	     /* solid angle, with 1/G and P_e; for a delta light 1/G */
	double t_max;	     /* how far the shadow ray looks */
	bool mis;	     /* emitters and the environment: weighted by MIS */
	const void *emitter; /* the emitter's sphere or triangle, which does not
				shadow its own point; null for the others */
};

/* RENDERING.md "The environment": what rays that leave the scene see, and
 * the environment as a light: `background` (uniform) or a map. */
class environment
{
      public:
	/* May throw std::bad_alloc. */
	explicit environment(const struct scene &sc);

	/* Le_env(d). */
	dvec3 radiance(const dvec3 &d) const;
	/* pdf_env(d) in solid angle (0 where it is no light). */
	double pdf(const dvec3 &d) const;
	/* A direction by pair B(i) = st. */
	dvec3 sample(dvec2 st) const;
	/* Whether it is a light group: a non-zero background, or a map of
	 * non-zero total weight. */
	bool is_light() const;

      private:
	bool lookup(const dvec3 &d, int *j, int *k, double *sin_theta) const;
	dvec3 direction(double u, double v) const;

	dvec3 background;
	int width, height;		/* 0: no map, the uniform background */
	std::vector<dvec3> texels;	/* E(j, k), row k from the top */
	std::vector<double> weight;	/* w(j, k) */
	std::vector<double> row_cdf;	/* over k, of the rows' summed weights */
	std::vector<double> column_cdf; /* over j within each row */
	double total;			/* the sum of the weights */
	double cos_psi, sin_psi;	/* the turn about +y */
};

class path_tracer : public scene_geometry
{
      public:
	/* The scene relative to origin (the eye), as scene_geometry's. May
	 * throw std::bad_alloc. */
	path_tracer(const struct scene &sc, int max_depth, const dvec3 &origin);

	/* RENDERING.md "The path": one sample's colour for the primary ray. */
	dvec3 radiance(const dvec3 &o, const dvec3 &d, const sample_id &sample) const;

	/* For tests: at the primary ray's hit, the MIS weights of vertex 0's
	 * light sample, w_l, and of the BSDF ray along that same direction when
	 * it finds the same light, w_hit. False when there is no such pair (no
	 * hit, a delta light, f = 0, a blocked or missed light). */
	bool mis_weights(const dvec3 &o, const dvec3 &d, const sample_id &sample, double *w_light,
			 double *w_hit) const;

      private:
	struct emitter {
		const triangle *tri; /* exactly one of tri and sph */
		const sphere *sph;
		double area;
		double weight; /* lum(Le) area */
		double cdf;    /* the sum of the weights up to this one's, over W */
	};

	void apply_normal_texture(const hit &h, surface *s) const;
	bool make_bsdf(const hit &h, const surface &s, const dvec3 &wo, bsdf *b) const;
	dvec3 next_event(const surface &s, const bsdf &b, const dvec3 &wo, int vertex,
			 const sample_id &sample) const;
	bool sample_light(const surface &s, int vertex, const sample_id &sample,
			  light_sample *ls) const;
	bool sample_emitter(const emitter &e, const dvec3 &p, dvec2 st, light_sample *ls) const;
	double emitter_probability(int e) const;
	dvec3 emission(int material, const triangle *tri, double u, double v) const;
	double emitter_pdf(const hit &h, const dvec3 &y, const dvec3 &x) const;
	double environment_pdf(const dvec3 &d) const;

	std::vector<emitter> emitters;
	std::vector<int> triangle_emitter; /* per triangle: its emitter, or -1 */
	std::vector<int> sphere_emitter;
	double emitter_total; /* W */
	int emitters_group;   /* the group's index, or -1 */
	environment env;
	int environment_group;
	int group_count; /* G */
	int max_depth;
};

} // namespace reference

#endif
