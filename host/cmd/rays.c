/* rtcl-rays: rtcl's traversal over rays read from a file, timed: the
 * instrument that sets rtcl beside a peer's traversal on the very same rays
 * (tools/rtcl_tools/commands/peer_compare.py, --rays; docs/bvh.md,
 * "Incoherent rays against TinyBVH"). It loads a scene as rtcl does, builds
 * its BVH and program as a render on the device would (block.c, program.c:
 * the same tree, leaves and build options), and launches cl/rays.cl's
 * trace_rays, one work-item per ray, once untimed and then -r times, timed by
 * OpenCL profiling events.
 *
 * usage: rtcl-rays SCENE RAYS HITS [-p PLATFORM] [-d DEVICE] [-r N] [-w N] [-c]
 *
 * -c/--counts: instead of timing, one launch of the counting build
 * (RTCL_COUNT_FLOPS, the binary tree on every device, as rtcl --flops): prints
 * the node visits, leaf visits and primitive tests per ray; HITS is not written.
 *
 * RAYS (little-endian): the 8 bytes "RTCLRAY1", uint32 count, uint32 flags
 * (bit 0: any hit, shadow rays), then count rays of 8 floats: origin x y z,
 * t_max, direction x y z, 0. HITS: count pairs (float t, int32 triangle),
 * t = 0 and triangle -1 for no hit; with any hit, some hit before t_max, not
 * the nearest. The origins are taken relative to the scene's eye, as the
 * device block's positions are (scene_from_eye): SCENE's camera is where
 * rtcl's float arithmetic is centred. Prints one line: the device, the rays, the median and least
 * kernel time in ms, the hits. */
#include <getopt.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/files.h"
#include "base/timing.h"
#include "device/device.h"
#include "render/block.h"
#include "render/launch.h"
#include "render/program.h"
#include "scene/scene.h"

#define RAYS_MAGIC "RTCLRAY1"
#define RAYS_HEADER 16
#define RAY_BYTES 32
#define RAYS_ANY_HIT 1u
#define RAYS_MAX (1u << 26) /* 64 M rays: 2 GiB of them */
#define REPEAT_MAX 1000

struct rays_options {
	const char *scene, *rays, *hits;
	int platform, device, repeat, group, counts;
};

static int usage(const char *message)
{
	fprintf(stderr,
		"rtcl-rays: %s\nusage: rtcl-rays SCENE RAYS HITS [-p PLATFORM] [-d DEVICE] "
		"[-r N] [-w N] [-c]\n(docs/bvh.md, \"Incoherent rays against TinyBVH\")\n",
		message);
	return 2;
}

static int parse_int(const char *text, int low, int high, int *out)
{
	char *end;
	long v = strtol(text, &end, 10);

	if (!*text || *end || v < low || v > high)
		return -1;
	*out = (int)v;
	return 0;
}

static int parse_options(int argc, char **argv, struct rays_options *o)
{
	static const struct option longs[] = {
		{"help", no_argument, 0, 'h'}, {"counts", no_argument, 0, 'c'}, {0, 0, 0, 0}};
	char message[160];
	int c;

	*o = (struct rays_options){.platform = -1, .device = -1, .repeat = 10, .group = 64};
	while ((c = getopt_long(argc, argv, "p:d:r:w:hc", longs, NULL)) != -1) {
		if (c == 'c') {
			o->counts = 1;
			continue;
		}
		int *to = c == 'p' ? &o->platform : c == 'd' ? &o->device : c == 'r' ? &o->repeat
										 : &o->group;
		int low = c == 'r' || c == 'w' ? 1 : 0, high = c == 'r' ? REPEAT_MAX : 1024;
		if (c == 'h') {
			usage("traces the rays of RAYS through SCENE with rtcl's traversal");
			exit(0);
		}
		if (c == '?')
			return usage("unknown option");
		if (parse_int(optarg, low, high, to)) {
			snprintf(message, sizeof(message), "-%c %s: give a whole number from %d to %d",
				 c, optarg, low, high);
			return usage(message);
		}
	}
	if (argc - optind != 3)
		return usage("give SCENE, RAYS and HITS");
	o->scene = argv[optind];
	o->rays = argv[optind + 1];
	o->hits = argv[optind + 2];
	return 0;
}

