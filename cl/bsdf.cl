/* The path integrator's BSDFs (docs/RENDERING.md, "The BSDFs"): diffuse,
 * conductor and dielectric (GGX, sampled by visible normals), principled, the mapped
 * BSDF of a Whitted material, each evaluated and sampled in the local frame
 * of the shading normal (z along n). Part of the tracer, only in programs
 * built with RTCL_PATH: built after walk.cl. */
#ifdef RTCL_PATH

/* Below this GGX alpha a conductor or dielectric is smooth (delta lobes). */
#define BSDF_SMOOTH_ALPHA 0.001f

/* An orthonormal frame around unit w (Duff et al., as "Light samples"). */
struct frame {
	float3 b1, b2, w;
};

/* Counted 13, as light_disk_offset's frame. */
static struct frame frame_around(struct tracer *tr, float3 w)
{
	float sign = copysign(1.0f, w.z);
	float e = -1.0f / (sign + w.z);
	float g = w.x * w.y * e;

	COUNT_FLOPS(tr, 13);
	return (struct frame){(float3)(1.0f + sign * w.x * w.x * e, sign * g, -sign * w.x),
			      (float3)(g, sign + w.y * w.y * e, -w.y), w};
}

/* Counted 3 FLOPS_DOT3. */
static inline float3 to_local(struct tracer *tr, const struct frame *f, float3 v)
{
	COUNT_FLOPS(tr, 3 * FLOPS_DOT3);
	return (float3)(dot3(v, f->b1), dot3(v, f->b2), dot3(v, f->w));
}

/* Counted three scalings and two sums. */
static inline float3 from_local(struct tracer *tr, const struct frame *f, float3 v)
{
	COUNT_FLOPS(tr, 3 * FLOPS_MUL3 + 2 * FLOPS_ADD3);
	return v.x * f->b1 + v.y * f->b2 + v.z * f->w;
}

/* A BSDF at a hit: the material's, its colours at the hit, and the side. */
struct bsdf {
	int type;     /* RT_BSDF_* */
	float3 color; /* reflectance, F0, base colour (mapped: rho) */
	float3 tint;  /* mapped: the mirror's F0 (white without its tint) */
	float alpha;  /* GGX width */
	float eta;    /* dielectric: the index beyond the surface over this side's */
	float mirror; /* mapped: the mirror's probability */
	float metallic, transmission; /* principled */
};

static inline float max3(float3 c)
{
	return fmax(fmax(c.x, c.y), c.z);
}

/* Whether the BSDF has a part that is not a delta: next-event estimation
 * is done only then. */
static inline bool bsdf_has_density(const struct bsdf *b)
{
	if (b->type == RT_BSDF_MAPPED)
		return b->mirror < 1.0f;
	if (b->type == RT_BSDF_CONDUCTOR || b->type == RT_BSDF_DIELECTRIC)
		return b->alpha >= BSDF_SMOOTH_ALPHA;
	return true;
}

/* Schlick's F0 + (1 - F0)(1 - c)^5 for a colour: counted 1 + 4 + 9. */
static inline float3 schlick3(struct tracer *tr, float3 f0, float c)
{
	float x = 1.0f - c;
	float x5 = x * x * x * x * x;

	COUNT_FLOPS(tr, 5 + 3 * FLOPS_ADD3);
	return f0 + (1.0f - f0) * x5;
}

/* The exact Fresnel reflectance of a dielectric for unpolarised light:
 * c the cosine on the incident side (> 0), eta the index beyond over this
 * side's. Counted 5, then 12 unless total internal reflection. */
static float fresnel_dielectric(struct tracer *tr, float c, float eta)
{
	float sin2t = (1.0f - c * c) / (eta * eta);

	COUNT_FLOPS(tr, 5);
	if (sin2t >= 1.0f)
		return 1.0f;
	float ct = sqrt(1.0f - sin2t);
	float rs = (c - eta * ct) / (c + eta * ct);
	float rp = (eta * c - ct) / (eta * c + ct);
	COUNT_FLOPS(tr, 12);
	return 0.5f * (rs * rs + rp * rp);
}

/* GGX's D(h), h local (h.z > 0 checked by the callers). Counted 8. */
static inline float ggx_d(struct tracer *tr, float3 h, float alpha)
{
	float a2 = alpha * alpha;
	float k = h.z * h.z * (a2 - 1.0f) + 1.0f;

	COUNT_FLOPS(tr, 8);
	return a2 / (M_PI_F * k * k);
}

