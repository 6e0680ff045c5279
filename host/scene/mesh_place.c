/* The placement maths of a version 2 mesh (see mesh_place.h). */
#define _POSIX_C_SOURCE 200809L

#include "scene/mesh_place.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/vec3.h"
#include "scene/scene_loader.h"

/* cos and sin of `degrees`, exact at multiples of 90 (cos(pi/2) in double is
 * 6e-17, which would tilt an axis-aligned mesh). */
static void cos_sin(double degrees, double *c, double *s)
{
	double quarter = degrees / 90.0;

	if (quarter == floor(quarter) && fabs(quarter) < 1e15) {
		static const double cosines[] = {1, 0, -1, 0};
		long k = ((long)fmod(quarter, 4.0) + 4) % 4;

		*c = cosines[k];
		*s = cosines[(k + 3) % 4];
		return;
	}
	*c = cos(degrees * M_PI / 180.0);
	*s = sin(degrees * M_PI / 180.0);
}

static void multiply(const double a[3][3], const double b[3][3], double out[3][3])
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			out[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
}

void place_set_rotation(struct placement *pl, const double degrees[3])
{
	double cx, sx, cy, sy, cz, sz, zy[3][3];

	cos_sin(degrees[0], &cx, &sx);
	cos_sin(degrees[1], &cy, &sy);
	cos_sin(degrees[2], &cz, &sz);
	const double rx[3][3] = {{1, 0, 0}, {0, cx, -sx}, {0, sx, cx}};
	const double ry[3][3] = {{cy, 0, sy}, {0, 1, 0}, {-sy, 0, cy}};
	const double rz[3][3] = {{cz, -sz, 0}, {sz, cz, 0}, {0, 0, 1}};

	multiply(rz, ry, zy);
	multiply(zy, rx, pl->rotation);
	pl->mirrored = (pl->scale[0] < 0) ^ (pl->scale[1] < 0) ^ (pl->scale[2] < 0);
}

static void apply(const double m[3][3], const double v[3], double out[3])
{
	for (int i = 0; i < 3; i++)
		out[i] = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
}

void place_point(const struct placement *pl, const double in[3], double out[3])
{
	double scaled[3];

	for (int i = 0; i < 3; i++)
		scaled[i] = pl->scale[i] * in[i];
	apply(pl->rotation, scaled, out);
	for (int i = 0; i < 3; i++)
		out[i] += pl->translate[i];
}

void place_vector(const struct placement *pl, const double in[3], double out[3])
{
	double scaled[3];

	for (int i = 0; i < 3; i++)
		scaled[i] = pl->scale[i] * in[i];
	apply(pl->rotation, scaled, out);
}

int place_unit(double v[3])
{
	double scaled[3], length;

	if (!loader_scale_to_unit_max(v, scaled))
		return 0;
	length = loader_length3(scaled);
	if (!isfinite(length) || length == 0)
		return 0;
	for (int i = 0; i < 3; i++)
		v[i] = scaled[i] / length;
	return 1;
}

int place_triangle_normal(const double v[3][3], double n[3])
{
	double e1[3], e2[3];

	for (int i = 0; i < 3; i++) {
		e1[i] = v[1][i] - v[0][i];
		e2[i] = v[2][i] - v[0][i];
	}
	vec3_cross(e1, e2, n);
	return place_unit(n);
}

void place_file_normals(const struct mesh_data *mesh, const struct placement *pl, double *vn)
{
	for (size_t v = 0; v < mesh->vertex_count; v++) {
		double n[3];

		for (int i = 0; i < 3; i++)
			n[i] = mesh->normals[3 * v + i] / pl->scale[i];
		apply(pl->rotation, n, vn + 3 * v);
		if (!place_unit(vn + 3 * v))
			memset(vn + 3 * v, 0, 3 * sizeof(double));
	}
}

/* Each vertex gets the sum of the (unnormalised, so area-weighted) geometric
 * normals of the triangles that touch its position. Formats such as OBJ and
 * STL repeat a vertex for each triangle it belongs to, so vertices are joined
 * by position, not by index. */
struct by_position {
	double p[3];
	size_t index;
};

static int compare_positions(const void *a, const void *b)
{
	const double *p = ((const struct by_position *)a)->p,
		     *q = ((const struct by_position *)b)->p;

	for (int i = 0; i < 3; i++)
		if (p[i] != q[i])
			return p[i] < q[i] ? -1 : 1;
	return 0;
}

static void add_face_normals(const struct mesh_data *mesh, const double *placed, int mirrored,
			     double *vn)
{
	for (size_t t = 0; t < mesh->triangle_count; t++) {
		const size_t *ix = mesh->indices + 3 * t;
		double e1[3], e2[3], n[3];

		for (int i = 0; i < 3; i++) {
			e1[i] = placed[3 * ix[1] + i] - placed[3 * ix[0] + i];
			e2[i] = placed[3 * ix[2] + i] - placed[3 * ix[0] + i];
		}
		vec3_cross(e1, e2, n);
		for (int k = 0; k < 3; k++)
			for (int i = 0; i < 3; i++)
				vn[3 * ix[k] + i] += mirrored ? -n[i] : n[i];
	}
}

int place_area_weighted_normals(const struct mesh_data *mesh, const double *placed, int mirrored,
				double *vn)
{
	struct by_position *sorted = malloc((mesh->vertex_count + 1) * sizeof(*sorted));

	if (!sorted)
		return -1;
	add_face_normals(mesh, placed, mirrored, vn);
	for (size_t v = 0; v < mesh->vertex_count; v++) {
		memcpy(sorted[v].p, placed + 3 * v, sizeof(sorted[v].p));
		sorted[v].index = v;
	}
	qsort(sorted, mesh->vertex_count, sizeof(*sorted), compare_positions);
	for (size_t first = 0, end; first < mesh->vertex_count; first = end) {
		double sum[3] = {0, 0, 0};

		for (end = first; end < mesh->vertex_count &&
				  compare_positions(&sorted[first], &sorted[end]) == 0;
		     end++)
			for (int i = 0; i < 3; i++)
				sum[i] += vn[3 * sorted[end].index + i];
		place_unit(sum); /* a zero sum stays zero: the triangle's own normal is used */
		for (size_t k = first; k < end; k++)
			memcpy(vn + 3 * sorted[k].index, sum, sizeof(sum));
	}
	free(sorted);
	return 0;
}
