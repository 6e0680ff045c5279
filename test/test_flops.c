/* Flop counting (RENDERING.md): the shared tracer's pieces count exactly their
 * hand-counted operations, and every kernel counts the same work per pixel.
 *
 * The unit tests build the tracer (cl/tracer.cl and the files after it) with RTCL_COUNT_FLOPS and a
 * small test kernel that calls one tracer function on the analytic scene: a sphere of radius 1 at
 * the origin, a plane y = -1, a light at (3,0,5), eye (0,0,5).
 */
#include <criterion/criterion.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rtcl_shared.h"
#include "layout/bvh.h"
#include "layout/scene_block.h"
#include "device/device.h"
#include "base/embedded.h"
#include "render/program.h"
#include "render/render.h"
#include "scene/scene.h"

static char err[65536];

static const char analytic_json[] =
	"{\"format\": \"rtcl-scene\", \"version\": 1,"
	" \"image\": {\"width\": 3, \"height\": 3},"
	" \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
	" \"lights\": [{\"position\": [3, 0, 5]}],"
	" \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}],"
	" \"planes\": [{\"point\": [0, -1, 0], \"normal\": [0, 1, 0]}]}";

/* One triangle in the plane z = 0, seen from the same eye: v0 = (-1,-1,0),
 * e1 = (2,0,0), e2 = (1,2,0). */
static const char triangle_json[] =
	"{\"format\": \"rtcl-scene\", \"version\": 2,"
	" \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
	" \"triangles\": [{\"vertices\": [[-1, -1, 0], [1, -1, 0], [0, 1, 0]]}]}";

/* A sliver: area 5e-11 in double, but 2 + 1e-10 rounds to 2 in float, where
 * its vertices lie on a line and e1 x e2 is 0. */
static const char sliver_json[] =
	"{\"format\": \"rtcl-scene\", \"version\": 2,"
	" \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
	" \"triangles\": [{\"vertices\": [[0, 0, 0], [1, 1, 0], [2, 2.0000000001, 0]]}]}";

/* One smooth triangle from a file, v0 = (0,0,0), v1 = (1,0,0), v2 = (0,1,0),
 * with vertex normals n0 = (0,0,1), n1 = (0,0,-1), n2 = (0,0,1). */
static const char smooth_json[] = "{\"format\": \"rtcl-scene\", \"version\": 2,"
				  " \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
				  " \"meshes\": [{\"file\": \"test/meshes/opposed_normals.obj\"}]}";

/* Each test kernel writes the flops counted into out[0] and a result into
 * out[1] (as float bits) so the test can check it took the intended path. */