/* Reads RAYS into *rays (count * 8 floats); returns 0 or -1 with err. */
static int read_rays(const char *path, float **rays, uint32_t *count, uint32_t *flags, char *err,
		     size_t err_size)
{
	char *data;
	size_t bytes;

	if (files_read(path, "ray file", RAYS_HEADER + (size_t)RAYS_MAX * RAY_BYTES, &data, &bytes,
		       err, err_size))
		return -1;
	if (bytes < RAYS_HEADER || memcmp(data, RAYS_MAGIC, 8) != 0) {
		snprintf(err, err_size, "%s: not a ray file (it starts with \"%s\")", path,
			 RAYS_MAGIC);
		free(data);
		return -1;
	}
	memcpy(count, data + 8, 4);
	memcpy(flags, data + 12, 4);
	if (*count == 0 || *count > RAYS_MAX || bytes != RAYS_HEADER + (size_t)*count * RAY_BYTES) {
		snprintf(err, err_size, "%s: %zu bytes for %u rays; a ray file of N rays has %d + %d N",
			 path, bytes, *count, RAYS_HEADER, RAY_BYTES);
		free(data);
		return -1;
	}
	*rays = malloc((size_t)*count * RAY_BYTES);
	if (!*rays) {
		snprintf(err, err_size, "out of host memory for %u rays", *count);
		free(data);
		return -1;
	}
	memcpy(*rays, data + RAYS_HEADER, (size_t)*count * RAY_BYTES);
	free(data);
	return 0;
}

static int write_hits(FILE *file, const void *hits)
{
	const struct {
		const float *data;
		size_t count;
	} *h = hits;

	return fwrite(h->data, 8, h->count, file) == h->count ? 0 : -1;
}

static int compare_ms(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;

	return (x > y) - (x < y);
}

/* What one run holds on the device, released by release(). */
struct trace {
	cl_mem scene, rays, hits, counts;
	cl_program program;
	cl_kernel kernel;
};

static void release(struct trace *t)
{
	if (t->kernel)
		clReleaseKernel(t->kernel);
	if (t->program)
		clReleaseProgram(t->program);
	if (t->hits)
		clReleaseMemObject(t->hits);
	if (t->counts)
		clReleaseMemObject(t->counts);
	if (t->rays)
		clReleaseMemObject(t->rays);
	if (t->scene)
		clReleaseMemObject(t->scene);
}

/* Launches trace_rays once untimed and repeat times timed; ms[repeat]. */
static int launch(struct device *dev, struct trace *t, size_t global, size_t local, int repeat,
		  double *ms, char *err, size_t err_size)
{
	for (int i = -1; i < repeat; i++) {
		cl_event event;
		cl_ulong start = 0, end = 0;
		cl_int status = clEnqueueNDRangeKernel(dev->queue, t->kernel, 1, NULL, &global,
						       &local, 0, NULL, &event);
		if (status == CL_SUCCESS)
			status = clWaitForEvents(1, &event);
		if (status == CL_SUCCESS) {
			clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_START, sizeof(start),
						&start, NULL);
			clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_END, sizeof(end), &end,
						NULL);
			clReleaseEvent(event);
		}
		if (status != CL_SUCCESS) {
			snprintf(err, err_size, "trace_rays failed on %s: %s", dev->name,
				 cl_error_name(status));
			return -1;
		}
		if (i >= 0)
			ms[i] = (double)(end - start) * 1e-6;
	}
	return 0;
}

/* -c: the counting launch's node visits, leaf visits and primitive tests
 * per ray, summed over the work-items. */
