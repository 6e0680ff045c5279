/* Small vector maths on double[3], for the host's geometry (camera basis,
 * triangle normals, the --frames orbit). static inline, not macros
 * (docs/STYLE.md); each written out in one order, so that results stay
 * bit for bit what the callers computed by hand. */
#ifndef RTCL_VEC3_H
#define RTCL_VEC3_H

#include <math.h>

static inline double vec3_dot(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline double vec3_length(const double v[3])
{
	return sqrt(vec3_dot(v, v));
}

/* Scales v to length 1 (v must not be zero). */
static inline void vec3_normalize(double v[3])
{
	double length = vec3_length(v);

	for (int i = 0; i < 3; i++)
		v[i] /= length;
}

/* out = a × b; out must not be a or b. */
static inline void vec3_cross(const double a[3], const double b[3], double out[3])
{
	out[0] = a[1] * b[2] - a[2] * b[1];
	out[1] = a[2] * b[0] - a[0] * b[2];
	out[2] = a[0] * b[1] - a[1] * b[0];
}

#endif
