#include "render.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../cl/rtcl_shared.h"
#include "devscene.h"
#include "embedded.h"
#include "outfile.h"
#include "render_internal.h"

const struct kernel_info render_kernels[] = {
	{"serial", "one work-item renders every pixel in row-major order", 0, 1, 0},
	{"naive", "one work-item per pixel, a 2D NDRange over the image", 0, 0, 0},
	{"cyclic", "persistent work-groups, chunk (cx,cy) to group (cx mod GX, cy mod GY)", 1, 0,
	 0},
	{"dynamic", "persistent work-groups fetch chunks from a global atomic counter", 1, 0, 0},
	{"persistent",
	 "persistent work-groups whose work-items each fetch --batch pixels, no barrier", 1, 0, 0},
	{"wavefront", "one launch per bounce over a queue of live rays: paths split in pieces", 0,
	 0, 1},
};
const int render_kernel_count = sizeof(render_kernels) / sizeof(render_kernels[0]);

const struct kernel_info *render_find_kernel(const char *name)
{
	for (int i = 0; i < render_kernel_count; i++)
		if (strcmp(render_kernels[i].name, name) == 0)
			return &render_kernels[i];
	return NULL;
}

/* Everything one render holds on the device, released in reverse order. */
struct launch_state {
	cl_program program;
	cl_kernel kernel;
	cl_mem scene_buffer;
	struct guarded_image image;
	cl_mem chunk_counter;
	cl_mem item_counts;
	cl_mem write_counts;
};

static void release_state(struct launch_state *st)
{
	if (st->write_counts)
		clReleaseMemObject(st->write_counts);
	if (st->item_counts)
		clReleaseMemObject(st->item_counts);
	if (st->chunk_counter)
		clReleaseMemObject(st->chunk_counter);
	render_release_image(&st->image);
	if (st->scene_buffer)
		clReleaseMemObject(st->scene_buffer);
	if (st->kernel)
		clReleaseKernel(st->kernel);
	if (st->program)
		clReleaseProgram(st->program);
}

/* Returns the text of cl/NAME, from dir or from the copy embedded at build
 * time; a loaded file is malloc'd and must be freed when *loaded is set. */
static const char *load_source(const char *dir, const char *name, int *loaded, char *err,
			       size_t err_size)
{
	*loaded = 0;
	if (!dir) {
		const char *text = embedded_file(name);
		if (!text)
			snprintf(err, err_size, "internal error: cl/%s is not embedded", name);
		return text;
	}

	char path[4096];
	snprintf(path, sizeof(path), "%s/%s", dir, name);
	FILE *f = fopen(path, "rb");
	if (!f) {
		snprintf(err, err_size, "%s: cannot open kernel source: %s", path, strerror(errno));
		return NULL;
	}
	char *text = NULL;
	if (fseek(f, 0, SEEK_END) == 0) {
		long size = ftell(f);
		rewind(f);
		text = size >= 0 ? malloc((size_t)size + 1) : NULL;
		if (text && fread(text, 1, (size_t)size, f) == (size_t)size) {
			text[size] = '\0';
		} else {
			free(text);
			text = NULL;
		}
	}
	fclose(f);
	if (!text)
		snprintf(err, err_size, "%s: cannot read kernel source", path);
	*loaded = text != NULL;
	return text;
}

/* -v: the compiler's messages for a program that built, if it had any (with
 * RTCL_BUILD_OPTIONS=-cl-nv-verbose, NVIDIA's register and spill report). */
static void print_build_log(cl_program program, const struct device *dev)
{
	char log[32768] = "";

	clGetProgramBuildInfo(program, dev->id, CL_PROGRAM_BUILD_LOG, sizeof(log) - 1, log,
			      NULL);
	if (log[strspn(log, " \t\r\n")] != '\0')
		fprintf(stderr, "rtcl: build log:\n%s\n", log);
}

struct bytes {
	const unsigned char *data;
	size_t size;
};

static int write_bytes(FILE *file, const void *context)
{
	const struct bytes *b = context;

	return fwrite(b->data, 1, b->size, file) == b->size ? 0 : -1;
}

/* RTCL_DUMP_BINARY=FILE: writes the built program's binary (PTX on NVIDIA's
 * OpenCL) to FILE, for reading what the compiler made of the tracer. */