/* Smith's G1(v, h) for GGX: 0 where v sees h's back. Counted 9. */
static inline float ggx_g1(struct tracer *tr, float3 v, float3 h, float alpha)
{
	float c2 = v.z * v.z;

	COUNT_FLOPS(tr, FLOPS_DOT3 + 1);
	if (dot3(v, h) * v.z <= 0.0f)
		return 0.0f;
	float tan2 = fmax(0.0f, 1.0f - c2) / c2;
	COUNT_FLOPS(tr, 8);
	return 2.0f / (1.0f + sqrt(1.0f + alpha * alpha * tan2));
}

/* The density of visible normals, D_wo(h) = G1(wo, h) max(0, wo.h) D(h) / wo.z. */
static inline float ggx_visible(struct tracer *tr, float3 wo, float3 h, float alpha)
{
	COUNT_FLOPS(tr, FLOPS_DOT3 + 4);
	return ggx_g1(tr, wo, h, alpha) * fmax(0.0f, dot3(wo, h)) * ggx_d(tr, h, alpha) / wo.z;
}

/* A normal sampled from the visible normals of wo (Heitz 2018), local. */
static float3 ggx_sample(struct tracer *tr, float3 wo, float alpha, float2 u)
{
	float3 v = normalize3((float3)(alpha * wo.x, alpha * wo.y, wo.z));
	float len2 = v.x * v.x + v.y * v.y;
	float3 t1 = len2 > 0.0f ? (float3)(-v.y, v.x, 0.0f) * rsqrt(len2) : (float3)(1.0f, 0.0f, 0.0f);
	float3 t2 = cross3(v, t1);
	float r = sqrt(u.x), phi = 2.0f * M_PI_F * u.y;
	float p1 = r * cos(phi), p2 = r * sin(phi);
	float s = 0.5f * (1.0f + v.z);
	p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * p2;
	float3 n = p1 * t1 + p2 * t2 + sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2)) * v;

	/* v (2 + 9), len2 3, t1 1 + 3, t2 9, r phi p1 p2 7, s 2, p2 8, n 6 +
	   6 + 6 + 6, h 2 + 9 */
	COUNT_FLOPS(tr, 11 + 3 + 4 + FLOPS_CROSS3 + 7 + 2 + 8 + 24 + 11);
	return normalize3((float3)(alpha * n.x, alpha * n.y, fmax(0.0f, n.z)));
}

/* v's mirror image about the unit h, 2(v.h)h - v. */
static inline float3 reflect_about(struct tracer *tr, float3 v, float3 h)
{
	COUNT_FLOPS(tr, FLOPS_DOT3 + 1 + FLOPS_MUL3 + FLOPS_ADD3);
	return 2.0f * dot3(v, h) * h - v;
}

/* v refracted through the surface of unit normal h on v's side (v.h > 0):
 * false under total internal reflection. */
static bool refract_about(struct tracer *tr, float3 v, float3 h, float eta, float3 *t)
{
	float c = dot3(v, h);
	float sin2t = (1.0f - c * c) / (eta * eta);

	COUNT_FLOPS(tr, FLOPS_DOT3 + 4);
	if (sin2t >= 1.0f)
		return false;
	*t = -v / eta + (c / eta - sqrt(1.0f - sin2t)) * h;
	COUNT_FLOPS(tr, FLOPS_MUL3 + 4 + FLOPS_MUL3 + FLOPS_ADD3);
	return true;
}

/* The conductor's and the dielectric's rough lobes for a given wi, local:
 * f and *pdf as RENDERING.md gives them. */
static float3 conductor_eval(struct tracer *tr, const struct bsdf *b, float3 wo, float3 wi,
			     float *pdf)
{
	float3 h = normalize3(wo + wi);
	float d = ggx_d(tr, h, b->alpha);
	float g = ggx_g1(tr, wo, h, b->alpha) * ggx_g1(tr, wi, h, b->alpha);
	float wo_h = dot3(wo, h);

	*pdf = ggx_visible(tr, wo, h, b->alpha) / (4.0f * wo_h);
	COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_NORMALIZE3 + 1 + FLOPS_DOT3 + 2 + 4 + FLOPS_MUL3);
	return schlick3(tr, b->color, wo_h) * (d * g / (4.0f * wo.z * wi.z));
}

