/* The placement maths of a version 2 mesh (docs/SCENE.md): scale, then
 * rotate, then translate, and the normals that go with it (the file's, or
 * area-weighted ones), in double. host/scene/scene_mesh.c reads the fields and
 * words the messages; this module only computes. */
#ifndef RTCL_MESH_PLACE_H
#define RTCL_MESH_PLACE_H

#include "scene/mesh.h"

/* p' = R (s p) + t, and for normals n' = R (n / s), the inverse transpose
 * of R S. */
struct placement {
	double scale[3];
	double rotation[3][3]; /* Rz Ry Rx */
	double translate[3];
	int mirrored; /* an odd number of negative scale parts */
	int smooth;
};

/* Sets pl->rotation to Rz Ry Rx of `degrees` (about x first, then y, then z,
 * all world axes) and pl->mirrored from pl->scale. */
void place_set_rotation(struct placement *pl, const double degrees[3]);

/* p' = R (s p) + t. */
void place_point(const struct placement *pl, const double in[3], double out[3]);

/* v' = R (s v): a direction (a camera's) placed, not normalised. */
void place_vector(const struct placement *pl, const double in[3], double out[3]);

/* Scales v to unit length; returns 0 (v untouched) for a zero or non-finite v. */
int place_unit(double v[3]);

/* The unit geometric normal (v1 - v0) x (v2 - v0); returns 0 for zero area. */
int place_triangle_normal(const double v[3][3], double n[3]);

/* The file's vertex normals in world space, R (n / s); a zero or non-finite
 * one becomes zero: the triangle's own normal is used there. */
void place_file_normals(const struct mesh_data *mesh, const struct placement *pl, double *vn);

/* Area-weighted vertex normals of the placed vertices (3 per vertex) for a
 * file without normals, joined by position; vn comes in zeroed. Returns -1
 * when out of memory. */
int place_area_weighted_normals(const struct mesh_data *mesh, const double *placed, int mirrored,
				double *vn);

#endif
