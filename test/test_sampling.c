/* The sample positions of docs/RENDERING.md ("Samples per pixel"): their
 * properties, checked on the CPU reference's independent implementation, and
 * the kernels' cl/sample.cl giving exactly the same bits and counting the
 * flops the rules say. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "device/device.h"
#include "base/embedded.h"
#include "render/program.h"
#include "render/reference.h"

static char err[65536];

Test(sampling, one_sample_is_the_centre)
{
	for (int y = 0; y < 50; y += 7)
		for (int x = 0; x < 50; x += 3) {
			double uv[2];
			reference_sample_position(x, y, 0, 1, uv);
			cr_assert(uv[0] == 0.5 && uv[1] == 0.5, "pixel (%d, %d): (%g, %g)", x, y,
				  uv[0], uv[1]);
		}
}

Test(sampling, positions_lie_in_the_pixel)
{
	static const int counts[] = {2, 3, 4, 7, 16, 100, 1024};

	for (size_t c = 0; c < sizeof(counts) / sizeof(counts[0]); c++)
		for (int p = 0; p < 40; p++)
			for (int k = 0; k < counts[c]; k++) {
				double uv[2];
				reference_sample_position(p * 37, p * 11 + 5, k, counts[c], uv);
				cr_assert(uv[0] >= 0 && uv[0] < 1 && uv[1] >= 0 && uv[1] < 1,
					  "sample %d of %d: (%g, %g)", k, counts[c], uv[0], uv[1]);
			}
}

/* For N = 2^m samples, every elementary interval of area 1/N (2^a columns by
 * 2^(m-a) rows, for every a) holds exactly one sample: the (0,m,2)-net
 * property that the Sobol' points keep under the per-pixel XOR scramble (an
 * XOR of the leading m bits permutes the intervals). Independent random
 * points, or the first two dimensions of a (t,2)-sequence with t > 0, leave
 * some interval empty. */
Test(sampling, powers_of_two_are_stratified_in_every_pixel)
{
	for (int m = 1; m <= 10; m++) {
		int n = 1 << m;
		int *hits = malloc(sizeof(int) * (size_t)n);
		cr_assert_not_null(hits);
		for (int p = 0; p < 25; p++) {
			int x = p * 101 % 640, y = p * 53 % 480;
			for (int a = 0; a <= m; a++) {
				int columns = 1 << a, rows = n / columns;
				memset(hits, 0, sizeof(int) * (size_t)n);
				for (int k = 0; k < n; k++) {
					double uv[2];
					reference_sample_position(x, y, k, n, uv);
					hits[(int)(uv[1] * rows) * columns +
					     (int)(uv[0] * columns)]++;
				}
				for (int cell = 0; cell < n; cell++)
					cr_assert_eq(hits[cell], 1,
						     "N = %d, pixel (%d, %d), %dx%d cells: cell %d "
						     "holds %d samples",
						     n, x, y, columns, rows, cell, hits[cell]);
			}
		}
		free(hits);
	}
}

/* The scramble is per pixel: neighbouring pixels place their samples
 * differently (so that no pattern repeats across the image), and the same
 * pixel always the same way. */
Test(sampling, scramble_differs_between_pixels_and_is_deterministic)
{
	int same = 0;

	for (int y = 0; y < 20; y++)
		for (int x = 0; x < 20; x++) {
			double a[2], b[2], again[2];
			reference_sample_position(x, y, 3, 16, a);
			reference_sample_position(x + 1, y, 3, 16, b);
			reference_sample_position(x, y, 3, 16, again);
			cr_assert(a[0] == again[0] && a[1] == again[1]);
			same += a[0] == b[0] && a[1] == b[1];
		}
	cr_assert_eq(same, 0, "%d of 400 pixels place sample 3 as their right neighbour", same);
}

/* Exact in binary: 24-bit fixed point. */
Test(sampling, positions_are_24_bit_fixed_point)
{
	for (int k = 0; k < 64; k++) {
		double uv[2];
		reference_sample_position(17, 23, k, 64, uv);
		for (int c = 0; c < 2; c++)
			cr_assert(ldexp(uv[c], 24) == floor(ldexp(uv[c], 24)), "%.17g", uv[c]);
	}
}

/* cl/sample.cl, run on the device: sample_offset for (x, y, k, n) given as
 * int4s, and the flops it counted. */