static int print_counts(struct device *dev, struct trace *t, uint32_t count, int any_hit,
			char *err, size_t err_size)
{
	size_t words = (size_t)count * RT_ITEM_COUNTS;
	cl_ulong *c = malloc(words * sizeof(*c));
	double nodes = 0, leaves = 0, tests = 0, rays = 0;

	if (!c) {
		snprintf(err, err_size, "out of host memory for the counts of %u rays", count);
		return -1;
	}
	cl_int status = clEnqueueReadBuffer(dev->queue, t->counts, CL_TRUE, 0,
					    words * sizeof(*c), c, 0, NULL, NULL);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "reading the counts back failed: %s", cl_error_name(status));
		free(c);
		return -1;
	}
	for (uint32_t i = 0; i < count; i++) {
		const cl_ulong *item = c + (size_t)i * RT_ITEM_COUNTS;
		rays += (double)item[RT_ITEM_RAYS];
		nodes += (double)item[RT_ITEM_NODE_VISITS];
		leaves += (double)item[RT_ITEM_LEAF_VISITS];
		tests += (double)item[RT_ITEM_PRIM_TESTS];
	}
	free(c);
	printf("rtcl-rays: %s; %u %s rays counted (%.0f); per ray: node visits %.3f, leaf visits "
	       "%.3f, primitive tests %.3f\n",
	       dev->name, count, any_hit ? "any-hit" : "closest-hit", rays, nodes / count,
	       leaves / count, tests / count);
	return 0;
}