static int dump_binary(cl_program program, char *err, size_t err_size)
{
	const char *path = getenv("RTCL_DUMP_BINARY");
	size_t size = 0;

	if (!path || !*path)
		return 0;
	if (clGetProgramInfo(program, CL_PROGRAM_BINARY_SIZES, sizeof(size), &size, NULL) !=
		    CL_SUCCESS ||
	    size == 0) {
		snprintf(err, err_size, "RTCL_DUMP_BINARY: the device gives no program binary");
		return -1;
	}
	unsigned char *binary = malloc(size);
	if (!binary) {
		snprintf(err, err_size, "out of memory for a %zu-byte program binary", size);
		return -1;
	}
	struct bytes contents = {binary, size};
	int ret;
	if (clGetProgramInfo(program, CL_PROGRAM_BINARIES, sizeof(binary), &binary, NULL) !=
	    CL_SUCCESS) {
		snprintf(err, err_size, "RTCL_DUMP_BINARY: cannot read the program binary");
		ret = -1;
	} else {
		ret = outfile_write(path, write_bytes, &contents, err, err_size);
	}
	free(binary);
	return ret;
}

/* NVIDIA's compiler gives the tracer about 100 registers, which leaves 4-5
 * warps per scheduler; capped at 80 (60 bytes spilled) the same kernels run
 * 3-5 % faster on an H100 (docs/performance.md, step 9). RTCL_BUILD_OPTIONS can override
 * it: the last -cl-nv-maxrregcount given wins. */
#define NV_REGISTER_CAP "-cl-nv-maxrregcount=80"

/* RTCL_BUILD_OPTIONS may add this many characters: rtcl's own options take at
 * most about 150 of the 512 in render_result.build_options. */
#define BUILD_OPTIONS_EXTRA_MAX 256

int render_build_program(struct device *dev, const struct render_settings *s,
			 struct render_result *res, cl_program *program, char *err, size_t err_size)
{
	char kernel_file[64];
	const char *names[3] = {"rtcl_shared.h", "tracer.cl", kernel_file};
	const char *texts[3] = {NULL, NULL, NULL};
	int loaded[3] = {0, 0, 0};
	int ret = -1;
	cl_int status;

	snprintf(kernel_file, sizeof(kernel_file), "%s.cl", s->kernel->name);
	for (int i = 0; i < 3; i++) {
		texts[i] = load_source(s->source_dir, names[i], &loaded[i], err, err_size);
		if (!texts[i])
			goto out_free_sources;
	}
	const char *extra = getenv("RTCL_BUILD_OPTIONS");
	if (extra && strlen(extra) > BUILD_OPTIONS_EXTRA_MAX) {
		snprintf(err, err_size, "RTCL_BUILD_OPTIONS is too long (at most %d characters)",
			 BUILD_OPTIONS_EXTRA_MAX);
		goto out_free_sources;
	}
	snprintf(res->build_options, sizeof(res->build_options),
		 "-cl-std=CL1.2 -DRTCL_MAX_DEPTH=%d -DRTCL_BATCH=%d%s%s%s%s%s%s", s->max_depth,
		 s->batch > 0 ? s->batch : 1, res->scene_in_local ? " -DRTCL_SCENE_IN_LOCAL" : "",
		 s->count_flops ? " -DRTCL_COUNT_FLOPS" : "",
		 s->check_writes ? " -DRTCL_COUNT_WRITES" : "",
		 dev->nv_compiler_options ? " " NV_REGISTER_CAP : "", extra && *extra ? " " : "",
		 extra ? extra : "");

	*program = clCreateProgramWithSource(dev->context, 3, texts, NULL, &status);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clCreateProgramWithSource failed: %s",
			 cl_error_name(status));
		goto out_free_sources;
	}
	status = clBuildProgram(*program, 1, &dev->id, res->build_options, NULL, NULL);
	if (status != CL_SUCCESS) {
		char log[32768] = "";
		clGetProgramBuildInfo(*program, dev->id, CL_PROGRAM_BUILD_LOG, sizeof(log) - 1, log,
				      NULL);
		snprintf(err, err_size,
			 "building kernel '%s' for %s failed: %s\noptions: %s\nbuild log:\n%s",
			 s->kernel->name, dev->name, cl_error_name(status), res->build_options,
			 log);
		goto out_free_sources;
	}
	if (s->verbose)
		print_build_log(*program, dev);
	ret = dump_binary(*program, err, err_size);