static float3 dielectric_eval(struct tracer *tr, const struct bsdf *b, float3 wo, float3 wi,
			      float *pdf)
{
	float eta = b->eta;

	*pdf = 0.0f;
	if (wi.z > 0.0f) {
		float3 h = normalize3(wo + wi);
		float wo_h = dot3(wo, h);
		float f = fresnel_dielectric(tr, wo_h, eta);
		float g = ggx_g1(tr, wo, h, b->alpha) * ggx_g1(tr, wi, h, b->alpha);
		*pdf = f * ggx_visible(tr, wo, h, b->alpha) / (4.0f * wo_h);
		COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_NORMALIZE3 + FLOPS_DOT3 + 1 + 4 + 7);
		return (float3)(f * ggx_d(tr, h, b->alpha) * g / (4.0f * wo.z * wi.z));
	}
	float3 h = normalize3(eta * wi + wo);
	if (h.z < 0.0f)
		h = -h;
	float wi_h = dot3(wi, h), wo_h = dot3(wo, h);
	COUNT_FLOPS(tr, FLOPS_MUL3 + FLOPS_ADD3 + FLOPS_NORMALIZE3 + 2 * FLOPS_DOT3);
	if (wi_h * wi.z <= 0.0f || wo_h <= 0.0f)
		return (float3)(0.0f);
	float f = fresnel_dielectric(tr, wo_h, eta);
	float den = wi_h + wo_h / eta;
	den = den * den;
	float g = ggx_g1(tr, wo, h, b->alpha) * ggx_g1(tr, wi, h, b->alpha);
	*pdf = (1.0f - f) * ggx_visible(tr, wo, h, b->alpha) * fabs(wi_h) / den;
	COUNT_FLOPS(tr, 3 + 1 + 4 + 10);
	return (float3)((1.0f - f) * ggx_d(tr, h, b->alpha) * g * fabs(wi_h * wo_h) /
			(fabs(wi.z) * wo.z * den) / (eta * eta));
}

/* The principled BSDF's plastic lobe (glTF 2.0's fresnel_mix of a GGX
 * highlight over a diffuse base) for a given wi above; *pdf of its own
 * sampling, the highlight with probability p_s = Schlick(F0, wo.z). */
static float3 plastic_eval(struct tracer *tr, const struct bsdf *b, float f0, float3 wo, float3 wi,
			   float *pdf)
{
	float3 h = normalize3(wo + wi);
	float wo_h = dot3(wo, h);
	float f = schlick3(tr, (float3)(f0), wo_h).x;
	float p_s = schlick3(tr, (float3)(f0), wo.z).x;
	float g = ggx_g1(tr, wo, h, b->alpha) * ggx_g1(tr, wi, h, b->alpha);
	float specular = f * ggx_d(tr, h, b->alpha) * g / (4.0f * wo.z * wi.z);

	*pdf = p_s * ggx_visible(tr, wo, h, b->alpha) / (4.0f * wo_h) +
	       (1.0f - p_s) * wi.z * M_1_PI_F;
	COUNT_FLOPS(tr, FLOPS_ADD3 + FLOPS_NORMALIZE3 + FLOPS_DOT3 + 1 + 6 + 7 + 2 + FLOPS_MUL3 +
				FLOPS_ADD3);
	return specular + (1.0f - f) * M_1_PI_F * b->color;
}

/* The principled BSDF (RENDERING.md): m metal + (1 - m) t glass (its
 * transmission tinted by the base colour) + (1 - m)(1 - t) plastic, and
 * the mixture of their pdfs. */
static float3 principled_eval(struct tracer *tr, const struct bsdf *b, float3 wo, float3 wi,
			      float *pdf)
{
	float m = b->metallic, t = b->transmission;
	float glass = (1.0f - m) * t, plastic = (1.0f - m) * (1.0f - t);
	float f0 = (b->eta - 1.0f) / (b->eta + 1.0f);
	float3 f = (float3)(0.0f);
	float lobe_pdf;

	f0 = f0 * f0;
	*pdf = 0.0f;
	COUNT_FLOPS(tr, 4 + 4);
	if (m > 0.0f && wi.z > 0.0f) {
		f += m * conductor_eval(tr, b, wo, wi, &lobe_pdf);
		*pdf += m * lobe_pdf;
		COUNT_FLOPS(tr, FLOPS_MUL3 + FLOPS_ADD3 + 2);
	}
	if (glass > 0.0f) {
		float3 g = dielectric_eval(tr, b, wo, wi, &lobe_pdf);
		f += glass * (wi.z < 0.0f ? g * b->color : g);
		*pdf += glass * lobe_pdf;
		COUNT_FLOPS(tr, 2 * FLOPS_MUL3 + FLOPS_ADD3 + 2);
	}
	if (plastic > 0.0f && wi.z > 0.0f) {
		f += plastic * plastic_eval(tr, b, f0, wo, wi, &lobe_pdf);
		*pdf += plastic * lobe_pdf;
		COUNT_FLOPS(tr, FLOPS_MUL3 + FLOPS_ADD3 + 2);
	}
	return f;
}

