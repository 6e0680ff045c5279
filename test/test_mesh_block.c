/* Indexing the triangles for the device (host/layout/mesh_block.c): a vertex shared by
 * several triangles is stored once, vertices that differ in position or, on
 * smooth triangles, in normal are not merged, and every triangle reads back
 * the vertices, normals and material it was given. */
#include <criterion/criterion.h>

#include <string.h>

#include "layout/mesh_block.h"

static char err[512];

static void load(struct scene *s, const char *json)
{
	cr_assert_eq(scene_load_string(s, json, "mesh_block", err, sizeof(err)), 0, "%s", err);
}

/* Triangle i's corner k as the device reads it, against the scene's. */
static void expect_corner(const struct mesh_block *mesh, const struct scene *s, int i, int k)
{
	const struct scene_triangle *tri = &s->triangles[i];
	rt_uint v = mesh->triangles[i].index.s[k];

	cr_assert_lt(v, (rt_uint)mesh->vertex_count);
	for (int c = 0; c < 3; c++) {
		/* Relative to the eye, as the device computes (scene_from_eye). */
		cr_expect_eq(mesh->vertices[v].position.s[c],
			     (float)(tri->v[k][c] - s->camera.eye[c]));
		cr_expect_eq(mesh->normals[v].normal.s[c],
			     tri->smooth ? (float)tri->normal[k][c] : 0.0f);
	}
}

static void expect_round_trip(const struct mesh_block *mesh, const struct scene *s)
{
	for (int i = 0; i < s->triangle_count; i++) {
		rt_uint w = mesh->triangles[i].index.s[3];
		cr_expect_eq((int)(w & ~RT_TRIANGLE_SMOOTH), s->triangles[i].material);
		cr_expect_eq((w & RT_TRIANGLE_SMOOTH) != 0, s->triangles[i].smooth != 0);
		for (int k = 0; k < 3; k++)
			expect_corner(mesh, s, i, k);
	}
}

/* The flat cube: 12 triangles over 8 corners. */
Test(mesh_block, cube_corners_are_shared)
{
	struct scene s;
	struct mesh_block mesh;

	load(&s, "{\"format\": \"rtcl-scene\", \"version\": 2,"
		 " \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
		 " \"meshes\": [{\"file\": \"test/meshes/cube.obj\", \"smooth\": false}]}");
	cr_assert_eq(mesh_block_build(&s, &mesh), 0);
	cr_expect_eq(s.triangle_count, 12);
	cr_expect_eq(mesh.vertex_count, 8);
	expect_round_trip(&mesh, &s);
	mesh_block_free(&mesh);
	scene_free(&s);
}

/* Smooth, the cube's area-weighted normals are one per corner: still 8. The
 * mixed scene below shares no vertex between a flat and a smooth triangle
 * (their normals differ), and two inline triangles on one edge share it. */
Test(mesh_block, normals_keep_vertices_apart)
{
	struct scene s;
	struct mesh_block mesh;

	load(&s, "{\"format\": \"rtcl-scene\", \"version\": 2,"
		 " \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
		 " \"meshes\": [{\"file\": \"test/meshes/cube.obj\"},"
		 "              {\"file\": \"test/meshes/cube.obj\", \"smooth\": false}],"
		 " \"triangles\": [{\"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]},"
		 "               {\"vertices\": [[1, 0, 0], [0, 1, 0], [1, 1, 0]],"
		 "                \"material\": {\"color\": [1, 0, 0]}}]}");
	cr_assert_eq(mesh_block_build(&s, &mesh), 0);
	cr_expect_eq(s.triangle_count, 26);
	cr_expect_eq(mesh.vertex_count, 8 + 8 + 4);
	expect_round_trip(&mesh, &s);
	mesh_block_free(&mesh);
	scene_free(&s);
}

Test(mesh_block, no_triangles)
{
	struct scene s;
	struct mesh_block mesh;

	load(&s, "{\"format\": \"rtcl-scene\", \"version\": 2,"
		 " \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
		 " \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}]}");
	cr_assert_eq(mesh_block_build(&s, &mesh), 0);
	cr_expect_eq(mesh.vertex_count, 0);
	cr_expect_null(mesh.triangles);
	mesh_block_free(&mesh);
	scene_free(&s);
}
