/* The path integrator's BSDFs (cl/bsdf.cl, docs/RENDERING.md "The BSDFs"),
 * run on the device by small test kernels: each BSDF samples directions with
 * the density it reports (a chi-square test of the histogram of sampled
 * directions against the integral of bsdf_eval's pdf over each bin, as pbrt
 * and Mitsuba test theirs); a sample's weight is f |cos| / pdf as bsdf_eval
 * gives them; the albedo (the mean weight) is at most 1; and the MIS weights
 * of two strategies sum to one (cl/light.cl). */
#include <criterion/criterion.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "device/device.h"
#include "base/embedded.h"

static char err[65536];

/* params[0]: type, alpha, eta, mirror; params[1]: colour; params[2]: wo. */
static const char test_kernels[] =
	"static struct bsdf test_bsdf(__global const float4 *params)\n"
	"{\n"
	"	struct bsdf b;\n"
	"	b.type = (int)params[0].x;\n"
	"	b.alpha = params[0].y;\n"
	"	b.eta = params[0].z;\n"
	"	b.mirror = params[0].w;\n"
	"	b.color = params[1].xyz;\n"
	"	b.tint = (float3)(1.0f);\n"
	"	b.metallic = params[1].w;\n"
	"	b.transmission = params[2].w;\n"
	"	return b;\n"
	"}\n"
	"__kernel void sample(__global const float4 *params, __global const float4 *u,\n"
	"		     __global float4 *wi_pdf, __global float4 *weight_flags)\n"
	"{\n"
	"	struct tracer tr;\n"
	"	struct bsdf b = test_bsdf(params);\n"
	"	struct bsdf_sample s;\n"
	"	size_t i = get_global_id(0);\n"
	"	float4 r = u[i];\n"
	"	bool ok = bsdf_sample(&tr, &b, params[2].xyz, r.xy, r.z, &s);\n"
	"	wi_pdf[i] = (float4)(s.wi, s.pdf);\n"
	"	weight_flags[i] = (float4)(s.weight, ok ? (s.delta ? 2.0f : 1.0f) : 0.0f);\n"
	"}\n"
	"__kernel void eval(__global const float4 *params, __global const float4 *wi,\n"
	"		   __global float4 *f_pdf)\n"
	"{\n"
	"	struct tracer tr;\n"
	"	struct bsdf b = test_bsdf(params);\n"
	"	float pdf;\n"
	"	size_t i = get_global_id(0);\n"
	"	float3 f = bsdf_eval(&tr, &b, params[2].xyz, wi[i].xyz, &pdf);\n"
	"	f_pdf[i] = (float4)(f, pdf);\n"
	"}\n"
	"__kernel void mis(__global const float2 *p, __global float *sum)\n"
	"{\n"
	"	struct tracer tr;\n"
	"	float2 q = p[get_global_id(0)];\n"
	"	sum[get_global_id(0)] = mis_weight(&tr, q.x, q.y) + mis_weight(&tr, q.y, q.x);\n"
	"}\n";

struct fixture {
	struct device dev;
	cl_program program;
};

static struct fixture fx;

static void setup(void)
{
	const char *sources[] = {embedded_file("rtcl_shared.h"), embedded_file("tracer.cl"),
				 embedded_file("sample.cl"),	 embedded_file("bsdf.cl"),
				 embedded_file("light.cl"),	 test_kernels};
	cl_int status;

	cr_assert_eq(device_open(&fx.dev, -1, -1, err, sizeof(err)), 0, "%s", err);
	fx.program = clCreateProgramWithSource(fx.dev.context, 6, sources, NULL, &status);
	cr_assert_eq(status, CL_SUCCESS);
	status = clBuildProgram(fx.program, 1, &fx.dev.id,
				"-cl-std=CL1.2 -DRTCL_MAX_DEPTH=1 -DRTCL_PATH", NULL, NULL);
	if (status != CL_SUCCESS) {
		clGetProgramBuildInfo(fx.program, fx.dev.id, CL_PROGRAM_BUILD_LOG, sizeof(err), err,
				      NULL);
		cr_assert_fail("build failed: %s", err);
	}
}

static void teardown(void)
{
	clReleaseProgram(fx.program);
	device_close(&fx.dev);
}