static const char test_kernels[] =
	"__kernel void count_sphere(__global const uint4 *scene, __global ulong *out,"
	"                           float4 o, float4 d)\n"
	"{\n"
	"	struct tracer tr;\n"
	"	tracer_init(&tr, (scene_ptr)scene, out, out);\n"
	"	struct hit hit = intersect_scene(&tr, o.xyz, d.xyz, INFINITY, false);\n"
	"	out[0] = tr.flops;\n"
	"	out[1] = as_uint(hit.t);\n"
	"	out[2] = tr.node_visits;\n"
	"	out[3] = tr.leaf_visits;\n"
	"	out[4] = tr.prim_tests;\n"
	"}\n"
	"__kernel void count_plane(__global const uint4 *scene, __global ulong *out,"
	"                          float4 o, float4 d)\n"
	"{\n"
	"	struct tracer tr;\n"
	"	tracer_init(&tr, (scene_ptr)scene, out, out);\n"
	"	float t = intersect_plane(&tr, &tr.planes[0], o.xyz, d.xyz);\n"
	"	out[0] = tr.flops;\n"
	"	out[1] = as_uint(t);\n"
	"}\n"
	"__kernel void count_triangle(__global const uint4 *scene, __global ulong *out,"
	"                             float4 o, float4 d)\n"
	"{\n"
	"	struct tracer tr;\n"
	"	float t = 0.0f;\n"
	"	float2 uv;\n"
	"	tracer_init(&tr, (scene_ptr)scene, out, out);\n"
	"	bool hit = triangle_hit(&tr, 0, o.xyz, d.xyz, INFINITY, &t, &uv);\n"
	"	out[0] = tr.flops;\n"
	"	out[1] = as_uint(hit ? t : -1.0f);\n"
	"}\n"
	"__kernel void count_triangle_normal(__global const uint4 *scene, __global ulong *out,"
	"                                    float4 unused, float4 d)\n"
	"{\n"
	"	struct tracer tr;\n"
	"	tracer_init(&tr, (scene_ptr)scene, out, out);\n"
	"	float3 n = triangle_normal(&tr, tr.triangles[0].index, d.xyz);\n"
	"	out[0] = tr.flops;\n"
	"	out[1] = as_uint(n.x + 2.0f * n.y + 4.0f * n.z);\n"
	"}\n"
	"__kernel void count_smooth_normal(__global const uint4 *scene, __global ulong *out,"
	"                                  float4 uv, float4 n_face)\n"
	"{\n"
	"	struct tracer tr;\n"
	"	struct hit hit = {1.0f, -1, -1, 0, uv.x, uv.y};\n"
	"	tracer_init(&tr, (scene_ptr)scene, out, out);\n"
	"	float3 n = triangle_shading_normal(&tr, tr.triangles[0].index, hit, n_face.xyz);\n"
	"	out[0] = tr.flops;\n"
	"	out[1] = as_uint(n.z);\n"
	"}\n"
	"__kernel void count_shading(__global const uint4 *scene, __global ulong *out,"
	"                            float4 o, float4 d)\n"
	"{\n"
	"	struct tracer tr;\n"
	"	struct ray_job ray = {o.xyz, d.xyz, 1.0f, RTCL_MAX_DEPTH};\n"
	"	struct ray_job children[2];\n"
	"	int spawned;\n"
	"	tracer_init(&tr, (scene_ptr)scene, out, out);\n"
	"	float3 c = trace_one(&tr, &ray, children, &spawned);\n"
	"	out[0] = tr.flops;\n"
	"	out[1] = as_uint(c.x);\n"
	"}\n";

struct fixture {
	struct device dev;
	struct scene scene;
	cl_program program;
	cl_mem scene_buffer, out;
	cl_ulong node_visits; /* what count_sphere counted, by run_kernel */
	cl_ulong leaf_visits, prim_tests;
};

/* Builds the test kernels over the scene json, with its BVH and RTCL_BVH
 * when bvh, and the tracer's other options `options` (max depth 1 when
 * NULL). */
static void setup_scene_with(struct fixture *f, const char *json, int bvh, const char *options)
{
	const char *sources[16];
	int count = 0;
	size_t bytes;
	cl_int status;

	for (; count < program_tracer_source_count; count++)
		sources[count] = embedded_file(program_tracer_sources[count]);
	sources[count++] = test_kernels;
	cr_assert_eq(device_open(&f->dev, -1, -1, err, sizeof(err)), 0, "%s", err);
	cr_assert_eq(scene_load_string(&f->scene, json, "analytic", err, sizeof(err)), 0, "%s",
		     err);
	struct bvh tree;
	struct mesh_block mesh;
	cr_assert_eq(bvh_build_scene(&f->scene, BVH_TRIANGLE_COST, &tree), 0);
	cr_assert_eq(mesh_block_build(&f->scene, &mesh), 0);
	void *block = scene_block_pack(&f->scene, &mesh, bvh ? &tree : NULL, 3, 3, 1, &bytes);
	bvh_free(&tree);
	mesh_block_free(&mesh);
	f->program =
		clCreateProgramWithSource(f->dev.context, (cl_uint)count, sources, NULL, &status);
	cr_assert_eq(status, CL_SUCCESS);
	char build[256];
	snprintf(build, sizeof(build), "-cl-std=CL1.2 -DRTCL_COUNT_FLOPS %s %s",
		 options ? options : "-DRTCL_MAX_DEPTH=1", bvh ? "-DRTCL_BVH" : "");
	status = clBuildProgram(f->program, 1, &f->dev.id, build, NULL, NULL);
	if (status != CL_SUCCESS) {
		clGetProgramBuildInfo(f->program, f->dev.id, CL_PROGRAM_BUILD_LOG, sizeof(err), err,
				      NULL);
		cr_assert_fail("build failed: %s\n%s", cl_error_name(status), err);
	}
	f->scene_buffer = clCreateBuffer(f->dev.context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
					 bytes, block, &status);
	cr_assert_eq(status, CL_SUCCESS);
	f->out = clCreateBuffer(f->dev.context, CL_MEM_READ_WRITE, 64, NULL, &status);
	cr_assert_eq(status, CL_SUCCESS);
	free(block);
}