static const char device_test[] =
	"__kernel void offsets(__global const int4 *in, __global float2 *out,"
	"                      __global ulong *flops)\n"
	"{\n"
	"	struct tracer tr;\n"
	"	int4 q = in[get_global_id(0)];\n"
	"	tr.flops = 0;\n"
	"	out[get_global_id(0)] = sample_offset(&tr, q.x, q.y, q.z, q.w);\n"
	"	flops[get_global_id(0)] = tr.flops;\n"
	"}\n";

#define DEVICE_CASES 4096

Test(sampling, kernels_place_samples_as_the_reference, .timeout = 120)
{
	const char *sources[4] = {embedded_file("rtcl_shared.h"), embedded_file("tracer.cl"),
				  embedded_file("sample.cl"), device_test};
	struct device dev;
	cl_int status;
	static cl_int in[DEVICE_CASES][4];
	static cl_float out[DEVICE_CASES][2];
	static cl_ulong flops[DEVICE_CASES];
	static const int counts[] = {1, 2, 5, 16, 64, 1000, 65536};

	for (int i = 0; i < DEVICE_CASES; i++) {
		int n = counts[i % 7];
		in[i][0] = i * 7919 % 32768;
		in[i][1] = i * 104729 % 32768;
		in[i][2] = (i * 31) % n;
		in[i][3] = n;
	}
	cr_assert_eq(device_open(&dev, -1, -1, err, sizeof(err)), 0, "%s", err);
	cl_program program = clCreateProgramWithSource(dev.context, 4, sources, NULL, &status);
	cr_assert_eq(status, CL_SUCCESS);
	status = clBuildProgram(program, 1, &dev.id,
				"-cl-std=CL1.2 -DRTCL_MAX_DEPTH=1 -DRTCL_COUNT_FLOPS", NULL, NULL);
	if (status != CL_SUCCESS) {
		clGetProgramBuildInfo(program, dev.id, CL_PROGRAM_BUILD_LOG, sizeof(err), err,
				      NULL);
		cr_assert_fail("build failed: %s", err);
	}
	cl_kernel kernel = clCreateKernel(program, "offsets", &status);
	cr_assert_eq(status, CL_SUCCESS);
	cl_mem bufs[3] = {
		clCreateBuffer(dev.context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(in), in,
			       &status),
		clCreateBuffer(dev.context, CL_MEM_WRITE_ONLY, sizeof(out), NULL, &status),
		clCreateBuffer(dev.context, CL_MEM_WRITE_ONLY, sizeof(flops), NULL, &status)};
	for (cl_uint a = 0; a < 3; a++)
		clSetKernelArg(kernel, a, sizeof(cl_mem), &bufs[a]);
	size_t global = DEVICE_CASES;
	cr_assert_eq(
		clEnqueueNDRangeKernel(dev.queue, kernel, 1, NULL, &global, NULL, 0, NULL, NULL),
		CL_SUCCESS);
	clEnqueueReadBuffer(dev.queue, bufs[1], CL_TRUE, 0, sizeof(out), out, 0, NULL, NULL);
	clEnqueueReadBuffer(dev.queue, bufs[2], CL_TRUE, 0, sizeof(flops), flops, 0, NULL, NULL);
	for (int i = 0; i < DEVICE_CASES; i++) {
		double uv[2];
		reference_sample_position(in[i][0], in[i][1], in[i][2], in[i][3], uv);
		cr_assert(out[i][0] == uv[0] && out[i][1] == uv[1],
			  "pixel (%d, %d) sample %d of %d: device (%.9g, %.9g), reference "
			  "(%.9g, %.9g)",
			  in[i][0], in[i][1], in[i][2], in[i][3], out[i][0], out[i][1], uv[0],
			  uv[1]);
		/* Two scalings by 2^-24; the centre of one sample is a constant. */
		cr_assert_eq(flops[i], in[i][3] == 1 ? 0u : 2u, "n = %d: %llu flops", in[i][3],
			     (unsigned long long)flops[i]);
	}
	for (int a = 0; a < 3; a++)
		clReleaseMemObject(bufs[a]);
	clReleaseKernel(kernel);
	clReleaseProgram(program);
	device_close(&dev);
}

/* A sample's colour channel in fixed point (RENDERING.md, "Samples per
 * pixel"): cl/sample.cl's conversion against round(c * 2^24) in double
 * (exact for |c| < 2^22), ties to even, saturation at 2^22, inf and NaN, and
 * -2^22 for anything below it. */
