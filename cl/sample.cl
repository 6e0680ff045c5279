/* Where the samples of a pixel lie (docs/RENDERING.md, "Samples per pixel"):
 * the first two dimensions of the Sobol' sequence, a (0,2)-sequence,
 * scrambled per pixel by an XOR with a hash of (x, y), in 24-bit fixed point.
 * Integer work only, then one exact scaling by 2^-24, so every device, kernel
 * and the CPU reference (host/render/reference.cpp) place the samples on the same
 * bits. Part of the tracer: built after tracer.cl. */

/* Fixed-point bits of a sample coordinate: 2^-24 · bits is exact in float. */
#define SAMPLE_BITS 24

/* A 32-bit integer hash with good avalanche (Wellons's "lowbias32"). */
static inline uint sample_hash(uint v)
{
	v ^= v >> 16;
	v *= 0x7feb352du;
	v ^= v >> 15;
	v *= 0x846ca68bu;
	v ^= v >> 16;
	return v;
}

/* Sobol' dimension 0 of index k: the van der Corput radical inverse in base 2. */
static inline uint sobol_dim0(uint k)
{
	uint r = 0;

	for (uint v = 1u << 31; k; k >>= 1, v >>= 1)
		if (k & 1u)
			r ^= v;
	return r;
}

/* Sobol' dimension 1 of index k (primitive polynomial x + 1, direction
 * numbers v_{i+1} = v_i ^ (v_i >> 1)). */
static inline uint sobol_dim1(uint k)
{
	uint r = 0;

	for (uint v = 1u << 31; k; k >>= 1, v ^= v >> 1)
		if (k & 1u)
			r ^= v;
	return r;
}

/* Returns sample k of pixel (x, y) out of n, in [0, 1)^2, as the 24-bit
 * integers u·2^24 and v·2^24. n = 1 gives the centre (2^23, 2^23). */
static inline uint2 sample_bits(int x, int y, uint k, uint n)
{
	if (n == 1)
		return (uint2)(1u << (SAMPLE_BITS - 1));
	uint su = sample_hash(sample_hash((uint)x) ^ (uint)y);
	uint sv = sample_hash(su);
	return (uint2)((sobol_dim0(k) ^ su) >> (32 - SAMPLE_BITS),
		       (sobol_dim1(k) ^ sv) >> (32 - SAMPLE_BITS));
}

/* Returns sample k of pixel (x, y) out of n as offsets in [0, 1)^2 from the
 * pixel's corner. Counted 2 (the two scalings; the conversions are exact and
 * count 0 like integer work); n = 1 is the constant 0.5 and counts 0. */
static inline float2 sample_offset(struct tracer *tr, int x, int y, uint k, uint n)
{
#if defined(RTCL_PROBE_JITTER) || defined(RTCL_PROBE_SAMPLE_WORK)
	/* Measurement probes for one sample per pixel, defined only through
	 * RTCL_BUILD_OPTIONS (docs/performance.md, "Why a sample costs more with
	 * --spp N > 1"): JITTER traces sample 0 of 2's scrambled position, not
	 * the centre (another image); with SHIFT too, one off-centre position
	 * for every pixel (another image); SAMPLE_WORK computes the bits and
	 * keeps the centre (the same image: k is 0, which the compiler cannot
	 * know). */
	if (n == 1) {
		uint2 probe = sample_bits(x, y, k, 2);
#if defined(RTCL_PROBE_JITTER) && defined(RTCL_PROBE_SHIFT)
		return (float2)(0.3125f, 0.6875f) + convert_float2(probe & (uint2)(k));
#elif defined(RTCL_PROBE_JITTER)
		COUNT_FLOPS(tr, 2);
		return convert_float2(probe) * 0x1p-24f;
#else
		return (float2)(0.5f) + convert_float2(probe & (uint2)(k));
#endif
	}
#endif
	uint2 bits = sample_bits(x, y, k, n);

	if (n == 1)
		return (float2)(0.5f);
	COUNT_FLOPS(tr, 2);
	return convert_float2(bits) * 0x1p-24f;
}