static void setup_scene(struct fixture *f, const char *json, int bvh)
{
	setup_scene_with(f, json, bvh, NULL);
}

static void setup(struct fixture *f)
{
	setup_scene(f, analytic_json, 0);
}

static void teardown(struct fixture *f)
{
	clReleaseMemObject(f->out);
	clReleaseMemObject(f->scene_buffer);
	clReleaseProgram(f->program);
	scene_free(&f->scene);
	device_close(&f->dev);
}

/* Runs one test kernel on one work-item; returns the flops it counted and
 * stores its float result in *result. */
static cl_ulong run_kernel(struct fixture *f, const char *name, const float a[4], const float b[4],
			   float *result)
{
	cl_int status;
	cl_kernel kernel = clCreateKernel(f->program, name, &status);
	size_t one = 1;
	cl_ulong out[5];
	/* A ray's origin, given in world coordinates here, goes in the device's:
	 * relative to the eye (scene_from_eye). */
	int a_is_origin = strcmp(name, "count_triangle_normal") != 0 &&
			  strcmp(name, "count_smooth_normal") != 0;
	const double *eye = f->scene.camera.eye;
	cl_float4 va = {{a_is_origin ? (float)(a[0] - eye[0]) : a[0],
			 a_is_origin ? (float)(a[1] - eye[1]) : a[1],
			 a_is_origin ? (float)(a[2] - eye[2]) : a[2], a[3]}};
	cl_float4 vb = {{b[0], b[1], b[2], b[3]}};

	cr_assert_eq(status, CL_SUCCESS, "clCreateKernel(%s): %s", name, cl_error_name(status));
	clSetKernelArg(kernel, 0, sizeof(cl_mem), &f->scene_buffer);
	clSetKernelArg(kernel, 1, sizeof(cl_mem), &f->out);
	clSetKernelArg(kernel, 2, sizeof(va), &va);
	clSetKernelArg(kernel, 3, sizeof(vb), &vb);
	status = clEnqueueNDRangeKernel(f->dev.queue, kernel, 1, NULL, &one, &one, 0, NULL, NULL);
	cr_assert_eq(status, CL_SUCCESS, "%s", cl_error_name(status));
	status = clEnqueueReadBuffer(f->dev.queue, f->out, CL_TRUE, 0, sizeof(out), out, 0, NULL,
				     NULL);
	cr_assert_eq(status, CL_SUCCESS);
	clReleaseKernel(kernel);
	f->node_visits = out[2];
	f->leaf_visits = out[3];
	f->prim_tests = out[4];
	uint32_t bits = (uint32_t)out[1];
	memcpy(result, &bits, sizeof(*result));
	return out[0];
}