out_free_sources:
	for (int i = 0; i < 3; i++)
		if (loaded[i])
			free((char *)texts[i]);
	return ret;
}

void render_default_groups(const struct device *dev, const struct render_settings *s, int groups[2])
{
	int items = s->workgroup[0] * s->workgroup[1];
	int chunks_x = (s->width + s->workgroup[0] - 1) / s->workgroup[0];
	int chunks_y = (s->height + s->workgroup[1] - 1) / s->workgroup[1];
	/* A GPU runs many work-groups per compute unit at once (up to 2048
	 * work-items on current NVIDIA parts); a CPU runs one per core. */
	long total = dev->is_gpu ? (long)dev->compute_units * (items >= 1024 ? 1 : 1024 / items)
				 : (long)dev->compute_units * 4;
	int gx = (int)ceil(sqrt((double)total));

	if (total < 1)
		total = 1;
	if (gx > chunks_x)
		gx = chunks_x;
	int gy = (int)((total + gx - 1) / gx);
	if (gy > chunks_y)
		gy = chunks_y;
	groups[0] = gx;
	groups[1] = gy;
}

/* Chooses the NDRange and checks it against the device. */
static int plan_geometry(const struct device *dev, const struct render_settings *s,
			 struct render_result *res, char *err, size_t err_size)
{
	const size_t *max_items = dev->max_work_item_sizes;
	size_t wx = (size_t)s->workgroup[0], wy = (size_t)s->workgroup[1];

	if (s->kernel->single_item) {
		res->local_size[0] = res->local_size[1] = 1;
		res->global_size[0] = res->global_size[1] = 1;
		res->groups[0] = res->groups[1] = 1;
		return 0;
	}
	if (wx > max_items[0] || wy > max_items[1] || wx * wy > dev->max_work_group_size) {
		snprintf(err, err_size,
			 "work-group %zux%zu (%zu work-items) is larger than %s allows: at most "
			 "%zu work-items, %zux%zu in x and y (choose a smaller -w)",
			 wx, wy, wx * wy, dev->name, dev->max_work_group_size, max_items[0],
			 max_items[1]);
		return -1;
	}
	res->local_size[0] = wx;
	res->local_size[1] = wy;
	if (s->kernel->uses_groups) {
		if (s->groups[0] > 0 && s->groups[1] > 0) {
			res->groups[0] = s->groups[0];
			res->groups[1] = s->groups[1];
		} else {
			render_default_groups(dev, s, res->groups);
		}
	} else {
		res->groups[0] = (int)((s->width + wx - 1) / wx);
		res->groups[1] = (int)((s->height + wy - 1) / wy);
	}
	res->global_size[0] = (size_t)res->groups[0] * wx;
	res->global_size[1] = (size_t)res->groups[1] * wy;
	return 0;
}

/* Checks that a buffer of `bytes` fits the device before asking for it. */
int render_check_fits(const struct device *dev, const char *what, double bytes, char *err,
		      size_t err_size)
{
	if (bytes > (double)dev->max_alloc_size) {
		snprintf(err, err_size,
			 "%s needs %.0f bytes of device memory, but %s allows at most %llu bytes "
			 "in one buffer (CL_DEVICE_MAX_MEM_ALLOC_SIZE): choose a smaller --size",
			 what, bytes, dev->name, (unsigned long long)dev->max_alloc_size);
		return -1;
	}
	return 0;
}

cl_mem render_create_buffer(struct device *dev, cl_mem_flags flags, size_t bytes, void *host,
			    const char *what, char *err, size_t err_size)
{
	cl_int status;
	cl_mem buffer = clCreateBuffer(dev->context, flags, bytes, host, &status);

	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clCreateBuffer for the %s (%zu bytes) failed: %s", what,
			 bytes, cl_error_name(status));
		return NULL;
	}
	return buffer;
}