/* Returns channel c of a sample's colour in fixed point, round(c *
 * RT_SUM_ONE), saturated (rtcl_shared.h, RT_SUM_LIMIT). */
static inline long sample_fixed(float c)
{
	if (!(c < RT_SUM_LIMIT)) /* also NaN */
		return RT_SUM_SATURATED;
	return convert_long_rte(fmax(c, -RT_SUM_LIMIT) * RT_SUM_ONE);
}

/* A pixel's sum is a long4 (docs/RENDERING.md, "Samples per pixel"): in x, y
 * and z the fixed-point sums of its samples' channels that did not saturate,
 * in w the channels that did, bits 1 (red), 2 (green) and 4 (blue). */

/* Returns a sample's colour as a term of the pixel's sum: each channel in
 * fixed point, a saturated one 0 with its bit set. Its three scalings count
 * 3; the conversions and the integer sums are exact and count 0. */
static inline long4 sample_term(struct tracer *tr, float3 color)
{
	long x = sample_fixed(color.x), y = sample_fixed(color.y), z = sample_fixed(color.z);
	long bits = (x == RT_SUM_SATURATED ? 1 : 0) | (y == RT_SUM_SATURATED ? 2 : 0) |
		    (z == RT_SUM_SATURATED ? 4 : 0);

	COUNT_FLOPS(tr, 3);
	return (long4)(bits & 1 ? 0 : x, bits & 2 ? 0 : y, bits & 4 ? 0 : z, bits);
}

/* Returns a + b, two sums of a pixel's samples: the channels added, the
 * saturated channels joined. */
static inline long4 sample_sums(long4 a, long4 b)
{
	return (long4)(a.x + b.x, a.y + b.y, a.z + b.z, a.w | b.w);
}

#ifdef cl_khr_int64_base_atomics
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
/* Adds term to pixel's sum in sums with 64-bit atomics: integers, so the
 * sum is the same whatever order the terms come in (the wavefront's stages
 * form adds the samples of one pixel from several work-items). */
static inline void sample_add_atomic(__global long *sums, int pixel, long4 term)
{
	volatile __global long *sum = (volatile __global long *)sums + 4 * (size_t)pixel;

	if (term.x)
		atom_add(sum, term.x);
	if (term.y)
		atom_add(sum + 1, term.y);
	if (term.z)
		atom_add(sum + 2, term.z);
	if (term.w)
		atom_or(sum + 3, term.w);
}
#endif

#if defined(cl_khr_int64_base_atomics) && !defined(RTCL_SUM_IN_REGISTERS)
/* A pass adds each sample's term to the pixel's sum where it lies, with
 * 64-bit atomics whose results it does not wait for, so that no sum is live
 * in registers across a trace: 1.8 % faster than the pass's sum in registers
 * on an H200 at 2048 spp, and 1.1 % faster than the float sums before the
 * fixed point (docs/results/multidevice, batch 77). Only the work-item of
 * the pixel writes it; the atomics only spare it the read. Devices without
 * 64-bit atomics (and RTCL_SUM_IN_REGISTERS) keep the pass's sum in
 * registers instead: the same integers, so the same image. */
#define RTCL_SUM_IN_PLACE
#endif

#ifdef RTCL_SUM_IN_PLACE
/* Adds term to pixel's sum in sums in place, or stores it there when the
 * buffer does not hold the pixel's sum yet (held false). */
static inline void sample_add_in_place(__global long *sums, int pixel, long4 term, bool held)
{
	if (!held) {
		vstore4(term, pixel, sums);
		return;
	}
	sample_add_atomic(sums, pixel, term);
}

/* Returns pixel's sum after this work-item's atomics on it: read by atomics
 * too, so that no cached copy from before them is read. */
static inline long4 sample_read_in_place(__global long *sums, int pixel)
{
	volatile __global long *sum = (volatile __global long *)sums + 4 * (size_t)pixel;

	return (long4)(atom_add(sum, 0L), atom_add(sum + 1, 0L), atom_add(sum + 2, 0L),
		       atom_or(sum + 3, 0L));
}
#endif