Test(flops, ray_sphere_test)
{
	struct fixture f;
	const float eye[4] = {0, 0, 5, 0};
	const float down_axis[4] = {0, 0, -1, 0}, up[4] = {0, 1, 0, 0};
	float t;

	setup(&f);
	/* intersect_scene over the sphere and the plane y = -1. The ray's frame
	 * (ray_frame): 23. The sphere: its offset across the ray, two fma chains
	 * of 6, and the squared length, 3: 15, which a miss stops at. A hit with
	 * the centre ahead: oc = o - c (3), b = oc.d (5), r2 - gap (1), far =
	 * sqrt(.) - b (2), near = (oc.oc - r2) / far (5 + 1 + 1 = 7): 15 + 18 =
	 * 33. The plane, parallel to d: n.d (5). 61 in all, and t = 4. */
	cr_expect_eq(run_kernel(&f, "count_sphere", eye, down_axis, &t), 61);
	cr_expect_float_eq(t, 4.0f, 1e-6f);
	/* Up the y axis: the frame (23), the sphere missed (15), the plane
	 * behind: n.d (5), t = (offset - n.o) / denom (7), negative. 50, t = 0. */
	cr_expect_eq(run_kernel(&f, "count_sphere", eye, up, &t), 50);
	cr_expect_eq(t, 0.0f);
	/* From inside, centre behind (b > 0): 23 + 15 + 11 (t is far), the
	 * plane parallel (5): 54, t = far. */
	const float inside[4] = {0, 0, 0.5f, 0}, outward[4] = {0, 0, 1, 0};
	cr_expect_eq(run_kernel(&f, "count_sphere", inside, outward, &t), 54);
	cr_expect_float_eq(t, 0.5f, 1e-6f);
	teardown(&f);
}

/* The BVH's part (RENDERING.md, "BVH traversal"): the analytic scene's one
 * sphere is a root whose two children are the same leaf (host/layout/bvh.c). */
Test(flops, ray_box_test)
{
	struct fixture f;
	const float eye[4] = {0, 0, 5, 0};
	const float down_axis[4] = {0, 0, -1, 0}, up[4] = {0, 1, 0, 0};
	float t;

	setup_scene(&f, analytic_json, 1);
	/* The frame 23; the box set-up, 1/d (3) and o/d (3): 6; the root's two
	 * boxes, each six slab fmas (12), a min and a max per axis (6), the
	 * entry's three maxes and the exit's three mins (6): 48, both hit.
	 * The leaf, twice: the sphere hit as in ray_sphere_test (33) the first
	 * time, the same again (33), which does not replace it. The plane,
	 * parallel (5). 23 + 6 + 48 + 66 + 5 = 148, one node visit, t = 4. */
	cr_expect_eq(run_kernel(&f, "count_sphere", eye, down_axis, &t), 148);
	cr_expect_eq(f.node_visits, 1);
	cr_expect_eq(f.leaf_visits, 2); /* the same leaf, from both children */
	cr_expect_eq(f.prim_tests, 2);
	cr_expect_float_eq(t, 4.0f, 1e-6f);
	/* Up the y axis, beside the box in z (the z slab's 0 · inf is NaN or
	 * -inf, which the min and max pass over): 23 + 6 + 48, no leaf; the
	 * plane behind (12). 89, t = 0. */
	cr_expect_eq(run_kernel(&f, "count_sphere", eye, up, &t), 89);
	cr_expect_eq(f.node_visits, 1);
	cr_expect_eq(f.leaf_visits, 0);
	cr_expect_eq(f.prim_tests, 0);
	cr_expect_eq(t, 0.0f);
	teardown(&f);
}

Test(flops, plane_test)
{
	struct fixture f;
	const float eye[4] = {0, 0, 5, 0};
	const float down[4] = {0, -1, 0, 0}, sideways[4] = {1, 0, 0, 0};
	float t;

	setup(&f);
	/* denom = n.d (5); t = (offset - n.o) / denom (5 + 1 + 1): 12, t = 1. */
	cr_expect_eq(run_kernel(&f, "count_plane", eye, down, &t), 12);
	cr_expect_float_eq(t, 1.0f, 1e-6f);
	/* Parallel to the plane: only the denominator, 5. */
	cr_expect_eq(run_kernel(&f, "count_plane", eye, sideways, &t), 5);
	cr_expect_eq(t, 0.0f);
	teardown(&f);
}