/* Runs kernel name over n items: buffers in[] (read) and out[] (written),
 * each of the given bytes; params first when given. */
static void run(const char *name, const void *params, size_t n, const void *in, size_t in_bytes,
		void **out, const size_t *out_bytes, int outs)
{
	cl_int status;
	cl_kernel kernel = clCreateKernel(fx.program, name, &status);
	cl_mem bufs[4];
	int arg = 0;

	cr_assert_eq(status, CL_SUCCESS, "%s", name);
	if (params) {
		bufs[arg] = clCreateBuffer(fx.dev.context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
					   3 * 4 * sizeof(cl_float), (void *)params, &status);
		clSetKernelArg(kernel, (cl_uint)arg, sizeof(cl_mem), &bufs[arg]);
		arg++;
	}
	bufs[arg] = clCreateBuffer(fx.dev.context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
				   in_bytes, (void *)in, &status);
	clSetKernelArg(kernel, (cl_uint)arg, sizeof(cl_mem), &bufs[arg]);
	arg++;
	for (int o = 0; o < outs; o++, arg++) {
		bufs[arg] = clCreateBuffer(fx.dev.context, CL_MEM_WRITE_ONLY, out_bytes[o], NULL,
					   &status);
		clSetKernelArg(kernel, (cl_uint)arg, sizeof(cl_mem), &bufs[arg]);
	}
	cr_assert_eq(clEnqueueNDRangeKernel(fx.dev.queue, kernel, 1, NULL, &n, NULL, 0, NULL,
					    NULL),
		     CL_SUCCESS);
	for (int o = 0; o < outs; o++)
		clEnqueueReadBuffer(fx.dev.queue, bufs[arg - outs + o], CL_TRUE, 0, out_bytes[o],
				    out[o], 0, NULL, NULL);
	for (int b = 0; b < arg; b++)
		clReleaseMemObject(bufs[b]);
	clReleaseKernel(kernel);
}

/* A reproducible uniform number in [0, 1) (splitmix64). */
static double uniform(uint64_t *state)
{
	uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
	z ^= z >> 31;
	return (double)(z >> 40) * 0x1p-24;
}

#define SAMPLES 200000
#define THETA_BINS 24
#define PHI_BINS 48
#define SUB 5 /* the pdf's integral over a bin: SUB x SUB midpoints */

enum { TYPE_MAPPED, TYPE_DIFFUSE, TYPE_CONDUCTOR, TYPE_DIELECTRIC, TYPE_PRINCIPLED };

struct bsdf_case {
	const char *name;
	float type, alpha, eta, mirror;
	float color[3];
	float theta_o; /* degrees */
	float metallic, transmission;
};

static int bin_of(const float wi[3])
{
	double z = fmax(-1.0, fmin(1.0, wi[2]));
	double theta = acos(z), phi = atan2(wi[1], wi[0]);
	if (phi < 0)
		phi += 2 * M_PI;
	int t = (int)(theta / M_PI * THETA_BINS), p = (int)(phi / (2 * M_PI) * PHI_BINS);
	return (t < THETA_BINS ? t : THETA_BINS - 1) * PHI_BINS + (p < PHI_BINS ? p : PHI_BINS - 1);
}

/* The chi-square quantile of probability 1 - 1e-4 for k degrees of freedom
 * (Wilson and Hilferty's approximation; z for 1e-4 is 3.719). */
static double chi2_threshold(int k)
{
	double a = 2.0 / (9.0 * k), c = 1 - a + 3.719 * sqrt(a);
	return k * c * c * c;
}