static int create_buffers(struct device *dev, const struct render_settings *s,
			  struct launch_state *st, struct render_result *res, void *scene_block,
			  char *err, size_t err_size)
{
	size_t pixels = (size_t)s->width * s->height;
	size_t items = res->global_size[0] * res->global_size[1];
	cl_int status;

	st->scene_buffer =
		render_create_buffer(dev, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, res->scene_bytes,
				     scene_block, "scene", err, err_size);
	if (!st->scene_buffer)
		return -1;

	if (render_create_image(dev, s, &st->image, err, err_size))
		return -1;

	st->chunk_counter = render_create_buffer(dev, CL_MEM_READ_WRITE, sizeof(cl_uint), NULL,
						 "chunk counter", err, err_size);
	if (!st->chunk_counter)
		return -1;
	res->item_count = items;
	st->item_counts =
		render_create_buffer(dev, CL_MEM_READ_WRITE,
				     s->count_flops ? (items * 2 + pixels) * sizeof(cl_ulong) : 16,
				     NULL, "flop counts", err, err_size);
	if (!st->item_counts)
		return -1;
	st->write_counts = render_create_buffer(dev, CL_MEM_READ_WRITE,
						s->check_writes ? pixels * sizeof(cl_uint) : 16,
						NULL, "write counts", err, err_size);
	if (!st->write_counts)
		return -1;

	cl_mem args[6] = {st->scene_buffer, NULL,
			  st->image.image,  st->chunk_counter,
			  st->item_counts,  st->write_counts};
	for (cl_uint i = 0; i < 6; i++) {
		if (i == 1)
			status = clSetKernelArg(st->kernel, i,
						res->scene_in_local ? res->scene_bytes : 16, NULL);
		else
			status = clSetKernelArg(st->kernel, i, sizeof(cl_mem), &args[i]);
		if (status != CL_SUCCESS) {
			snprintf(err, err_size, "clSetKernelArg(%u) failed: %s", i,
				 cl_error_name(status));
			return -1;
		}
	}
	return 0;
}

static double now_seconds(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Waits for the launch, showing the elapsed time on stderr when asked. */
cl_int render_wait(cl_event event, const char *label, int progress)
{
	if (!progress)
		return clWaitForEvents(1, &event);

	double start = now_seconds();
	struct timespec tick = {0, 100 * 1000 * 1000};
	cl_int state = CL_QUEUED;
	for (;;) {
		cl_int status = clGetEventInfo(event, CL_EVENT_COMMAND_EXECUTION_STATUS,
					       sizeof(state), &state, NULL);
		if (status != CL_SUCCESS)
			return status;
		if (state == CL_COMPLETE || state < 0)
			break;
		fprintf(stderr, "\r%s: %.1f s", label, now_seconds() - start);
		nanosleep(&tick, NULL);
	}
	fprintf(stderr, "\r%*s\r", 60, "");
	return state < 0 ? state : clWaitForEvents(1, &event);
}

/* Enqueues what must precede every launch: the counter reset and, in tests,
 * the poison and the write counts. */
static cl_int prepare_launch(struct device *dev, const struct render_settings *s,
			     struct launch_state *st, size_t pixels)
{
	cl_uint zero = 0, poison = POISON_WORD;
	cl_int status = clEnqueueFillBuffer(dev->queue, st->chunk_counter, &zero, sizeof(zero), 0,
					    sizeof(zero), 0, NULL, NULL);

	if (status == CL_SUCCESS && s->check_writes)
		status = clEnqueueFillBuffer(dev->queue, st->write_counts, &zero, sizeof(zero), 0,
					     pixels * sizeof(cl_uint), 0, NULL, NULL);
	if (status == CL_SUCCESS && s->check_writes)
		status = clEnqueueFillBuffer(
			dev->queue, st->image.parent, &poison, sizeof(poison), 0,
			pixels * 3 * sizeof(float) + 2 * st->image.guard_bytes, 0, NULL, NULL);
	return status;
}

int render_compare_ms(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* Tests: RTCL_TEST_DEVICE_FAULT=1 makes the last launch fail as a device that
 * failed mid-render does (there is no way to make a real one fail on demand). */
static int device_fault_injected(void)
{
	const char *fault = getenv("RTCL_TEST_DEVICE_FAULT");
	return fault && strcmp(fault, "1") == 0;
}

int render_begin_timing(const struct render_settings *s, struct render_result *res, char *err,
			size_t err_size)
{
	/* Counting runs are not timed: one run is enough. */
	int timed = s->count_flops ? 1 : s->repeat;

	res->kernel_ms = calloc((size_t)timed, sizeof(double));
	if (!res->kernel_ms) {
		snprintf(err, err_size, "out of host memory");
		return -1;
	}
	res->repeat = timed;
	return s->count_flops ? 1 : timed + 1;
}

cl_int render_launch(struct device *dev, const struct render_settings *s, cl_kernel kernel,
		     cl_uint dims, const size_t *global, const size_t *local, const char *label,
		     double *ms, const char **call)
{
	cl_event event;
	cl_ulong start = 0, end = 0;
	cl_int status;

	*call = "clEnqueueNDRangeKernel";
	status = clEnqueueNDRangeKernel(dev->queue, kernel, dims, NULL, global, local, 0, NULL,
					&event);
	if (status != CL_SUCCESS)
		return status;
	*call = "clFlush";
	status = clFlush(dev->queue);
	if (status == CL_SUCCESS) {
		*call = "waiting for the kernel";
		status = render_wait(event, label, s->progress);
	}
	if (status == CL_SUCCESS) {
		*call = "clGetEventProfilingInfo";
		status = clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_START, sizeof(start),
						 &start, NULL);
	}
	if (status == CL_SUCCESS)
		status = clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_END, sizeof(end), &end,
						 NULL);
	*ms += (double)(end - start) * 1e-6;
	clReleaseEvent(event);
	return status;
}

