/* The CPU reference's path integrator (see reference_path.h).
 *
 * Written from docs/RENDERING.md "Path tracing" alone, independently of
 * cl/: each function names the part of that section it computes, so the two
 * can be read side by side. Double precision throughout; the random numbers
 * are the same bits as the kernels' (integer work, one exact scaling), so
 * the two agree sample by sample up to the branches a float and a double
 * comparison take differently.
 */
#include "render/reference_path.h"

#include "render/reference.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <new>

namespace reference
{

namespace
{

const double pi = M_PI;

/* "The random numbers of a path": vertex i's four pairs. */
int pair_light_choice(int vertex) /* A(i): s the group, t the emitter */
{
	return 2 + 4 * vertex;
}
int pair_light_point(int vertex) /* B(i) */
{
	return 3 + 4 * vertex;
}
int pair_direction(int vertex) /* C(i): the BSDF's direction */
{
	return 4 + 4 * vertex;
}
int pair_lobe(int vertex) /* D(i): s the lobe, t Russian roulette */
{
	return 5 + 4 * vertex;
}

/* Notation: lum(c) and max(c). */
double luminance(const dvec3 &c)
{
	return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
}

double max_channel(const dvec3 &c)
{
	return std::max(c.r, std::max(c.g, c.b));
}

bool is_black(const dvec3 &c)
{
	return c.r == 0.0 && c.g == 0.0 && c.b == 0.0;
}

/* "The path": the power heuristic, for a light found by a BSDF ray. */
double w_hit(bool specular, double pdf_prev, double p_light)
{
	if (specular || p_light == 0.0)
		return 1.0;
	double ratio = p_light / pdf_prev;
	return 1.0 / (1.0 + ratio * ratio);
}

/* "next_event(i)": the same heuristic for a light sample. */
double w_light(double p_light, double pdf_bsdf)
{
	double ratio = pdf_bsdf / p_light;
	return 1.0 / (1.0 + ratio * ratio);
}

/* "next_event(i)": cone(w, c_max, s, t), the uniformly sampled cone of
 * cosine c_max around unit w (its pdf is 1 / (2 pi (1 - c_max))). */
dvec3 cone(const dvec3 &w, double c_max, double s, double t)
{
	dvec3 b1, b2;
	frame_across(w, &b1, &b2);
	double cos_theta = 1.0 - s * (1.0 - c_max);
	double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
	double phi = 2.0 * pi * t;
	return sin_theta * std::cos(phi) * b1 + sin_theta * std::sin(phi) * b2 + cos_theta * w;
}

/* 1 - c_max for a sphere of sin^2(theta_max) = sin2 seen from outside, as
 * sin2 / (1 + c_max), which keeps small far spheres from cancelling. */
double one_minus_cos(double sin2, double c_max)
{
	return sin2 / (1.0 + c_max);
}

/* ---- "The BSDFs": the building blocks ---- */

double schlick(double f0, double c)
{
	return f0 + (1.0 - f0) * std::pow(1.0 - c, 5.0);
}

dvec3 schlick(const dvec3 &f0, double c)
{
	return f0 + (1.0 - f0) * std::pow(1.0 - c, 5.0);
}

/* The exact dielectric Fresnel reflectance, c_i = |cosine on the incident
 * side|, eta = eta_t / eta_i. */
double fresnel_dielectric(double c_i, double eta)
{
	double sin2_t = (1.0 - c_i * c_i) / (eta * eta);
	if (sin2_t >= 1.0)
		return 1.0; /* total internal reflection */
	double c_t = std::sqrt(1.0 - sin2_t);
	double r_s = (c_i - eta * c_t) / (c_i + eta * c_t);
	double r_p = (eta * c_i - c_t) / (eta * c_i + c_t);
	return (r_s * r_s + r_p * r_p) / 2.0;
}

/* GGX D(h) of width alpha, h . n = cos_h. */
double ggx_d(double alpha, double cos_h)
{
	if (cos_h <= 0.0)
		return 0.0;
	double a2 = alpha * alpha;
	double k = cos_h * cos_h * (a2 - 1.0) + 1.0;
	return a2 / (pi * k * k);
}

/* Smith's G1(v, h) for v . h = vh, v . n = vn. */
double smith_g1(double alpha, double vh, double vn)
{
	if (vh * vn <= 0.0)
		return 0.0;
	double tan2 = (1.0 - vn * vn) / (vn * vn);
	return 2.0 / (1.0 + std::sqrt(1.0 + alpha * alpha * tan2));
}

/* The visible-normal density D_wo(h). */
double ggx_d_visible(double alpha, const dvec3 &wo, const dvec3 &h, const dvec3 &n)
{
	double oh = glm::dot(wo, h), on = glm::dot(wo, n);
	return smith_g1(alpha, oh, on) * std::max(0.0, oh) * ggx_d(alpha, glm::dot(h, n)) / on;
}

dvec3 reflect(const dvec3 &v, const dvec3 &h)
{
	return 2.0 * glm::dot(v, h) * h - v;
}

/* refract(v, h, eta) for v on h's side; false when there is none. */
bool refract(const dvec3 &v, const dvec3 &h, double eta, dvec3 *out)
{
	double c = glm::dot(v, h);
	double sin2_t = (1.0 - c * c) / (eta * eta);
	if (sin2_t >= 1.0)
		return false;
	*out = -v / eta + (c / eta - std::sqrt(1.0 - sin2_t)) * h;
	return true;
}

/* Heitz's sampling of the visible normals of wo (JCGT 2018), in the local
 * frame of b's shading normal, with (u1, u2) = pair C(i). */
dvec3 sample_visible_normal(const bsdf &b, double alpha, const dvec3 &wo, dvec2 u)
{
	dvec3 wl(glm::dot(wo, b.b1), glm::dot(wo, b.b2), glm::dot(wo, b.n));
	dvec3 V = glm::normalize(dvec3(alpha * wl.x, alpha * wl.y, wl.z));
	double l2 = V.x * V.x + V.y * V.y;
	dvec3 T1 = l2 > 0.0 ? dvec3(-V.y, V.x, 0.0) / std::sqrt(l2) : dvec3(1.0, 0.0, 0.0);
	dvec3 T2 = glm::cross(V, T1);
	double r = std::sqrt(u.x), phi = 2.0 * pi * u.y;
	double t1 = r * std::cos(phi), t2 = r * std::sin(phi);
	double s = (1.0 + V.z) / 2.0;
	t2 = (1.0 - s) * std::sqrt(1.0 - t1 * t1) + s * t2;
	dvec3 N = t1 * T1 + t2 * T2 + std::sqrt(std::max(0.0, 1.0 - t1 * t1 - t2 * t2)) * V;
	dvec3 hl = glm::normalize(dvec3(alpha * N.x, alpha * N.y, std::max(0.0, N.z)));
	return hl.x * b.b1 + hl.y * b.b2 + hl.z * b.n;
}

/* The cosine-weighted hemisphere of Diffuse: the disk of pair C lifted. */
dvec3 sample_cosine(const bsdf &b, dvec2 u)
{
	dvec2 disk = concentric_disk(u.x, u.y);
	double z = std::sqrt(std::max(0.0, 1.0 - disk.x * disk.x - disk.y * disk.y));
	return disk.x * b.b1 + disk.y * b.b2 + z * b.n;
}

/* "The path": a direction's side rules, both normals. */
bool reflection_side(const bsdf &b, const dvec3 &wi)
{
	return glm::dot(wi, b.n) > 0.0 && glm::dot(wi, b.n_face) > 0.0;
}

bool transmission_side(const bsdf &b, const dvec3 &wi)
{
	return glm::dot(wi, b.n) < 0.0 && glm::dot(wi, b.n_face) < 0.0;
}

/* ---- The lobes, f and pdf for a given wi (wi on its side) ---- */

/* Rough conductor: f and pdf of reflection at wi. */
dvec3 conductor_f(const dvec3 &f0, double alpha, const dvec3 &wo, const dvec3 &wi, const dvec3 &n)
{
	dvec3 h = glm::normalize(wo + wi);
	double on = glm::dot(wo, n), in = glm::dot(wi, n), oh = glm::dot(wo, h);
	double g = smith_g1(alpha, oh, on) * smith_g1(alpha, glm::dot(wi, h), in);
	return ggx_d(alpha, glm::dot(h, n)) * schlick(f0, oh) * g / (4.0 * on * in);
}

double reflection_pdf(double alpha, const dvec3 &wo, const dvec3 &wi, const dvec3 &n)
{
	dvec3 h = glm::normalize(wo + wi);
	return ggx_d_visible(alpha, wo, h, n) / (4.0 * glm::dot(wo, h));
}

/* Rough dielectric: f and pdf at wi, reflection or transmission by the side
 * of wi. With `tint`, its transmitted part is multiplied by it (the
 * principled glass lobe). */
void dielectric_f_pdf(double eta, double alpha, const dvec3 &wo, const dvec3 &wi, const dvec3 &n,
		      const dvec3 &tint, dvec3 *f, double *pdf)
{
	double on = glm::dot(wo, n), in = glm::dot(wi, n);
	*f = dvec3(0.0);
	*pdf = 0.0;
	if (in > 0.0) {
		dvec3 h = glm::normalize(wo + wi);
		double oh = glm::dot(wo, h);
		double F = fresnel_dielectric(oh, eta);
		double g = smith_g1(alpha, oh, on) * smith_g1(alpha, glm::dot(wi, h), in);
		*f = dvec3(F * ggx_d(alpha, glm::dot(h, n)) * g / (4.0 * on * in));
		*pdf = F * ggx_d_visible(alpha, wo, h, n) / (4.0 * oh);
		return;
	}
	dvec3 h = glm::normalize(eta * wi + wo);
	if (glm::dot(h, n) < 0.0)
		h = -h;
	double ih = glm::dot(wi, h), oh = glm::dot(wo, h);
	if (ih * in <= 0.0 || oh <= 0.0)
		return;
	double F = fresnel_dielectric(oh, eta);
	double den = (ih + oh / eta) * (ih + oh / eta);
	double g = smith_g1(alpha, oh, on) * smith_g1(alpha, ih, in);
	double value = (1.0 - F) * ggx_d(alpha, glm::dot(h, n)) * g * std::fabs(ih * oh) /
		       (std::fabs(in) * on * den) / (eta * eta);
	*f = value * tint;
	*pdf = (1.0 - F) * ggx_d_visible(alpha, wo, h, n) * std::fabs(ih) / den;
}

/* Principled's plastic lobe: glTF's fresnel_mix of a GGX specular over a
 * Lambertian base; its pdf given p_s, the specular part's probability. */
dvec3 plastic_f(const bsdf &b, const dvec3 &wo, const dvec3 &wi)
{
	double f0 = (b.ior - 1.0) / (b.ior + 1.0);
	f0 *= f0;
	dvec3 h = glm::normalize(wo + wi);
	double on = glm::dot(wo, b.n), in = glm::dot(wi, b.n), oh = glm::dot(wo, h);
	double F = schlick(f0, oh);
	double g = smith_g1(b.alpha, oh, on) * smith_g1(b.alpha, glm::dot(wi, h), in);
	return dvec3(F * ggx_d(b.alpha, glm::dot(h, b.n)) * g / (4.0 * on * in)) +
	       (1.0 - F) * b.color / pi;
}

double plastic_specular_probability(const bsdf &b, const dvec3 &wo)
{
	double f0 = (b.ior - 1.0) / (b.ior + 1.0);
	return schlick(f0 * f0, glm::dot(wo, b.n));
}

/* ---- A BSDF: f, pdf, sample ---- */

/* Whether b has a part that next_event can reach. */
bool has_non_delta(const bsdf &b)
{
	switch (b.type) {
	case bsdf::CONDUCTOR:
	case bsdf::DIELECTRIC:
		return !b.smooth;
	case bsdf::MAPPED:
		return b.kr < 1.0;
	default:
		return true;
	}
}

/* f(wo, wi) and pdf(wo, wi): 0 outside the lobes' side rules and for the
 * delta lobes. */
void bsdf_f_pdf(const bsdf &b, const dvec3 &wo, const dvec3 &wi, dvec3 *f, double *pdf)
{
	bool reflection = reflection_side(b, wi), transmission = transmission_side(b, wi);
	double in = glm::dot(wi, b.n);

	*f = dvec3(0.0);
	*pdf = 0.0;
	switch (b.type) {
	case bsdf::DIFFUSE:
		if (reflection) {
			*f = b.color / pi;
			*pdf = in / pi;
		}
		return;
	case bsdf::MAPPED:
		if (reflection && b.kr < 1.0) {
			*f = (1.0 - b.kr) * b.color / pi;
			*pdf = (1.0 - b.kr) * in / pi;
		}
		return;
	case bsdf::CONDUCTOR:
		if (reflection && !b.smooth) {
			*f = conductor_f(b.color, b.alpha, wo, wi, b.n);
			*pdf = reflection_pdf(b.alpha, wo, wi, b.n);
		}
		return;
	case bsdf::DIELECTRIC:
		if ((reflection || transmission) && !b.smooth)
			dielectric_f_pdf(b.eta, b.alpha, wo, wi, b.n, dvec3(1.0), f, pdf);
		return;
	case bsdf::PRINCIPLED: {
		double m = b.metallic, t = b.transmission;
		if (reflection) {
			double p_s = plastic_specular_probability(b, wo);
			*f += m * conductor_f(b.color, b.alpha, wo, wi, b.n);
			*pdf += m * reflection_pdf(b.alpha, wo, wi, b.n);
			*f += (1.0 - m) * (1.0 - t) * plastic_f(b, wo, wi);
			*pdf += (1.0 - m) * (1.0 - t) *
				(p_s * reflection_pdf(b.alpha, wo, wi, b.n) +
				 (1.0 - p_s) * in / pi);
		}
		if ((reflection || transmission) && t > 0.0) {
			dvec3 fg;
			double pg;
			dielectric_f_pdf(b.eta, b.alpha, wo, wi, b.n, b.color, &fg, &pg);
			*f += (1.0 - m) * t * fg;
			*pdf += (1.0 - m) * t * pg;
		}
		return;
	}
	}
}

/* "The path": whether the sampled direction lies on its lobe's side of
 * both normals. */
bool valid_side(const bsdf &b, const bsdf_sample &s)
{
	return s.transmitted ? transmission_side(b, s.wi) : reflection_side(b, s.wi);
}

/* A rough dielectric's sample: VNDF h, then reflect (u < F) or refract. */
bool sample_rough_dielectric(double eta, double alpha, const bsdf &b, const dvec3 &wo, dvec2 uc,
			     double u, dvec3 *wi, bool *reflected)
{
	dvec3 h = sample_visible_normal(b, alpha, wo, uc);
	double F = fresnel_dielectric(glm::dot(wo, h), eta);
	*reflected = u < F;
	if (*reflected) {
		*wi = reflect(wo, h);
		return true;
	}
	return refract(wo, h, eta, wi);
}

/* sample: false when there is none (the path stops). Side rules are the
 * caller's. */
bool bsdf_sample_direction(const bsdf &b, const dvec3 &wo, dvec2 uc, double u, bsdf_sample *out)
{
	out->delta = false;
	out->transmitted = false;
	switch (b.type) {
	case bsdf::DIFFUSE:
		out->wi = sample_cosine(b, uc);
		out->weight = b.color;
		out->pdf = glm::dot(out->wi, b.n) / pi;
		return true;

	case bsdf::MAPPED:
		if (u < b.kr) {
			out->wi = reflect(wo, b.n);
			out->weight = b.mirror;
			out->pdf = 0.0;
			out->delta = true;
			return true;
		}
		out->wi = sample_cosine(b, uc);
		out->weight = b.color;
		out->pdf = (1.0 - b.kr) * glm::dot(out->wi, b.n) / pi;
		return true;

	case bsdf::CONDUCTOR: {
		if (b.smooth) {
			out->wi = reflect(wo, b.n);
			out->weight = schlick(b.color, glm::dot(wo, b.n));
			out->pdf = 0.0;
			out->delta = true;
			return true;
		}
		dvec3 h = sample_visible_normal(b, b.alpha, wo, uc);
		out->wi = reflect(wo, h);
		double oh = glm::dot(wo, h);
		out->weight = schlick(b.color, oh) *
			      smith_g1(b.alpha, glm::dot(out->wi, h), glm::dot(out->wi, b.n));
		out->pdf = ggx_d_visible(b.alpha, wo, h, b.n) / (4.0 * oh);
		return true;
	}

	case bsdf::DIELECTRIC: {
		if (b.smooth) {
			double F = fresnel_dielectric(glm::dot(wo, b.n), b.eta);
			out->pdf = 0.0;
			out->delta = true;
			if (u < F) {
				out->wi = reflect(wo, b.n);
				out->weight = dvec3(1.0);
				return true;
			}
			out->weight = dvec3(1.0 / (b.eta * b.eta));
			out->transmitted = true;
			return refract(wo, b.n, b.eta, &out->wi);
		}
		dvec3 h = sample_visible_normal(b, b.alpha, wo, uc);
		double oh = glm::dot(wo, h);
		double F = fresnel_dielectric(oh, b.eta);
		double g1;
		if (u < F) {
			out->wi = reflect(wo, h);
			g1 = smith_g1(b.alpha, glm::dot(out->wi, h), glm::dot(out->wi, b.n));
			out->weight = dvec3(g1);
			out->pdf = F * ggx_d_visible(b.alpha, wo, h, b.n) / (4.0 * oh);
			return true;
		}
		if (!refract(wo, h, b.eta, &out->wi))
			return false;
		out->transmitted = true;
		double ih = glm::dot(out->wi, h);
		double den = (ih + oh / b.eta) * (ih + oh / b.eta);
		g1 = smith_g1(b.alpha, ih, glm::dot(out->wi, b.n));
		out->weight = dvec3(g1 / (b.eta * b.eta));
		out->pdf = (1.0 - F) * ggx_d_visible(b.alpha, wo, h, b.n) * std::fabs(ih) / den;
		return true;
	}

	case bsdf::PRINCIPLED: {
		/* The lobe by u in the order metal, glass, plastic; u rescaled to
		 * the chosen interval. Then pdf and weight of the mixture at wi. */
		double m = b.metallic, t = b.transmission;
		double glass_end = m + (1.0 - m) * t;
		bool reflected;
		if (u < m) {
			out->wi = reflect(wo, sample_visible_normal(b, b.alpha, wo, uc));
		} else if (u < glass_end) {
			double u2 = (u - m) / (glass_end - m);
			if (!sample_rough_dielectric(b.eta, b.alpha, b, wo, uc, u2, &out->wi,
						     &reflected))
				return false;
			out->transmitted = !reflected;
		} else {
			double u2 = (u - glass_end) / (1.0 - glass_end);
			if (u2 < plastic_specular_probability(b, wo))
				out->wi = reflect(wo, sample_visible_normal(b, b.alpha, wo, uc));
			else
				out->wi = sample_cosine(b, uc);
		}
		if (!valid_side(b, *out))
			return false;
		dvec3 f;
		bsdf_f_pdf(b, wo, out->wi, &f, &out->pdf);
		if (!(out->pdf > 0.0))
			return false;
		out->weight = f * std::fabs(glm::dot(out->wi, b.n)) / out->pdf;
		return true;
	}
	}
	return false;
}

} // namespace

/* ---- "The environment" ---- */

environment::environment(const struct scene &sc)
    : background(to_dvec3(sc.background)), width(0), height(0), total(0.0)
{
	const scene_environment &map = sc.environment;
	double psi = glm::radians(map.rotate);
	cos_psi = std::cos(psi);
	sin_psi = std::sin(psi);
	if (!map.file || !map.rgb)
		return;
	width = map.width;
	height = map.height;
	texels.resize((size_t)width * height);
	weight.resize(texels.size());
	row_cdf.resize(height);
	column_cdf.resize(texels.size());
	for (int k = 0; k < height; k++) {
		/* w(j, k) = lum(E(j, k)) sin(pi (k + 0.5) / H), E = scale texel
		 * rounded once to float */
		double sin_row = std::sin(pi * (k + 0.5) / height), row = 0.0;
		for (int j = 0; j < width; j++) {
			size_t at = (size_t)k * width + j;
			const float *t = map.rgb + 3 * at;
			for (int c = 0; c < 3; c++)
				texels[at][c] = (float)(map.scale * t[c]);
			weight[at] = luminance(texels[at]) * sin_row;
			row += weight[at];
			column_cdf[at] = row;
		}
		for (int j = 0; j < width; j++)
			column_cdf[(size_t)k * width + j] =
				row > 0.0 ? column_cdf[(size_t)k * width + j] / row : 0.0;
		total += row;
		row_cdf[k] = total;
	}
	for (int k = 0; k < height; k++)
		row_cdf[k] = total > 0.0 ? row_cdf[k] / total : 0.0;
}

bool environment::is_light() const
{
	return width > 0 ? total > 0.0 : !is_black(background);
}

/* The direction of (u, v): theta = pi v, phi = 2 pi u, turned about +y. */
dvec3 environment::direction(double u, double v) const
{
	double theta = pi * v, phi = 2.0 * pi * u;
	dvec3 d0(-std::sin(theta) * std::sin(phi), std::cos(theta),
		 std::sin(theta) * std::cos(phi));
	return dvec3(d0.x * cos_psi + d0.z * sin_psi, d0.y, -d0.x * sin_psi + d0.z * cos_psi);
}

/* The texel (j, k) of direction d, and sin(theta) there. */
bool environment::lookup(const dvec3 &d, int *j, int *k, double *sin_theta) const
{
	dvec3 d0(d.x * cos_psi - d.z * sin_psi, d.y, d.x * sin_psi + d.z * cos_psi);
	double theta = std::acos(std::clamp(d0.y, -1.0, 1.0));
	double phi = std::atan2(-d0.x, d0.z);
	if (phi < 0.0)
		phi += 2.0 * pi;
	*j = std::min(width - 1, (int)std::floor(width * phi / (2.0 * pi)));
	*k = std::min(height - 1, (int)std::floor(height * theta / pi));
	*sin_theta = std::sin(theta);
	return true;
}

dvec3 environment::radiance(const dvec3 &d) const
{
	if (width == 0)
		return background;
	int j, k;
	double sin_theta;
	lookup(d, &j, &k, &sin_theta);
	return texels[(size_t)k * width + j];
}

/* pdf_env(d): 1/(4 pi) uniform; a map's w(j, k) W H / (sum w 2 pi^2 sin(theta)). */
double environment::pdf(const dvec3 &d) const
{
	if (width == 0)
		return 1.0 / (4.0 * pi);
	int j, k;
	double sin_theta;
	lookup(d, &j, &k, &sin_theta);
	double w = weight[(size_t)k * width + j];
	if (sin_theta == 0.0 || w == 0.0)
		return 0.0;
	return w * width * height / (total * 2.0 * pi * pi * sin_theta);
}

/* The first index of cdf[0 .. n) that exceeds x (n - 1 at most), and x's
 * position inside its interval. */
static double invert_cdf(const double *cdf, int n, double x, int *index)
{
	int i = 0;
	while (i + 1 < n && !(x < cdf[i]))
		i++;
	double lo = i > 0 ? cdf[i - 1] : 0.0;
	*index = i;
	return cdf[i] > lo ? (x - lo) / (cdf[i] - lo) : 0.5;
}

dvec3 environment::sample(dvec2 st) const
{
	if (width == 0) {
		/* Uniform: z = 1 - 2s, phi = 2 pi t. */
		double z = 1.0 - 2.0 * st.x;
		double r = std::sqrt(std::max(0.0, 1.0 - z * z));
		double phi = 2.0 * pi * st.y;
		return dvec3(r * std::cos(phi), r * std::sin(phi), z);
	}
	/* The row by t, then the column within it by s. */
	int j, k;
	double fv = invert_cdf(row_cdf.data(), height, st.y, &k);
	double fu = invert_cdf(column_cdf.data() + (size_t)k * width, width, st.x, &j);
	return direction((j + fu) / width, (k + fv) / height);
}

/* ---- The scene's lights ---- */

path_tracer::path_tracer(const struct scene &sc, int max_depth_, const dvec3 &origin)
    : scene_geometry(sc, origin), emitter_total(0.0), emitters_group(-1), env(sc),
      environment_group(-1), max_depth(max_depth_)
{
	/* "Lights and their selection": the lights of `lights`, then the
	 * emitters (triangles, then spheres, in scene order), then the
	 * environment. */
	triangle_emitter.assign(triangles.size(), -1);
	sphere_emitter.assign(spheres.size(), -1);
	for (size_t i = 0; i < triangles.size(); i++) {
		const triangle &tri = triangles[i];
		const dvec3 &Le = materials[tri.material].emission;
		if (is_black(Le))
			continue;
		double area = glm::length(glm::cross(tri.v1 - tri.v0, tri.v2 - tri.v0)) / 2.0;
		triangle_emitter[i] = (int)emitters.size();
		emitters.push_back({&tri, nullptr, area, luminance(Le) * area, 0.0});
	}
	for (size_t i = 0; i < spheres.size(); i++) {
		const sphere &sph = spheres[i];
		const dvec3 &Le = materials[sph.material].emission;
		if (is_black(Le))
			continue;
		double area = 4.0 * pi * sph.radius_sq;
		sphere_emitter[i] = (int)emitters.size();
		emitters.push_back({nullptr, &sph, area, luminance(Le) * area, 0.0});
	}
	for (const emitter &e : emitters)
		emitter_total += e.weight;
	double running = 0.0;
	for (emitter &e : emitters) {
		running += e.weight;
		e.cdf = running / emitter_total;
	}
	if (!emitters.empty())
		emitters.back().cdf = 1.0;

	group_count = (int)lights.size();
	if (!emitters.empty())
		emitters_group = group_count++;
	if (env.is_light())
		environment_group = group_count++;
}

/* P_e = w_e / W. */
double path_tracer::emitter_probability(int e) const
{
	return emitters[e].weight / emitter_total;
}

/* pdf_e(x -> y) of the emitter hit at y (h), seen from x, in solid angle:
 * "next_event(i)", emitter triangle and emitter sphere. */
double path_tracer::emitter_pdf(const hit &h, const dvec3 &y, const dvec3 &x) const
{
	if (h.tri) {
		const emitter &e = emitters[triangle_emitter[h.tri - triangles.data()]];
		dvec3 to = y - x;
		double dist2 = glm::dot(to, to);
		double cos_e = std::fabs(glm::dot(to / std::sqrt(dist2), h.tri->n_g));
		return dist2 / (e.area * cos_e);
	}
	double D = glm::length(h.sphere->center - x), R = h.sphere->radius;
	if (D <= R)
		return 0.0;
	double sin2 = R * R / (D * D);
	double c_max = std::sqrt(std::max(0.0, 1.0 - sin2));
	return 1.0 / (2.0 * pi * one_minus_cos(sin2, c_max));
}

/* p_env(d) = (1/G) pdf_env(d); 0 without an environment group. */
double path_tracer::environment_pdf(const dvec3 &d) const
{
	return environment_group < 0 ? 0.0 : env.pdf(d) / group_count;
}

/* Le of material m (SCENE.md "Emission"), times its emissive texture at
 * barycentric (u, v) of triangle tri ("Models' textures"). */
dvec3 path_tracer::emission(int m, const triangle *tri, double u, double v) const
{
	const material &mat = materials[m];
	if (!tri || mat.emissive_texture < 0)
		return mat.emission;
	return mat.emission * dvec3(texture_at(mat.emissive_texture, *tri, u, v));
}

/* "next_event(i)": an emitter's sample from p with (s, t) = pair B(i), its
 * pdf without 1/G and P_e. */
bool path_tracer::sample_emitter(const emitter &e, const dvec3 &p, dvec2 st, light_sample *ls) const
{
	if (e.tri) {
		const triangle &tri = *e.tri;
		double r = std::sqrt(st.x);
		dvec3 y = (1.0 - r) * tri.v0 + r * (1.0 - st.y) * tri.v1 + r * st.y * tri.v2;
		dvec3 to = y - p;
		double dist = glm::length(to);
		if (dist == 0.0)
			return false;
		ls->l = to / dist;
		double cos_e = glm::dot(ls->l, tri.n_g);
		if (!(cos_e < 0.0))
			return false; /* y's front does not face p */
		/* y's barycentric coordinates of v1 and v2: (r (1 - t), r t) */
		ls->E = emission(tri.material, &tri, r * (1.0 - st.y), r * st.y);
		ls->pdf = dist * dist / (e.area * std::fabs(cos_e));
		ls->t_max = dist - 2.0 * epsilon;
		return true;
	}
	const sphere &sph = *e.sph;
	double D = glm::length(sph.center - p), R = sph.radius;
	if (D <= R)
		return false; /* p inside: the outside is not seen */
	double sin2 = R * R / (D * D);
	double c_max = std::sqrt(std::max(0.0, 1.0 - sin2));
	ls->l = glm::normalize(cone((sph.center - p) / D, c_max, st.x, st.y));
	double cos_theta = 1.0 - st.x * (1.0 - c_max);
	double sin2_theta = std::max(0.0, 1.0 - cos_theta * cos_theta);
	double dist = D * cos_theta - std::sqrt(std::max(0.0, R * R - D * D * sin2_theta));
	ls->E = materials[sph.material].emission;
	ls->pdf = 1.0 / (2.0 * pi * one_minus_cos(sin2, c_max));
	ls->t_max = dist - 2.0 * epsilon;
	return true;
}

/* "next_event(i)": choose group g with A(i).s, sample it with B(i). */
bool path_tracer::sample_light(const surface &s, int vertex, const sample_id &sample,
			       light_sample *ls) const
{
	uint32_t choice[2];
	sample_pair_bits(sample, pair_light_choice(vertex), choice);
	int g = (int)(((uint64_t)choice[0] * (uint64_t)group_count) >> 24);
	dvec2 st = sample_pair(sample, pair_light_point(vertex));
	double group_pdf = 1.0 / group_count;
	const dvec3 &p = s.p;

	ls->mis = false;
	ls->t_max = HUGE_VAL;
	ls->emitter = nullptr;
	if (g < (int)lights.size()) {
		const light &li = lights[g];
		if (li.directional) {
			if (li.angle == 0.0) {
				ls->l = li.toward;
				ls->E = li.color;
				ls->pdf = group_pdf;
				return true;
			}
			double c = std::cos(li.angle), sin_a = std::sin(li.angle);
			ls->l = glm::normalize(cone(li.toward, c, st.x, st.y));
			ls->E = li.color / (pi * sin_a * sin_a);
			ls->pdf = group_pdf / (2.0 * pi * (1.0 - c));
			return true;
		}
		dvec3 to = li.position - p;
		double D = glm::length(to);
		if (li.radius == 0.0) { /* a point light: delta */
			if (D == 0.0)
				return false;
			ls->l = to / D;
			ls->E = li.color / (D * D);
			ls->pdf = group_pdf;
			ls->t_max = D;
			return true;
		}
		double R = li.radius;
		if (D <= R)
			return false;
		double sin2 = R * R / (D * D);
		double c_max = std::sqrt(std::max(0.0, 1.0 - sin2));
		ls->l = glm::normalize(cone(to / D, c_max, st.x, st.y));
		double cos_theta = 1.0 - st.x * (1.0 - c_max);
		double sin2_theta = std::max(0.0, 1.0 - cos_theta * cos_theta);
		ls->t_max = D * cos_theta - std::sqrt(std::max(0.0, R * R - D * D * sin2_theta));
		ls->E = li.color / (pi * R * R);
		ls->pdf = group_pdf / (2.0 * pi * one_minus_cos(sin2, c_max));
		return true;
	}
	ls->mis = true;
	if (g == emitters_group) {
		/* The first e with A(i).t < cdf_e. */
		double t = std::ldexp((double)choice[1], -24);
		int e = 0;
		while (e + 1 < (int)emitters.size() && !(t < emitters[e].cdf))
			e++;
		ls->emitter = emitters[e].tri ? (const void *)emitters[e].tri
					      : (const void *)emitters[e].sph;
		/* Not the emitter p lies on: none of it is seen from its own
		 * surface (convex, emitting outwards), while D <= R or
		 * l.n_e < 0 would be decided there by rounding (proposed
		 * RENDERING.md fix). */
		if (ls->emitter == s.object || !sample_emitter(emitters[e], p, st, ls))
			return false;
		ls->pdf *= group_pdf * emitter_probability(e);
		return true;
	}
	ls->l = env.sample(st);
	ls->E = env.radiance(ls->l);
	ls->pdf = environment_pdf(ls->l);
	return ls->pdf > 0.0;
}

/* "next_event(i)": one light sample's contribution at vertex i. */
dvec3 path_tracer::next_event(const surface &s, const bsdf &b, const dvec3 &wo, int vertex,
			      const sample_id &sample) const
{
	light_sample ls;
	if (group_count == 0 || !sample_light(s, vertex, sample, &ls))
		return dvec3(0.0);
	dvec3 f;
	double pdf_bsdf;
	bsdf_f_pdf(b, wo, ls.l, &f, &pdf_bsdf);
	if (is_black(f))
		return dvec3(0.0);
	dvec3 origin = glm::dot(ls.l, s.n_face) > 0.0 ? s.p + epsilon * s.n_face
						      : s.p - epsilon * s.n_face;
	/* Not blocked by the emitter itself: from the shadow ray's origin, an
	 * epsilon off p, the emitter's own surface can lie nearer than its
	 * sampled point by more than 2 epsilon (a sphere near its silhouette, a
	 * triangle at a grazing angle), which would darken the direct light of
	 * an emitting sphere by 5 % at any epsilon (proposed RENDERING.md fix). */
	if (ls.t_max > 0.0 && blocked(origin, ls.l, ls.t_max, ls.emitter))
		return dvec3(0.0);
	double w = ls.mis ? w_light(ls.pdf, pdf_bsdf) : 1.0;
	return f * ls.E * std::fabs(glm::dot(ls.l, s.n)) / ls.pdf * w;
}

/* "Models' textures": a normal texture turns the shading normal, in the
 * triangle's own tangent frame (from its edges and texture coordinates). */
void path_tracer::apply_normal_texture(const hit &h, surface *s) const
{
	const material &m = materials[s->material];
	if (!h.tri || m.normal_texture < 0)
		return;
	const triangle &tri = *h.tri;
	dvec3 e1 = tri.v1 - tri.v0, e2 = tri.v2 - tri.v0;
	dvec2 d1 = tri.uv[1] - tri.uv[0], d2 = tri.uv[2] - tri.uv[0];
	double det = d1.x * d2.y - d2.x * d1.y;
	if (det == 0.0)
		return;
	dvec3 n_f = s->inside ? -s->n : s->n; /* on the front side */
	dvec3 dp_du = (d2.y * e1 - d1.y * e2) / det;
	dvec3 dp_dv = (d1.x * e2 - d2.x * e1) / det;
	dvec3 t = dp_du - glm::dot(n_f, dp_du) * n_f;
	if (t == dvec3(0.0))
		return;
	t = glm::normalize(t);
	dvec3 b = glm::cross(n_f, t);
	if (glm::dot(b, dp_dv) < 0.0)
		b = -b;
	dvec3 N = dvec3(texture_at(m.normal_texture, tri, h.u, h.v));
	dvec3 v = 2.0 * N - 1.0;
	dvec3 n = v.x * t + v.y * b + v.z * n_f;
	if (n == dvec3(0.0))
		return; /* a texel of (0.5, 0.5, 0.5): no direction */
	n = glm::normalize(n);
	s->n = s->inside ? -n : n;
}

/* "The BSDFs": the material's BSDF at the hit, its colours there
 * (textures, checkers), in the frame of the shading normal. */
bool path_tracer::make_bsdf(const hit &h, const surface &s, const dvec3 &wo, bsdf *b) const
{
	const material &m = materials[s.material];
	const scene_bsdf &sb = m.bsdf;

	b->n = s.n;
	b->n_face = s.n_face;
	frame_across(s.n, &b->b1, &b->b2);
	b->alpha = sb.roughness * sb.roughness;
	b->smooth = b->alpha < 0.001;
	b->eta = s.inside ? 1.0 / sb.ior : sb.ior;
	b->ior = sb.ior;
	b->metallic = sb.metallic;
	b->transmission = sb.transmission;
	/* The colour of diffuse, conductor and principled: times the base
	 * colour texture (at most 1), or min(1, checker colour) on an odd
	 * square. */
	b->color = glm::min(to_dvec3(sb.color) * texture_rgb(h), dvec3(1.0));
	if (odd_checker_square(h, s.p))
		b->color = glm::min(h.plane->checker_color, dvec3(1.0));

	switch (sb.type) {
	case SCENE_BSDF_DIFFUSE:
		b->type = bsdf::DIFFUSE;
		return true;
	case SCENE_BSDF_CONDUCTOR:
		b->type = bsdf::CONDUCTOR;
		return true;
	case SCENE_BSDF_DIELECTRIC:
		b->type = bsdf::DIELECTRIC;
		return true;
	case SCENE_BSDF_PRINCIPLED:
		b->type = bsdf::PRINCIPLED;
		if (h.tri && m.metallic_roughness_texture >= 0) {
			/* "Models' textures": roughness r T.g, metallic m T.b */
			glm::dvec4 T = texture_at(m.metallic_roughness_texture, *h.tri, h.u, h.v);
			double roughness = sb.roughness * T.g;
			b->alpha = roughness * roughness;
			b->metallic = sb.metallic * T.b;
		}
		b->alpha = std::max(b->alpha, 0.001);
		b->smooth = false;
		return true;
	default:
		break;
	}

	/* "The mapped BSDF of a material without bsdf". */
	dvec3 C = base_color(h, s.p);
	if (m.kt > 0.0) {
		b->type = bsdf::DIELECTRIC;
		b->smooth = true;
		b->eta = s.inside ? 1.0 / m.ior : m.ior;
		return true;
	}
	b->type = bsdf::MAPPED;
	b->color = glm::min(dvec3(1.0), m.kd * C);
	b->kr = m.kr;
	b->mirror =
		m.fresnel == SCENE_FRESNEL_CONDUCTOR ? schlick(C, glm::dot(wo, s.n)) : dvec3(1.0);
	return true;
}

/* "The path". */
dvec3 path_tracer::radiance(const dvec3 &o_, const dvec3 &d_, const sample_id &sample) const
{
	dvec3 o = o_, d = d_;
	dvec3 L(0.0), beta(1.0);
	bool specular = true;
	double pdf_prev = 0.0;
	dvec3 x_prev = o;

	for (int i = 0;; i++) {
		hit h;
		if (!nearest_hit(o, d, &h)) {
			L += beta * env.radiance(d) * w_hit(specular, pdf_prev, environment_pdf(d));
			break;
		}
		surface s = surface_at(h, o, d);
		apply_normal_texture(h, &s);
		dvec3 wo = -d;
		if (!s.inside && !is_black(materials[s.material].emission)) {
			dvec3 Le = emission(s.material, h.tri, h.u, h.v);
			double p_light = 0.0; /* an emitting plane is not a light */
			if (h.tri || h.sphere) {
				int e = h.tri ? triangle_emitter[h.tri - triangles.data()]
					      : sphere_emitter[h.sphere - spheres.data()];
				p_light = emitter_probability(e) * emitter_pdf(h, s.p, x_prev) /
					  group_count;
			}
			L += beta * Le * w_hit(specular, pdf_prev, p_light);
		}
		if (i > max_depth)
			break;

		bsdf b;
		make_bsdf(h, s, wo, &b);
		if (glm::dot(wo, s.n) <= 0.0)
			break; /* a shading normal facing away */
		if (has_non_delta(b))
			L += beta * next_event(s, b, wo, i, sample);

		dvec2 uc = sample_pair(sample, pair_direction(i));
		dvec2 ud = sample_pair(sample, pair_lobe(i));
		bsdf_sample bs;
		if (!bsdf_sample_direction(b, wo, uc, ud.x, &bs) || !valid_side(b, bs))
			break;
		beta *= bs.weight;
		if (is_black(beta))
			break;
		if (i >= 3) { /* Russian roulette */
			double q = std::min(1.0, max_channel(beta));
			if (ud.y >= q)
				break;
			beta /= q;
		}
		specular = bs.delta;
		pdf_prev = bs.pdf;
		x_prev = s.p;
		o = glm::dot(bs.wi, s.n_face) > 0.0 ? s.p + epsilon * s.n_face
						    : s.p - epsilon * s.n_face;
		/* Unit to the last bit: intersect_sphere needs |d| = 1 (see
		 * reference.cpp's secondary_colors). */
		d = glm::normalize(bs.wi);
	}
	return L;
}

bool path_tracer::mis_weights(const dvec3 &o, const dvec3 &d, const sample_id &sample, double *w_l,
			      double *w_h) const
{
	hit h;
	if (!nearest_hit(o, d, &h))
		return false;
	surface s = surface_at(h, o, d);
	apply_normal_texture(h, &s);
	dvec3 wo = -d;
	bsdf b;
	make_bsdf(h, s, wo, &b);
	light_sample ls;
	if (glm::dot(wo, s.n) <= 0.0 || !has_non_delta(b) || group_count == 0 ||
	    !sample_light(s, 0, sample, &ls) || !ls.mis)
		return false;
	dvec3 f;
	double pdf_bsdf;
	bsdf_f_pdf(b, wo, ls.l, &f, &pdf_bsdf);
	if (is_black(f))
		return false;
	*w_l = w_light(ls.pdf, pdf_bsdf);

	/* The BSDF ray along l, as "The path" weighs what it finds: the light
	 * sampled, when the shadow ray reaches it. */
	dvec3 origin = glm::dot(ls.l, s.n_face) > 0.0 ? s.p + epsilon * s.n_face
						      : s.p - epsilon * s.n_face;
	if (ls.t_max > 0.0 && blocked(origin, ls.l, ls.t_max, ls.emitter))
		return false;
	hit found;
	double p_light;
	if (!nearest_hit(origin, ls.l, &found)) {
		p_light = environment_pdf(ls.l);
	} else {
		surface sf = surface_at(found, origin, ls.l);
		if (sf.inside || !(found.tri || found.sphere) ||
		    is_black(materials[sf.material].emission))
			return false;
		int e = found.tri ? triangle_emitter[found.tri - triangles.data()]
				  : sphere_emitter[found.sphere - spheres.data()];
		p_light = emitter_probability(e) * emitter_pdf(found, sf.p, s.p) / group_count;
	}
	*w_h = w_hit(false, pdf_bsdf, p_light);
	return true;
}

} // namespace reference

extern "C" int reference_path_mis_weights(const struct scene *scene, int x, int y, int k, int n,
					  double weights[2])
{
	using namespace reference;
	const sample_id sample = {x, y, k, n};
	dvec3 o, d;
	const dvec3 eye = to_dvec3(scene->camera.eye);
	camera(scene->camera, scene->width, scene->height, eye).primary_ray(sample, &o, &d);

	try {
		const path_tracer pt(*scene, scene->max_depth, eye);
		return pt.mis_weights(o, d, sample, &weights[0], &weights[1]) ? 0 : -1;
	} catch (const std::bad_alloc &) {
		return -1;
	}
}