static void check_case(const struct bsdf_case *c)
{
	static cl_float u[SAMPLES][4], wi_pdf[SAMPLES][4], weight[SAMPLES][4];
	static cl_float grid[THETA_BINS * PHI_BINS * SUB * SUB][4];
	static cl_float f_pdf[THETA_BINS * PHI_BINS * SUB * SUB][4];
	static double observed[THETA_BINS * PHI_BINS], expected[THETA_BINS * PHI_BINS];
	double to = c->theta_o * M_PI / 180;
	cl_float params[3][4] = {{c->type, c->alpha, c->eta, c->mirror},
				 {c->color[0], c->color[1], c->color[2], c->metallic},
				 {(float)sin(to), 0, (float)cos(to), c->transmission}};
	uint64_t state = 12345;
	size_t grid_n = THETA_BINS * PHI_BINS * SUB * SUB;

	for (int i = 0; i < SAMPLES; i++)
		for (int k = 0; k < 4; k++)
			u[i][k] = (float)uniform(&state);
	void *outs[2] = {wi_pdf, weight};
	size_t sizes[2] = {sizeof(wi_pdf), sizeof(weight)};
	run("sample", params, SAMPLES, u, sizeof(u), outs, sizes, 2);

	/* The pdf at each bin's SUB x SUB midpoints. */
	for (int t = 0, g = 0; t < THETA_BINS; t++)
		for (int p = 0; p < PHI_BINS; p++)
			for (int a = 0; a < SUB; a++)
				for (int b = 0; b < SUB; b++, g++) {
					double theta = (t + (a + 0.5) / SUB) * M_PI / THETA_BINS;
					double phi = (p + (b + 0.5) / SUB) * 2 * M_PI / PHI_BINS;
					grid[g][0] = (float)(sin(theta) * cos(phi));
					grid[g][1] = (float)(sin(theta) * sin(phi));
					grid[g][2] = (float)cos(theta);
					grid[g][3] = 0;
				}
	void *eval_out[1] = {f_pdf};
	size_t eval_size[1] = {sizeof(f_pdf)};
	run("eval", params, grid_n, grid, sizeof(grid), eval_out, eval_size, 1);

	memset(observed, 0, sizeof(observed));
	memset(expected, 0, sizeof(expected));
	for (int t = 0, g = 0; t < THETA_BINS; t++)
		for (int p = 0; p < PHI_BINS; p++)
			for (int a = 0; a < SUB; a++)
				for (int b = 0; b < SUB; b++, g++) {
					double theta = (t + (a + 0.5) / SUB) * M_PI / THETA_BINS;
					double area = sin(theta) * (M_PI / THETA_BINS / SUB) *
						      (2 * M_PI / PHI_BINS / SUB);
					expected[t * PHI_BINS + p] += f_pdf[g][3] * area * SAMPLES;
				}

	double albedo[3] = {0, 0, 0};
	for (int i = 0; i < SAMPLES; i++) {
		if (weight[i][3] == 0)
			continue;
		/* A transmitted sample's weight carries the radiance's 1/eta^2
		 * (RENDERING.md): the energy it carries does not. */
		double energy = wi_pdf[i][2] < 0 ? (double)c->eta * c->eta : 1.0;
		for (int k = 0; k < 3; k++)
			albedo[k] += weight[i][k] * energy / SAMPLES;
		if (weight[i][3] == 2) /* a delta lobe: no density */
			continue;
		observed[bin_of(wi_pdf[i])] += 1;
	}
	for (int k = 0; k < 3; k++)
		cr_expect(albedo[k] <= 1.0 + 5.0 / sqrt(SAMPLES), "%s: albedo %g in channel %d",
			  c->name, albedo[k], k);

	/* Pool the bins expected to hold fewer than 5 samples into one. */
	double chi2 = 0, pooled_o = 0, pooled_e = 0;
	int dof = 0;
	for (int b = 0; b < THETA_BINS * PHI_BINS; b++) {
		if (expected[b] < 5) {
			pooled_o += observed[b];
			pooled_e += expected[b];
			continue;
		}
		chi2 += (observed[b] - expected[b]) * (observed[b] - expected[b]) / expected[b];
		dof++;
	}
	if (pooled_e >= 5) {
		chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
		dof++;
	}
	cr_assert_gt(dof, 10, "%s: only %d bins", c->name, dof);
	cr_expect(chi2 < chi2_threshold(dof - 1), "%s: chi-square %g over %d bins (limit %g)",
		  c->name, chi2, dof, chi2_threshold(dof - 1));

	/* At the sampled directions, bsdf_eval's pdf is the sample's and the
	 * weight is f |cos| / pdf. */
	static cl_float at[2000][4], at_out[2000][4];
	int n = 0, index[2000];
	for (int i = 0; i < SAMPLES && n < 2000; i++)
		if (weight[i][3] == 1) {
			memcpy(at[n], wi_pdf[i], sizeof(at[n]));
			index[n++] = i;
		}
	void *at_outs[1] = {at_out};
	size_t at_size[1] = {sizeof(at_out)};
	run("eval", params, (size_t)n, at, sizeof(at), at_outs, at_size, 1);
	for (int j = 0; j < n; j++) {
		int i = index[j];
		double pdf = wi_pdf[i][3], eval_pdf = at_out[j][3];
		cr_assert(fabs(pdf - eval_pdf) <= 2e-3 * fmax(pdf, eval_pdf) + 1e-6,
			  "%s: sample %d: pdf %g, bsdf_eval's %g", c->name, i, pdf, eval_pdf);
		for (int k = 0; k < 3; k++) {
			double w = at_out[j][k] * fabs(wi_pdf[i][2]) / eval_pdf;
			cr_assert(fabs(w - weight[i][k]) <= 2e-3 * fmax(w, weight[i][k]) + 1e-6,
				  "%s: sample %d: weight %g, f |cos| / pdf %g", c->name, i,
				  weight[i][k], w);
		}
	}
}

