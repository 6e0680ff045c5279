/* Do kernels on two in-order queues of one device run at the same time?
 * (issue 28: hiding the idle end of one launch behind the next needs it;
 * docs/results/multidevice/README.md, "Why the idle end does not split").
 *
 * Launches a busy kernel LAUNCHES times on each of two queues, alternating,
 * and then the same number on one queue; prints both wall times and how
 * often a kernel of one queue started before the other queue's previous one
 * ended (OpenCL profiling events). On a device that overlaps them, two
 * queues take less wall time than one.
 *
 *   cc -O2 -o queue_overlap tools/device/queue_overlap.c -lOpenCL
 *   ./queue_overlap [PLATFORM [DEVICE [GROUPS [ITERATIONS]]]]
 */
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define LAUNCHES 20

static const char *source =
	"__kernel void busy(__global float *out, int iterations)\n"
	"{\n"
	"	float x = get_global_id(0) * 1e-6f;\n"
	"	for (int i = 0; i < iterations; i++)\n"
	"		x = x * 0.999f + 0.001f;\n"
	"	out[get_global_id(0)] = x;\n"
	"}\n";

static void check(cl_int status, const char *what)
{
	if (status != CL_SUCCESS) {
		fprintf(stderr, "queue_overlap: %s failed (%d)\n", what, status);
		exit(1);
	}
}

static double now(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + t.tv_nsec * 1e-9;
}

static cl_ulong event_time(cl_event e, cl_profiling_info what)
{
	cl_ulong t = 0;

	check(clGetEventProfilingInfo(e, what, sizeof(t), &t, NULL), "clGetEventProfilingInfo");
	return t;
}

/* Enqueues LAUNCHES kernels on each queue of q[0..queues), alternating;
 * returns the wall time in ms and counts the overlaps in *overlaps. */
static double run(cl_command_queue *q, int queues, cl_kernel k, size_t global, size_t local,
		  int *overlaps)
{
	cl_event events[2 * LAUNCHES];
	int n = 0;
	double start = now();

	for (int i = 0; i < LAUNCHES * 2; i++)
		check(clEnqueueNDRangeKernel(q[i % queues], k, 1, NULL, &global, &local, 0, NULL,
					     &events[n++]),
		      "clEnqueueNDRangeKernel");
	for (int i = 0; i < queues; i++)
		check(clFinish(q[i]), "clFinish");
	double wall = (now() - start) * 1e3;
	*overlaps = 0;
	for (int i = 1; i < n; i++)
		if (event_time(events[i], CL_PROFILING_COMMAND_START) <
		    event_time(events[i - 1], CL_PROFILING_COMMAND_END))
			++*overlaps;
	for (int i = 0; i < n; i++)
		clReleaseEvent(events[i]);
	return wall;
}

int main(int argc, char **argv)
{
	cl_uint platform_index = argc > 1 ? (cl_uint)atoi(argv[1]) : 0;
	cl_uint device_index = argc > 2 ? (cl_uint)atoi(argv[2]) : 0;
	size_t groups = argc > 3 ? (size_t)atol(argv[3]) : 132, local = 256;
	int iterations = argc > 4 ? atoi(argv[4]) : 200000;
	cl_platform_id platforms[16];
	cl_device_id devices[16];
	cl_uint count;
	cl_int status;
	char name[256];

	check(clGetPlatformIDs(16, platforms, &count), "clGetPlatformIDs");
	if (platform_index >= count)
		return fprintf(stderr, "queue_overlap: no platform %u\n", platform_index), 1;
	check(clGetDeviceIDs(platforms[platform_index], CL_DEVICE_TYPE_ALL, 16, devices, &count),
	      "clGetDeviceIDs");
	if (device_index >= count)
		return fprintf(stderr, "queue_overlap: no device %u\n", device_index), 1;
	cl_device_id dev = devices[device_index];
	clGetDeviceInfo(dev, CL_DEVICE_NAME, sizeof(name), name, NULL);
	cl_context ctx = clCreateContext(NULL, 1, &dev, NULL, NULL, &status);
	check(status, "clCreateContext");
	cl_program prog = clCreateProgramWithSource(ctx, 1, &source, NULL, &status);
	check(status, "clCreateProgramWithSource");
	check(clBuildProgram(prog, 1, &dev, "", NULL, NULL), "clBuildProgram");
	cl_kernel k = clCreateKernel(prog, "busy", &status);
	check(status, "clCreateKernel");
	size_t global = groups * local;
	cl_mem out = clCreateBuffer(ctx, CL_MEM_WRITE_ONLY, global * sizeof(float), NULL, &status);
	check(status, "clCreateBuffer");
	check(clSetKernelArg(k, 0, sizeof(out), &out), "clSetKernelArg");
	check(clSetKernelArg(k, 1, sizeof(iterations), &iterations), "clSetKernelArg");
	cl_command_queue q[2];
	for (int i = 0; i < 2; i++) {
		q[i] = clCreateCommandQueue(ctx, dev, CL_QUEUE_PROFILING_ENABLE, &status);
		check(status, "clCreateCommandQueue");
	}
	int overlaps;
	run(q, 1, k, global, local, &overlaps); /* warm-up */
	double one = run(q, 1, k, global, local, &overlaps);
	printf("%s: %d launches of %zu groups of %zu, %d iterations\n", name, 2 * LAUNCHES,
	       groups, local, iterations);
	printf("one queue:  %.1f ms wall, %d overlaps\n", one, overlaps);
	double two = run(q, 2, k, global, local, &overlaps);
	printf("two queues: %.1f ms wall, %d of %d launches started before the previous "
	       "ended: %s\n",
	       two, overlaps, 2 * LAUNCHES - 1,
	       overlaps > 0 && two < 0.9 * one ? "the queues overlap" : "no overlap");
	return 0;
}