/* f(wo, wi) of the BSDF's non-delta parts, and *pdf, the density with which
 * bsdf_sample returns wi; local directions, wo.z > 0. The side rules are the
 * caller's (path.cl). */
static float3 bsdf_eval(struct tracer *tr, const struct bsdf *b, float3 wo, float3 wi, float *pdf)
{
	*pdf = 0.0f;
	switch (b->type) {
	case RT_BSDF_CONDUCTOR:
		if (b->alpha < BSDF_SMOOTH_ALPHA || wi.z <= 0.0f)
			return (float3)(0.0f);
		return conductor_eval(tr, b, wo, wi, pdf);
	case RT_BSDF_DIELECTRIC:
		if (b->alpha < BSDF_SMOOTH_ALPHA)
			return (float3)(0.0f);
		return dielectric_eval(tr, b, wo, wi, pdf);
	case RT_BSDF_PRINCIPLED:
		return principled_eval(tr, b, wo, wi, pdf);
	default: /* diffuse, and the mapped BSDF's diffuse lobe */
		if (wi.z <= 0.0f)
			return (float3)(0.0f);
		float share = b->type == RT_BSDF_MAPPED ? 1.0f - b->mirror : 1.0f;
		*pdf = share * wi.z * M_1_PI_F;
		COUNT_FLOPS(tr, 4 + 1 + FLOPS_MUL3);
		return b->color * (share * M_1_PI_F);
	}
}

/* A sampled direction: wi (local), weight = f |wi.z| / pdf, pdf, whether
 * the lobe taken is a delta. */
struct bsdf_sample {
	float3 wi, weight;
	float pdf;
	bool delta;
};

/* The cosine-weighted hemisphere, pdf z / pi. */
static float3 cosine_direction(struct tracer *tr, float2 u)
{
	float2 d = sample_disk(tr, u);

	COUNT_FLOPS(tr, 5);
	return (float3)(d.x, d.y, sqrt(fmax(0.0f, 1.0f - d.x * d.x - d.y * d.y)));
}

/* Samples the BSDF for wo (local, wo.z > 0) with u (pair C) and the lobe
 * coordinate u_lobe (pair D's first): false when the sample is none. Each
 * kind's branch takes the shading phase's SIMD step (RENDERING.md, "SIMD
 * efficiency, measured"), so that lanes on different kinds count apart. */