Test(flops, shading_evaluation)
{
	struct fixture f;
	const float o[4] = {0, 0, 5, 0}, d[4] = {0, 0, -1, 0};
	float red;

	setup(&f);
	/* trace_one of a ray at the last depth (nothing spawned) from (0,0,5)
	 * along d = (0,0,-1): it hits the sphere at p = (0,0,1), n = (0,0,1);
	 * default material (white, ka 1, kd 0.7, ks 0.3, shininess 32), ambient
	 * 0.1, white light at (3,0,5):
	 *   the hit, as in ray_sphere_test        61
	 *   p = o + t d 6, n = (p - c) / r 6, inside: n.d 5   17
	 *   ka C (x) ambient                      3 + 3 = 6
	 *   shadow origin p + eps n               3 + 3 = 6
	 *   the light: light - p 3, its squared length 5, 1/distance
	 *     (rsqrt) 1, distance 1, L 3, kd max(0, n.L) 5 + 1 + 1    20
	 *   L - d 3, its squared length 5         8
	 *   H 1 + 3, ks max(0, n.H)^s 5 + 3       12
	 *   the shadow ray: its frame 23, the sphere it leaves, within the
	 *     radius, centre behind: 15 + 11; the plane y = -1: n.d = 0,
	 *     parallel: 5                          54
	 *   (kd max + ks spec) C (x) Lc, added    3 + 3 + 3 + 3 = 12
	 *   weight times the local colour         3
	 * 61 + 17 + 6 + 6 + 20 + 8 + 12 + 54 + 12 + 3 = 199.
	 * Red: 0.1 + 0.7 * 0.8 + 0.3 * ((1.8 / sqrt(3.6))^2)^16 = 0.1 + 0.56 + 0.3 * 0.9^16. */
	cr_expect_eq(run_kernel(&f, "count_shading", o, d, &red), 199);
	cr_expect_float_eq(red, 0.1 + 0.56 + 0.3 * 0.18530202, 1e-5);
	teardown(&f);
}

/* A scene without lights at max_depth 0 uses no normal (RENDERING.md step
 * 2), so the hit above computes and counts none: the hit 61, p 6, ka C (x)
 * ambient 6, the shadow origin 6 (along n_face = -d), the weight 3: 82,
 * where 199 - 82 is the normal, the side test and the light's terms. The
 * same colour: the ambient term, 0.1. (A build of its own: flops_slow.) */
Test(flops_slow, shading_without_lights_at_depth_0_counts_no_normal)
{
	struct fixture f;
	const float o[4] = {0, 0, 5, 0}, d[4] = {0, 0, -1, 0};
	float red;

	setup_scene_with(&f, analytic_json, 0, "-DRTCL_MAX_DEPTH=0 -DRTCL_NO_LIGHTS");
	cr_expect_eq(run_kernel(&f, "count_shading", o, d, &red), 82);
	cr_expect_float_eq(red, 0.1, 1e-6);
	teardown(&f);
}

/* triangle_hit by stage (RENDERING.md): the edges e1 = v1 - v0 and
 * e2 = v2 - v0 3 + 3, det = e1.(d x e2), a cross product 9 and a dot
 * product 5: 20, where a ray parallel to the triangle stops; 1/det 1,
 * s = o - v0 3, u = (s.p)/det 5 + 1: 30, where u outside [0, 1] stops;
 * q = s x e1 9, v = (d.q)/det 5 + 1, u + v 1: 46, where v < 0 or u + v > 1
 * stops; t = (e2.q)/det 5 + 1: 52. */
Test(flops, ray_triangle_test)
{
	struct fixture f;
	const float eye[4] = {0, 0, 5, 0}, ahead[4] = {0, 0, -1, 0}, behind[4] = {0, 0, 1, 0};
	const float parallel[4] = {1, 0, 0, 0};
	const float right_of_it[4] = {3, 0, 5, 0}, above_it[4] = {0.9f, 0.5f, 5, 0};
	float t;

	setup_scene(&f, triangle_json, 0);
	cr_expect_eq(run_kernel(&f, "count_triangle", eye, ahead, &t), 52);
	cr_expect_float_eq(t, 5.0f, 1e-6f);
	/* From behind the eye's side, the plane is behind: all 52, no hit. */
	cr_expect_eq(run_kernel(&f, "count_triangle", eye, behind, &t), 52);
	cr_expect_eq(t, -1.0f);
	/* d x e2 = (0,0,2), e1.(0,0,2) = 0. */
	cr_expect_eq(run_kernel(&f, "count_triangle", eye, parallel, &t), 20);
	cr_expect_eq(t, -1.0f);
	/* Through (3,0,0): s = (4,1,5), p = (2,-1,0), det 4, u = 7/4. */
	cr_expect_eq(run_kernel(&f, "count_triangle", right_of_it, ahead, &t), 30);
	cr_expect_eq(t, -1.0f);
	/* Through (0.9,0.5,0): u = 0.575, v = 0.75, u + v > 1. */
	cr_expect_eq(run_kernel(&f, "count_triangle", above_it, ahead, &t), 46);
	cr_expect_eq(t, -1.0f);
	teardown(&f);
}