TestSuite(bsdf, .init = setup, .fini = teardown, .timeout = 300);

Test(bsdf, diffuse)
{
	check_case(&(struct bsdf_case){"diffuse", TYPE_DIFFUSE, 0, 1.5f, 0, {0.9f, 0.5f, 0.1f}, 30, 0, 0});
}

Test(bsdf, mapped_with_a_mirror)
{
	check_case(&(struct bsdf_case){"mapped", TYPE_MAPPED, 0, 1.5f, 0.3f, {0.7f, 0.7f, 0.7f},
				       50, 0, 0});
}

Test(bsdf, rough_conductor)
{
	check_case(&(struct bsdf_case){"conductor a=0.25", TYPE_CONDUCTOR, 0.25f, 1.5f, 0,
				       {1, 0.8f, 0.4f}, 40, 0, 0});
	check_case(&(struct bsdf_case){"conductor a=0.6", TYPE_CONDUCTOR, 0.6f, 1.5f, 0,
				       {1, 1, 1}, 70, 0, 0});
}

Test(bsdf, rough_dielectric)
{
	check_case(&(struct bsdf_case){"dielectric entering", TYPE_DIELECTRIC, 0.3f, 1.5f, 0,
				       {1, 1, 1}, 35, 0, 0});
	check_case(&(struct bsdf_case){"dielectric leaving", TYPE_DIELECTRIC, 0.4f, 1 / 1.5f, 0,
				       {1, 1, 1}, 20, 0, 0});
}

Test(bsdf, principled)
{
	check_case(&(struct bsdf_case){"principled plastic", TYPE_PRINCIPLED, 0.3f, 1.5f, 0,
				       {0.8f, 0.3f, 0.2f}, 30, 0, 0});
	check_case(&(struct bsdf_case){"principled half metal", TYPE_PRINCIPLED, 0.2f, 1.5f, 0,
				       {0.9f, 0.7f, 0.3f}, 60, 0.5f, 0});
	check_case(&(struct bsdf_case){"principled glass", TYPE_PRINCIPLED, 0.35f, 1.5f, 0,
				       {0.9f, 0.9f, 0.9f}, 25, 0.2f, 0.8f});
}

Test(bsdf, mis_weights_sum_to_one)
{
	static cl_float p[4096][2];
	static cl_float sum[4096];
	uint64_t state = 7;

	for (int i = 0; i < 4096; i++) {
		p[i][0] = (float)exp(40 * uniform(&state) - 20);
		p[i][1] = (float)exp(40 * uniform(&state) - 20);
	}
	void *outs[1] = {sum};
	size_t sizes[1] = {sizeof(sum)};
	run("mis", NULL, 4096, p, sizeof(p), outs, sizes, 1);
	for (int i = 0; i < 4096; i++)
		cr_assert(fabsf(sum[i] - 1.0f) <= 1e-6f, "pdfs %g and %g: weights sum to %.9g",
			  p[i][0], p[i][1], sum[i]);
}