static int trace(const struct rays_options *o, char *err, size_t err_size)
{
	static const struct kernel_info kernel = {.name = "rays"};
	struct render_settings s = {.kernel = &kernel, .accel = ACCEL_BVH, .repeat = o->repeat,
				    .count_flops = o->counts};
	struct render_result res = {0};
	struct scene scene = {0};
	struct device dev = {0};
	struct trace t = {0};
	float *rays = NULL, *hits = NULL;
	double *ms = NULL;
	void *block = NULL;
	uint32_t count, flags;
	int any_hit, ret = -1;

	if (files_check_writable(o->hits, err, err_size) ||
	    read_rays(o->rays, &rays, &count, &flags, err, err_size))
		return -1;
	any_hit = (flags & RAYS_ANY_HIT) != 0;
	if (scene_load_file(&scene, o->scene, err, err_size))
		goto out;
	/* The device block holds every position relative to the eye
	 * (scene_from_eye): so do the origins, in double, rounded once to
	 * float, as the renderer's are. */
	for (uint32_t i = 0; i < count; i++) {
		double at[3] = {rays[8 * i], rays[8 * i + 1], rays[8 * i + 2]}, moved[3];
		scene_from_eye(&scene, at, moved);
		for (int k = 0; k < 3; k++)
			rays[8 * i + k] = (float)moved[k];
	}
	if (device_open(&dev, o->platform, o->device, err, err_size))
		goto out_scene;
	s.width = scene.width;
	s.height = scene.height;
	s.max_depth = scene.max_depth;
	s.workgroup[0] = o->group;
	s.workgroup[1] = 1;
	if (block_prepare_scene(&dev, &scene, &s, &res, &block, err, err_size))
		goto out_device;
	struct program_features features = {
		.scene_in_local = res.scene_in_local,
		.use_bvh = res.bvh_nodes > 0,
		.has_triangles = scene.triangle_count > 0,
		.leaf_triangles_only = res.bvh_nodes > 0 && scene.sphere_count == 0,
		.no_lights = scene.light_count == 0,
		.bvh4 = res.bvh_width == 4,
	};
	int cached;
	double lap = timing_now();
	if (program_build(&dev, &s, &features, &t.program, res.build_options, &cached, err,
			  err_size))
		goto out_block;
	double build_ms = timing_lap_ms(&lap);
	size_t local = (size_t)o->group;
	size_t global = (count + local - 1) / local * local;
	hits = malloc((size_t)count * 8);
	ms = malloc(sizeof(*ms) * (size_t)o->repeat);
	if (!hits || !ms) {
		snprintf(err, err_size, "out of host memory for %u hits", count);
		goto out_release;
	}
	t.kernel = program_create_kernel(t.program, "trace_rays", err, err_size);
	if (!t.kernel)
		goto out_release;
	t.scene = device_create_buffer(&dev, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
				       res.scene_bytes, block, "the scene", err, err_size);
	if (!t.scene)
		goto out_release;
	t.rays = device_create_buffer(&dev, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
				      (size_t)count * RAY_BYTES, rays, "the rays", err, err_size);
	if (!t.rays)
		goto out_release;
	t.hits = device_create_buffer(&dev, CL_MEM_WRITE_ONLY, (size_t)count * 8, NULL, "the hits",
				      err, err_size);
	if (!t.hits)
		goto out_release;
	size_t count_bytes = o->counts ? global * RT_ITEM_COUNTS * sizeof(cl_ulong) : 8;
	t.counts = device_create_buffer(&dev, CL_MEM_READ_WRITE, count_bytes, NULL, "the counts",
					err, err_size);
	if (!t.counts)
		goto out_release;
	cl_uint n = count;
	cl_int flag = any_hit;
	cl_int status = clSetKernelArg(t.kernel, 0, sizeof(cl_mem), &t.scene);
	status |= clSetKernelArg(t.kernel, 1, res.scene_in_local ? res.scene_bytes
								 : UNUSED_BUFFER_BYTES,
				 NULL);
	status |= clSetKernelArg(t.kernel, 2, sizeof(cl_mem), &t.rays);
	status |= clSetKernelArg(t.kernel, 3, sizeof(cl_mem), &t.hits);
	status |= clSetKernelArg(t.kernel, 4, sizeof(n), &n);
	status |= clSetKernelArg(t.kernel, 5, sizeof(flag), &flag);
	status |= clSetKernelArg(t.kernel, 6, sizeof(cl_mem), &t.counts);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clSetKernelArg failed for trace_rays");
		goto out_release;
	}
	if (launch(&dev, &t, global, local, o->counts ? 0 : o->repeat, ms, err, err_size))
		goto out_release;
	if (o->counts) {
		ret = print_counts(&dev, &t, count, any_hit, err, err_size);
		goto out_release;
	}
	status = clEnqueueReadBuffer(dev.queue, t.hits, CL_TRUE, 0, (size_t)count * 8, hits, 0,
				     NULL, NULL);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "reading the hits back failed: %s", cl_error_name(status));
		goto out_release;
	}
	struct {
		const float *data;
		size_t count;
	} out = {hits, count};
	if (files_write(o->hits, write_hits, &out, err, err_size))
		goto out_release;
	uint32_t hit_count = 0;
	for (uint32_t i = 0; i < count; i++)
		hit_count += hits[2 * i] > 0.0f;
	qsort(ms, (size_t)o->repeat, sizeof(*ms), compare_ms);
	printf("rtcl-rays: %s; %u %s rays, median %.4f ms, min %.4f ms of %d -> %.1f M rays/s; "
	       "hits %u; bvh width %d, %d nodes, built in %.1f ms; program %s in %.0f ms; "
	       "scene in %s memory\n",
	       dev.name, count, any_hit ? "any-hit" : "closest-hit", ms[o->repeat / 2], ms[0],
	       o->repeat, count / (ms[o->repeat / 2] * 1e-3) * 1e-6, hit_count, res.bvh_width,
	       res.bvh_device_nodes, res.bvh_build_ms, cached ? "from the cache" : "built",
	       build_ms, res.scene_in_local ? "__local" : "__global");
	ret = 0;
out_release:
	release(&t);
out_block:
	free(block);
	free(res.rgb);
out_device:
	device_close(&dev);
out_scene:
	scene_free(&scene);
out:
	free(ms);
	free(hits);
	free(rays);
	return ret;
}

int main(int argc, char **argv)
{
	struct rays_options o;
	char err[40000];

	if (parse_options(argc, argv, &o))
		return 2;
	if (trace(&o, err, sizeof(err))) {
		fprintf(stderr, "rtcl-rays: %s\n", err);
		return 1;
	}
	return 0;
}