/* The geometric normal at a triangle hit (RENDERING.md): the edges 3 + 3,
 * their cross product 9, its largest component in size (2 maxima): 17,
 * where a cross product of 0 stops (the triangle faces the ray: -d); then
 * 1/largest 1, the scaling 3 and the normalisation 9: 30. The kernel returns
 * n.x + 2 n.y + 4 n.z, to tell the normals apart. */
Test(flops, triangle_geometric_normal)
{
	struct fixture f;
	const float none[4] = {0, 0, 0, 0}, d[4] = {0.6f, 0, -0.8f, 0};
	float code;

	/* e1 = (2,0,0), e2 = (1,2,0): e1 x e2 = (0,0,4), so n = (0,0,1). */
	setup_scene(&f, triangle_json, 0);
	cr_expect_eq(run_kernel(&f, "count_triangle_normal", none, d, &code), 30);
	cr_expect_eq(code, 4.0f);
	teardown(&f);

	setup_scene(&f, sliver_json, 0);
	cr_assert_eq(f.scene.triangle_count, 1);
	cr_expect_eq(run_kernel(&f, "count_triangle_normal", none, d, &code), 17);
	cr_expect_float_eq(code, -0.6f + 4.0f * 0.8f, 1e-6f);
	teardown(&f);
}

/* The smooth shading normal at a triangle hit (RENDERING.md): w = 1 - u - v
 * 2, w n0 + u n1 + v n2 three scalings 9 and two sums 6, its squared length
 * 5: 22, where a zero sum stops (n_face is used); then 1/length (rsqrt) 1,
 * the scaling 3 and the side test dot(n, n_face) 5: 31. */
Test(flops, smooth_shading_normal)
{
	struct fixture f;
	const float up[4] = {0, 0, 1, 0}, down[4] = {0, 0, -1, 0};
	const float at_v0[4] = {0, 0, 0, 0}, inner[4] = {0.25f, 0.25f, 0, 0};
	const float halfway_v0_v1[4] = {0.5f, 0, 0, 0};
	float z;

	setup_scene(&f, smooth_json, 0);
	cr_assert_eq(f.scene.triangle_count, 1);
	cr_assert_eq(f.scene.triangles[0].smooth, 1);
	/* At v0: n = n0 = (0,0,1), turned to n_face = (0,0,-1). */
	cr_expect_eq(run_kernel(&f, "count_smooth_normal", at_v0, down, &z), 31);
	cr_expect_eq(z, -1.0f);
	/* w = 0.5: 0.5 n0 + 0.25 n1 + 0.25 n2 = (0,0,0.5), normalised, kept. */
	cr_expect_eq(run_kernel(&f, "count_smooth_normal", inner, up, &z), 31);
	cr_expect_eq(z, 1.0f);
	/* w = 0.5, u = 0.5: 0.5 n0 + 0.5 n1 = 0, so n_face itself. */
	cr_expect_eq(run_kernel(&f, "count_smooth_normal", halfway_v0_v1, down, &z), 22);
	cr_expect_eq(z, -1.0f);
	teardown(&f);
}

static struct render_settings counting(const char *kernel, int wx, int wy, int max_depth, int accel)
{
	struct render_settings s;