static int launch_all(struct device *dev, const struct render_settings *s, struct launch_state *st,
		      struct render_result *res, char *err, size_t err_size)
{
	size_t pixels = (size_t)s->width * s->height;
	int launches = render_begin_timing(s, res, err, err_size);

	if (launches < 0)
		return -1;
	for (int i = 0; i < launches; i++) {
		char label[96];
		double ms = 0;
		const char *call = "clEnqueueFillBuffer";
		cl_int status = prepare_launch(dev, s, st, pixels);

		snprintf(label, sizeof(label), "rendering (%s, launch %d of %d)", s->kernel->name,
			 i + 1, launches);
		if (status == CL_SUCCESS)
			status = render_launch(dev, s, st->kernel, 2, res->global_size,
					       res->local_size, label, &ms, &call);
		if (status == CL_SUCCESS && i == launches - 1 && device_fault_injected()) {
			call = "waiting for the kernel";
			status = CL_OUT_OF_RESOURCES;
		}
		if (status != CL_SUCCESS) {
			snprintf(err, err_size, "%s failed (kernel '%s' on %s): %s", call,
				 s->kernel->name, dev->name, cl_error_name(status));
			return -1;
		}
		int slot = i - (launches - res->repeat);
		if (slot >= 0)
			res->kernel_ms[slot] = ms;
	}
	return render_summarize_times(res, err, err_size);
}

int render_summarize_times(struct render_result *res, char *err, size_t err_size)
{
	int n = res->repeat;
	double *sorted = malloc((size_t)n * sizeof(double));

	if (!sorted) {
		snprintf(err, err_size, "out of host memory");
		return -1;
	}
	memcpy(sorted, res->kernel_ms, (size_t)n * sizeof(double));
	qsort(sorted, (size_t)n, sizeof(double), render_compare_ms);
	res->kernel_ms_min = sorted[0];
	res->kernel_ms_max = sorted[n - 1];
	res->kernel_ms_median = n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
	free(sorted);
	return 0;
}

static int read_back(struct device *dev, const struct render_settings *s, struct launch_state *st,
		     struct render_result *res, char *err, size_t err_size)
{
	size_t pixels = (size_t)s->width * s->height;
	size_t image_bytes = pixels * 3 * sizeof(float);
	cl_int status = clEnqueueReadBuffer(dev->queue, st->image.image, CL_TRUE, 0, image_bytes,
					    res->rgb, 0, NULL, NULL);