/* Returns a channel's mean from its sum: the sum rounded to float, times
 * the piece's mean_scale (1 / (N * RT_SUM_ONE)); +inf when saturated. */
static inline float sample_mean_channel(long sum, bool saturated, float scale)
{
	return saturated ? INFINITY : convert_float_rte(sum) * scale;
}

/* Returns the pixel's mean colour from the sum of all its N samples: one
 * product per channel, counted 3 (the exact rounding of the integer to float
 * counts 0, as the sample position's conversions do). */
static inline float3 sample_mean(struct tracer *tr, long4 sum, const struct rt_piece *piece)
{
	COUNT_FLOPS(tr, 3);
	return (float3)(sample_mean_channel(sum.x, sum.w & 1, piece->mean_scale),
			sample_mean_channel(sum.y, sum.w & 2, piece->mean_scale),
			sample_mean_channel(sum.z, sum.w & 4, piece->mean_scale));
}

/* Whether a pass over piece holds the pixel's sum so far in the sums buffer
 * (it does not start the buffer's samples), and whether it ends the pixel:
 * its last sample is the render's last and the buffer holds them all. */
static inline bool sample_sum_held(const struct rt_piece *piece, int sample_begin)
{
	return sample_begin > piece->sum_begin;
}

static inline bool sample_ends_pixel(const struct rt_piece *piece, int sample_end)
{
	return sample_end == piece->samples && piece->sum_begin == 0;
}

/* Kensler's hashed permutation of 0 ... n-1 ("Correlated Multi-Jittered
 * Sampling", 2013): returns where i goes under the permutation seeded by p.
 * The rounds are a bijection of 0 ... w (w + 1 a power of two), walked until
 * the result falls below n: less than two rounds on average. */
static inline uint sample_permute(uint i, uint n, uint p)
{
	uint w = n - 1;

	w |= w >> 1;
	w |= w >> 2;
	w |= w >> 4;
	w |= w >> 8;
	w |= w >> 16;
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

/* Returns dimension pair `pair` (>= 1: the lens, the lights) of sample k of
 * pixel (x, y) out of n, in [0, 1)^2 (RENDERING.md, "More dimensions"): the
 * same scrambled (0,2)-sequence as the pixel position, its samples shuffled
 * per pixel and pair so that the pairs do not move together. Counted 2, the
 * two scalings. */
static inline uint2 sample_pair_bits(int x, int y, uint k, uint n, uint pair)
{
	uint seed = sample_hash(sample_hash(sample_hash((uint)x) ^ (uint)y) ^ sample_hash(pair));
	uint a = sample_hash(seed), b = sample_hash(a);
	uint i = sample_permute(k, n, seed);
	return (uint2)((sobol_dim0(i) ^ a) >> (32 - SAMPLE_BITS),
		       (sobol_dim1(i) ^ b) >> (32 - SAMPLE_BITS));
}

static inline float2 sample_pair(struct tracer *tr, int x, int y, uint k, uint n, uint pair)
{
	uint2 bits = sample_pair_bits(x, y, k, n, pair);

	COUNT_FLOPS(tr, 2);
	return convert_float2(bits) * 0x1p-24f;
}

/* Shirley and Chiu's concentric mapping of [0, 1)^2 onto the unit disk
 * (RENDERING.md, "The thin lens"): squares go to rings, so the strata of the
 * sequence stay compact on the disk. Counted 4, then 7, or 8 in the third
 * case, or nothing more at the centre. */
static inline float2 sample_disk(struct tracer *tr, float2 st)
{
	float x = 2.0f * st.x - 1.0f, y = 2.0f * st.y - 1.0f;
	float radius, phi;

	COUNT_FLOPS(tr, 4);
	if (x == 0.0f && y == 0.0f)
		return (float2)(0.0f);
	if (fabs(x) > fabs(y)) {
		radius = x;
		phi = M_PI_4_F * (y / x);
		COUNT_FLOPS(tr, 7);
	} else {
		radius = y;
		phi = M_PI_2_F - M_PI_4_F * (x / y);
		COUNT_FLOPS(tr, 8);
	}
	return (float2)(radius * cos(phi), radius * sin(phi));
}