static bool bsdf_sample(struct tracer *tr, const struct bsdf *b, float3 wo, float2 u,
			float u_lobe, struct bsdf_sample *out)
{
	out->delta = false;
	switch (b->type) {
	case RT_BSDF_CONDUCTOR:
		SIMD_STEP(tr, RT_SIMD_SHADE);
		if (b->alpha < BSDF_SMOOTH_ALPHA) {
			out->wi = (float3)(-wo.x, -wo.y, wo.z);
			out->weight = schlick3(tr, b->color, wo.z);
			out->pdf = 0.0f;
			out->delta = true;
			return true;
		} else {
			float3 h = ggx_sample(tr, wo, b->alpha, u);
			out->wi = reflect_about(tr, wo, h);
			if (out->wi.z <= 0.0f)
				return false;
			float wo_h = dot3(wo, h);
			out->pdf = ggx_visible(tr, wo, h, b->alpha) / (4.0f * wo_h);
			out->weight = schlick3(tr, b->color, wo_h) * ggx_g1(tr, out->wi, h, b->alpha);
			COUNT_FLOPS(tr, FLOPS_DOT3 + 2 + FLOPS_MUL3);
			return true;
		}
	case RT_BSDF_DIELECTRIC: {
		SIMD_STEP(tr, RT_SIMD_SHADE);
		float eta = b->eta;
		if (b->alpha < BSDF_SMOOTH_ALPHA) {
			float3 n = (float3)(0.0f, 0.0f, 1.0f);
			out->delta = true;
			out->pdf = 0.0f;
			if (u_lobe < fresnel_dielectric(tr, wo.z, eta)) {
				out->wi = (float3)(-wo.x, -wo.y, wo.z);
				out->weight = (float3)(1.0f);
				return true;
			}
			if (!refract_about(tr, wo, n, eta, &out->wi))
				return false;
			out->weight = (float3)(1.0f / (eta * eta));
			COUNT_FLOPS(tr, 2);
			return true;
		}
		float3 h = ggx_sample(tr, wo, b->alpha, u);
		float wo_h = dot3(wo, h);
		float f = fresnel_dielectric(tr, wo_h, eta);
		float visible = ggx_visible(tr, wo, h, b->alpha);
		COUNT_FLOPS(tr, FLOPS_DOT3);
		if (u_lobe < f) {
			out->wi = reflect_about(tr, wo, h);
			if (out->wi.z <= 0.0f)
				return false;
			out->pdf = f * visible / (4.0f * wo_h);
			out->weight = (float3)(ggx_g1(tr, out->wi, h, b->alpha));
			COUNT_FLOPS(tr, 3);
			return true;
		}
		if (!refract_about(tr, wo, h, eta, &out->wi) || out->wi.z >= 0.0f)
			return false;
		float wi_h = dot3(out->wi, h);
		float den = wi_h + wo_h / eta;
		den = den * den;
		out->pdf = (1.0f - f) * visible * fabs(wi_h) / den;
		out->weight = (float3)(ggx_g1(tr, out->wi, h, b->alpha) / (eta * eta));
		COUNT_FLOPS(tr, FLOPS_DOT3 + 3 + 4 + 3);
		return true;
	}
	case RT_BSDF_PRINCIPLED: {
		/* The lobe by u_lobe (metal, glass, plastic), u rescaled to its
		 * interval; then the mixture's pdf and weight at wi. */
		SIMD_STEP(tr, RT_SIMD_SHADE);
		float m = b->metallic, glass = (1.0f - m) * b->transmission;
		COUNT_FLOPS(tr, 2);
		bool reflected = true; /* the lobe's side: a sample on the other is none */
		if (u_lobe < m) {
			float3 h = ggx_sample(tr, wo, b->alpha, u);
			out->wi = reflect_about(tr, wo, h);
		} else if (u_lobe < m + glass) {
			float v = (u_lobe - m) / glass;
			float3 h = ggx_sample(tr, wo, b->alpha, u);
			float wo_h = dot3(wo, h);
			COUNT_FLOPS(tr, 3 + FLOPS_DOT3);
			if (v < fresnel_dielectric(tr, wo_h, b->eta))
				out->wi = reflect_about(tr, wo, h);
			else if (!refract_about(tr, wo, h, b->eta, &out->wi))
				return false;
			else
				reflected = false;
		} else {
			float f0 = (b->eta - 1.0f) / (b->eta + 1.0f);
			float v = (u_lobe - m - glass) / (1.0f - m - glass);
			COUNT_FLOPS(tr, 3 + 4 + 1);
			if (v < schlick3(tr, (float3)(f0 * f0), wo.z).x)
				out->wi = reflect_about(tr, wo, ggx_sample(tr, wo, b->alpha, u));
			else
				out->wi = cosine_direction(tr, u);
		}
		if (reflected != (out->wi.z > 0.0f))
			return false;
		float3 f = principled_eval(tr, b, wo, out->wi, &out->pdf);
		if (!(out->pdf > 0.0f))
			return false;
		out->weight = f * (fabs(out->wi.z) / out->pdf);
		COUNT_FLOPS(tr, 2 + FLOPS_MUL3);
		return true;
	}
	case RT_BSDF_MAPPED:
		SIMD_STEP(tr, RT_SIMD_SHADE);
		if (u_lobe < b->mirror) {
			out->wi = (float3)(-wo.x, -wo.y, wo.z);
			out->weight = schlick3(tr, b->tint, wo.z);
			out->pdf = 0.0f;
			out->delta = true;
			return true;
		}
		/* fall through: the diffuse lobe */
	default:
		if (b->type != RT_BSDF_MAPPED) /* its step was taken above */
			SIMD_STEP(tr, RT_SIMD_SHADE);
		out->wi = cosine_direction(tr, u);
		if (out->wi.z <= 0.0f)
			return false;
		out->weight = b->color;
		out->pdf = (b->type == RT_BSDF_MAPPED ? 1.0f - b->mirror : 1.0f) * out->wi.z *
			   M_1_PI_F;
		COUNT_FLOPS(tr, 3);
		return true;
	}
}

#endif