	memset(&s, 0, sizeof(s));
	s.kernel = render_find_kernel(kernel);
	s.workgroup[0] = wx;
	s.workgroup[1] = wy;
	s.width = 61;
	s.height = 47;
	s.max_depth = max_depth;
	s.repeat = 1;
	s.count_flops = 1;
	s.check_writes = 1; /* guard zones: counting must not write out of bounds either */
	s.accel = accel;
	return s;
}

/* Every kernel counts the same total and the same work for each pixel, and
 * the same node visits; the per-pixel counts add up to the per-work-item
 * ones. */
static void check_same_work(const char *path, int accel)
{
	static const char *const kernels[] = {"serial",	 "naive",      "cyclic",
					      "dynamic", "persistent", "wavefront"};
	struct device dev;
	struct scene scene;
	struct render_result want;
	size_t pixels = 61 * 47;

	cr_assert_eq(device_open(&dev, -1, -1, err, sizeof(err)), 0, "%s", err);
	cr_assert_eq(scene_load_file(&scene, path, err, sizeof(err)), 0, "%s", err);
	struct render_settings s = counting("serial", 1, 1, scene.max_depth, accel);
	cr_assert_eq(render(&dev, &scene, &s, &want, err, sizeof(err)), 0, "%s", err);
	cr_assert_gt(want.total_flops, 0);
	cr_assert_gt(want.total_rays, pixels);
	if (accel == ACCEL_BVH)
		cr_assert_gt(want.total_node_visits, 0);
	else
		cr_assert_eq(want.total_node_visits, 0);
	cr_assert_eq(want.item_count, 1);
	cr_assert_eq(want.item_flops[0], want.total_flops);

	for (int k = 0; k < 6; k++) {
		for (int shape = 0; shape < 2; shape++) {
			struct render_result got;
			uint64_t pixel_sum = 0;
			s = counting(kernels[k], shape ? 16 : 8, shape ? 4 : 8, scene.max_depth,
				     accel);
			cr_assert_eq(render(&dev, &scene, &s, &got, err, sizeof(err)), 0, "%s",
				     err);
			cr_expect_eq(got.total_flops, want.total_flops,
				     "%s: %llu flops, serial %llu", kernels[k],
				     (unsigned long long)got.total_flops,
				     (unsigned long long)want.total_flops);
			cr_expect_eq(got.total_rays, want.total_rays, "%s rays", kernels[k]);
			cr_expect_eq(got.total_node_visits, want.total_node_visits,
				     "%s node visits", kernels[k]);
			cr_assert(got.guards_intact, "%s: wrote outside the image", kernels[k]);
			for (size_t i = 0; i < pixels; i++) {
				cr_assert_eq(got.pixel_flops[i], want.pixel_flops[i],
					     "%s: pixel %zu counts %llu, serial %llu", kernels[k],
					     i, (unsigned long long)got.pixel_flops[i],
					     (unsigned long long)want.pixel_flops[i]);
				pixel_sum += got.pixel_flops[i];
				cr_assert_eq(got.write_counts[i], 1,
					     "%s: pixel %zu written %u times", kernels[k], i,
					     got.write_counts[i]);
			}
			cr_expect_eq(pixel_sum, got.total_flops, "%s: pixels add up", kernels[k]);
			if (!s.kernel->multi_pass)
				cr_expect_eq(got.item_count,
					     got.global_size[0] * got.global_size[1]);
			render_result_free(&got);
		}
	}
	render_result_free(&want);
	scene_free(&scene);
	device_close(&dev);
}

Test(flops, kernels_count_the_same_work, .timeout = 300)
{
	check_same_work("scenes/two_balls.json", ACCEL_NONE);
}

Test(flops_slow, kernels_count_the_same_work_bvh, .timeout = 300)
{
	check_same_work("scenes/two_balls.json", ACCEL_BVH);
}

/* Spheres, triangles (glass through closed meshes) and planes. */
Test(flops_slow, kernels_count_the_same_work_on_meshes, .timeout = 600)
{
	check_same_work("test/meshes/mesh_scene.json", ACCEL_NONE);
}

Test(flops, kernels_count_the_same_work_on_meshes_bvh, .timeout = 600)
{
	check_same_work("test/meshes/mesh_scene.json", ACCEL_BVH);
}