static const char fixed_test[] = "__kernel void fixed(__global const float *in, __global long *out)\n"
				 "{\n"
				 "	out[get_global_id(0)] = sample_fixed(in[get_global_id(0)]);\n"
				 "}\n";

static long long fixed_reference(float c)
{
	if (!(c < 0x1p22f))
		return RT_SUM_SATURATED;
	if (c < -0x1p22f)
		c = -0x1p22f;
	return llrint((double)c * 0x1p24); /* the default mode: to nearest, ties to even */
}

#define FIXED_CASES 8192

Test(sampling, colours_go_to_fixed_point_as_the_rule_says, .timeout = 120)
{
	const char *sources[4] = {embedded_file("rtcl_shared.h"), embedded_file("tracer.cl"),
				  embedded_file("sample.cl"), fixed_test};
	static const char *const options[] = {"-cl-std=CL1.2 -DRTCL_MAX_DEPTH=1"};
	static cl_float in[FIXED_CASES];
	static cl_long out[FIXED_CASES];
	static const float special[] = {0.0f, -0.0f, 1.0f, -1.0f, 0x1p-25f, 0x1.8p-25f,
					0x1p-24f, 0x1.8p-24f, 0x1.4p-23f, 0x1.8p-23f, 0x1p-126f,
					0x1p-149f, 0x1p22f, -0x1p22f, 0x1.fffffep21f,
					-0x1.fffffep21f, 1e30f, -1e30f, INFINITY, -INFINITY, NAN};
	struct device dev;
	cl_int status;
	unsigned seed = 12345;

	for (int i = 0; i < FIXED_CASES; i++) {
		if (i < (int)(sizeof(special) / sizeof(special[0]))) {
			in[i] = special[i];
			continue;
		}
		seed = seed * 1103515245u + 12345u;
		if (i % 3 == 0) { /* a tie: k + 1/2 steps of 2^-24, k of either parity */
			in[i] = ((float)(seed >> 12 & 0xfffff) + 0.5f) * 0x1p-24f * (i % 2 ? 1 : -1);
			continue;
		}
		/* Any bit pattern with an exponent from 2^-40 to 2^23 (past the limit). */
		unsigned bits = (seed & 0x807fffffu) | ((unsigned)(87 + (seed >> 8) % 64) << 23);
		memcpy(&in[i], &bits, sizeof(float));
	}
	cr_assert_eq(device_open(&dev, -1, -1, err, sizeof(err)), 0, "%s", err);
	for (size_t o = 0; o < sizeof(options) / sizeof(options[0]); o++) {
		cl_program program = clCreateProgramWithSource(dev.context, 4, sources, NULL, &status);
		cr_assert_eq(status, CL_SUCCESS);
		status = clBuildProgram(program, 1, &dev.id, options[o], NULL, NULL);
		if (status != CL_SUCCESS) {
			clGetProgramBuildInfo(program, dev.id, CL_PROGRAM_BUILD_LOG, sizeof(err),
					      err, NULL);
			cr_assert_fail("build failed: %s", err);
		}
		cl_kernel kernel = clCreateKernel(program, "fixed", &status);
		cr_assert_eq(status, CL_SUCCESS);
		cl_mem bufs[2] = {clCreateBuffer(dev.context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
						 sizeof(in), in, &status),
				  clCreateBuffer(dev.context, CL_MEM_WRITE_ONLY, sizeof(out), NULL,
						 &status)};
		for (cl_uint a = 0; a < 2; a++)
			clSetKernelArg(kernel, a, sizeof(cl_mem), &bufs[a]);
		size_t global = FIXED_CASES;
		cr_assert_eq(clEnqueueNDRangeKernel(dev.queue, kernel, 1, NULL, &global, NULL, 0,
						    NULL, NULL),
			     CL_SUCCESS);
		clEnqueueReadBuffer(dev.queue, bufs[1], CL_TRUE, 0, sizeof(out), out, 0, NULL,
				    NULL);
		for (int i = 0; i < FIXED_CASES; i++)
			cr_assert_eq(out[i], fixed_reference(in[i]),
				     "%s: %a (%.9g) became %lld, want %lld", options[o], in[i],
				     in[i], (long long)out[i], fixed_reference(in[i]));
		for (int a = 0; a < 2; a++)
			clReleaseMemObject(bufs[a]);
		clReleaseKernel(kernel);
		clReleaseProgram(program);
	}
	device_close(&dev);
}