	if (status == CL_SUCCESS && s->count_flops) {
		size_t item_bytes = res->item_count * 2 * sizeof(cl_ulong);
		cl_ulong *counts = malloc(item_bytes);
		res->item_flops = malloc(res->item_count * sizeof(uint64_t));
		res->pixel_flops = malloc(pixels * sizeof(uint64_t));
		if (!counts || !res->item_flops || !res->pixel_flops) {
			free(counts);
			snprintf(err, err_size, "out of host memory for the flop counts");
			return -1;
		}
		status = clEnqueueReadBuffer(dev->queue, st->item_counts, CL_TRUE, 0, item_bytes,
					     counts, 0, NULL, NULL);
		if (status == CL_SUCCESS)
			status = clEnqueueReadBuffer(dev->queue, st->item_counts, CL_TRUE,
						     item_bytes, pixels * sizeof(cl_ulong),
						     res->pixel_flops, 0, NULL, NULL);
		for (size_t i = 0; status == CL_SUCCESS && i < res->item_count; i++) {
			res->item_flops[i] = counts[2 * i];
			res->total_flops += counts[2 * i];
			res->total_rays += counts[2 * i + 1];
		}
		free(counts);
	}
	if (status == CL_SUCCESS)
		status = render_read_write_checks(dev, s, &st->image, st->write_counts, res);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clEnqueueReadBuffer failed: %s", cl_error_name(status));
		return -1;
	}
	return 0;
}

/* Checks the kernel's own work-group limit, known only once it is built. */
static int check_kernel_limits(struct device *dev, struct launch_state *st,
			       const struct render_result *res, const char *name, char *err,
			       size_t err_size)
{
	size_t max_items = 0;
	cl_int status = clGetKernelWorkGroupInfo(st->kernel, dev->id, CL_KERNEL_WORK_GROUP_SIZE,
						 sizeof(max_items), &max_items, NULL);

	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clGetKernelWorkGroupInfo failed: %s",
			 cl_error_name(status));
		return -1;
	}
	size_t items = res->local_size[0] * res->local_size[1];
	if (items > max_items) {
		snprintf(err, err_size,
			 "work-group %zux%zu (%zu work-items) is larger than kernel '%s' allows on "
			 "%s: at most %zu work-items (choose a smaller -w)",
			 res->local_size[0], res->local_size[1], items, name, dev->name, max_items);
		return -1;
	}
	return 0;
}

int render_create_image(struct device *dev, const struct render_settings *s,
			struct guarded_image *g, char *err, size_t err_size)
{
	size_t image_bytes = (size_t)s->width * s->height * 3 * sizeof(float);
	cl_int status;

	g->guard_bytes = 0;
	if (s->check_writes)
		g->guard_bytes = dev->mem_base_addr_align > 4096 ? dev->mem_base_addr_align : 4096;
	g->parent = render_create_buffer(dev, CL_MEM_READ_WRITE, image_bytes + 2 * g->guard_bytes,
					 NULL, "image", err, err_size);
	if (!g->parent)
		return -1;
	cl_buffer_region region = {g->guard_bytes, image_bytes};
	g->image = clCreateSubBuffer(g->parent, CL_MEM_READ_WRITE, CL_BUFFER_CREATE_TYPE_REGION,
				     &region, &status);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clCreateSubBuffer for the image failed: %s",
			 cl_error_name(status));
		return -1;
	}
	return 0;
}

void render_release_image(struct guarded_image *g)
{
	if (g->image)
		clReleaseMemObject(g->image);
	if (g->parent)
		clReleaseMemObject(g->parent);
	g->image = g->parent = NULL;
}

cl_int render_read_write_checks(struct device *dev, const struct render_settings *s,
				const struct guarded_image *g, cl_mem write_counts,
				struct render_result *res)
{
	size_t pixels = (size_t)s->width * s->height;
	cl_uint *guard = malloc(g->guard_bytes);
	cl_int status;

	if (!s->check_writes) {
		free(guard);
		return CL_SUCCESS;
	}
	res->write_counts = malloc(pixels * sizeof(uint32_t));
	if (!guard || !res->write_counts) {
		free(guard);
		return CL_OUT_OF_HOST_MEMORY;
	}
	status = clEnqueueReadBuffer(dev->queue, write_counts, CL_TRUE, 0, pixels * sizeof(cl_uint),
				     res->write_counts, 0, NULL, NULL);
	res->guards_intact = 1;
	for (int side = 0; status == CL_SUCCESS && side < 2; side++) {
		size_t offset = side ? g->guard_bytes + pixels * 3 * sizeof(float) : 0;
		status = clEnqueueReadBuffer(dev->queue, g->parent, CL_TRUE, offset, g->guard_bytes,
					     guard, 0, NULL, NULL);
		for (size_t i = 0; status == CL_SUCCESS && i < g->guard_bytes / sizeof(cl_uint);
		     i++)
			res->guards_intact &= guard[i] == POISON_WORD;
	}
	free(guard);
	return status;
}

int render_prepare_scene(struct device *dev, const struct scene *scene,
			 const struct render_settings *s, struct render_result *res, void **block,
			 char *err, size_t err_size)
{
	size_t pixels = (size_t)s->width * s->height;

	*block = devscene_pack(scene, s->width, s->height, s->max_depth, &res->scene_bytes);
	res->rgb = malloc(pixels * 3 * sizeof(float));
	if (!*block || !res->rgb) {
		snprintf(err, err_size, "out of host memory for a %dx%d image", s->width,
			 s->height);
		return -1;
	}
	if (render_check_fits(dev, "the scene", (double)res->scene_bytes, err, err_size))
		return -1;
	res->scene_in_local = !s->force_global_scene &&
			      res->scene_bytes + LOCAL_MEM_RESERVE <= dev->local_mem_size;
	if (s->verbose)
		fprintf(stderr, "rtcl: scene is %zu bytes; %s\n", res->scene_bytes,
			res->scene_in_local
				? "copied into __local memory by each work-group"
				: "read from __global memory (it does not fit in __local memory)");
	return 0;
}

cl_kernel render_create_kernel(cl_program program, const char *name, char *err, size_t err_size)
{
	cl_int status;
	cl_kernel kernel = clCreateKernel(program, name, &status);

	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clCreateKernel(\"%s\") failed: %s", name,
			 cl_error_name(status));
		return NULL;
	}
	return kernel;
}

int render(struct device *dev, const struct scene *scene, const struct render_settings *s,
	   struct render_result *res, char *err, size_t err_size)
{
	if (s->kernel->multi_pass)
		return render_wavefront(dev, scene, s, res, err, err_size);

	struct launch_state st;
	size_t pixels = (size_t)s->width * s->height;
	void *scene_block = NULL;
	int ret = -1;

	memset(res, 0, sizeof(*res));
	memset(&st, 0, sizeof(st));
	if (plan_geometry(dev, s, res, err, err_size))
		return -1;
	if (render_check_fits(dev, "the image", (double)pixels * 3 * sizeof(float), err, err_size))
		return -1;
	if (s->count_flops &&
	    render_check_fits(dev, "the flop count buffer",
			      ((double)res->global_size[0] * res->global_size[1] * 2 + pixels) * 8,
			      err, err_size))
		return -1;

	if (render_prepare_scene(dev, scene, s, res, &scene_block, err, err_size))
		goto out;
	if (render_build_program(dev, s, res, &st.program, err, err_size))
		goto out;
	st.kernel = render_create_kernel(st.program, "render", err, err_size);
	if (!st.kernel)
		goto out;
	if (!s->kernel->single_item &&
	    check_kernel_limits(dev, &st, res, s->kernel->name, err, err_size))
		goto out;
	if (create_buffers(dev, s, &st, res, scene_block, err, err_size))
		goto out;
	if (launch_all(dev, s, &st, res, err, err_size))
		goto out;
	if (read_back(dev, s, &st, res, err, err_size))
		goto out;
	ret = 0;

out:
	release_state(&st);
	free(scene_block);
	if (ret)
		render_result_free(res);
	return ret;
}

void render_result_free(struct render_result *res)
{
	free(res->rgb);
	free(res->kernel_ms);
	free(res->item_flops);
	free(res->pixel_flops);
	free(res->write_counts);
	res->pixel_flops = NULL;
	res->rgb = NULL;
	res->kernel_ms = NULL;
	res->item_flops = NULL;
	res->write_counts = NULL;
}
