#include "render/buffers.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rtcl_shared.h"
#include "layout/scene_block.h"
#include "render/launch.h"

/* Bytes of the per-pixel flops at the head of the flop-count buffer. */
static size_t pixel_flops_bytes(const struct render_settings *s)
{
	return (size_t)s->width * s->height * sizeof(cl_ulong);
}

static int buffers_place(struct device *dev, struct render_buffers *b, char *err,
			 size_t err_size);

/* The environment map's texels and column CDFs, a few rows at a time
 * (scene_block_env_rows), then zeros to 16 bytes: the host holds no second
 * copy of them either. */
static cl_int write_environment(struct device *dev, cl_mem buffer, const struct rt_path *path,
				const struct scene_environment *env)
{
	static const unsigned char zeros[16];
	/* About 1 MiB at a time: 20 bytes a texel. */
	size_t w = (size_t)env->width, rows = (1u << 20) / (w * 20) + 1;
	size_t end = path->env_column_cdf_offset + w * env->height * sizeof(float);
	unsigned char *texels = malloc(rows * w * sizeof(rt_vec4));
	float *columns = malloc(rows * w * sizeof(float));
	cl_int status = texels && columns ? CL_SUCCESS : CL_OUT_OF_HOST_MEMORY;

	for (int k = 0; status == CL_SUCCESS && k < env->height; k += (int)rows) {
		int k1 = k + (int)rows < env->height ? k + (int)rows : env->height;
		size_t n = (size_t)(k1 - k) * w;
		scene_block_env_rows(env, k, k1, texels, columns);
		status = clEnqueueWriteBuffer(dev->queue, buffer, CL_TRUE,
					      path->env_texel_offset + k * w * sizeof(rt_vec4),
					      n * sizeof(rt_vec4), texels, 0, NULL, NULL);
		if (status == CL_SUCCESS)
			status = clEnqueueWriteBuffer(dev->queue, buffer, CL_TRUE,
						      path->env_column_cdf_offset +
							      k * w * sizeof(float),
						      n * sizeof(float), columns, 0, NULL, NULL);
	}
	if (status == CL_SUCCESS && end % 16)
		status = clEnqueueWriteBuffer(dev->queue, buffer, CL_TRUE, end, 16 - end % 16,
					      zeros, 0, NULL, NULL);
	free(texels);
	free(columns);
	return status;
}

/* The scene buffer: the packed block, then the environment map's arrays
 * and each texture's texels written from the scene's own
 * (scene_block_pack_head), so that the host holds no second copy of them: a
 * 256 MiB texture took rtcl 869 MB with the texels packed into the block,
 * the scene's, the block's and the device buffer's (issue 39, finding 14).
 * The block is freed once written. */
static int create_scene_buffer(struct device *dev, const struct scene *scene,
			       const struct render_result *res, struct render_buffers *b, char *err,
			       size_t err_size)
{
	static const unsigned char zeros[16];
	const struct rt_scene *header = b->scene_block;
	const struct rt_texture *textures =
		(const struct rt_texture *)((const unsigned char *)b->scene_block +
					    header->texture_offset);
	const struct rt_path *path =
		(const struct rt_path *)((const unsigned char *)b->scene_block + header->path_offset);
	cl_int status;

	b->scene = device_create_buffer(dev, CL_MEM_READ_ONLY, res->scene_bytes, NULL, "scene", err,
					err_size);
	if (!b->scene)
		return -1;
	status = clEnqueueWriteBuffer(dev->queue, b->scene, CL_TRUE, 0,
				      scene_block_head_bytes(b->scene_block), b->scene_block, 0,
				      NULL, NULL);
	if (status == CL_SUCCESS && header->path_offset && path->environment == RT_ENVIRONMENT_MAP)
		status = write_environment(dev, b->scene, path, &scene->environment);
	for (int i = 0; status == CL_SUCCESS && i < header->texture_count; i++) {
		const struct scene_texture *t = &scene->textures[i];
		size_t pad = (16 - t->bytes % 16) % 16;
		if (t->bytes)
			status = clEnqueueWriteBuffer(dev->queue, b->scene, CL_TRUE,
						      textures[i].offset, t->bytes, t->texels, 0,
						      NULL, NULL);
		if (status == CL_SUCCESS && pad)
			status = clEnqueueWriteBuffer(dev->queue, b->scene, CL_TRUE,
						      textures[i].offset + t->bytes, pad, zeros, 0,
						      NULL, NULL);
	}
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "writing the scene's %zu bytes to %s failed: %s",
			 res->scene_bytes, dev->name, cl_error_name(status));
		return -1;
	}
	free(b->scene_block);
	b->scene_block = NULL;
	return 0;
}

int buffers_create(struct device *dev, const struct scene *scene, const struct render_settings *s,
		   const struct render_result *res, struct render_buffers *b, size_t flops_bytes,
		   const char *flops_what, char *err, size_t err_size)
{
	if (create_scene_buffer(dev, scene, res, b, err, err_size) ||
	    checks_create_image(dev, s, &b->image, err, err_size))
		return -1;
	b->sums = device_create_buffer(dev, CL_MEM_READ_WRITE,
				       settings_samples(s) > 1 ? image_sum_bytes(s->width, s->height)
							       : UNUSED_BUFFER_BYTES,
				       NULL, "sample sums", err, err_size);
	if (!b->sums)
		return -1;
	b->flops = device_create_buffer(dev, CL_MEM_READ_WRITE,
					s->count_flops ? flops_bytes : UNUSED_BUFFER_BYTES, NULL,
					flops_what, err, err_size);
	if (!b->flops)
		return -1;
	b->probe = probe_create(dev, s, err, err_size);
	return b->probe ? buffers_place(dev, b, err, err_size) : -1;
}

/* Every buffer on the device now, in the renderer's set-up: an OpenCL
 * implementation may allocate and fill a buffer at its first use, which
 * would fall in the first frame of a render without -r (on two H200s under
 * --mpi a device's busy time held 39-64 ms beyond its kernels, gone with
 * this and the set-up before the clock together, batch 85:
 * docs/results/multidevice/README.md). */
static int buffers_place(struct device *dev, struct render_buffers *b, char *err,
			 size_t err_size)
{
	cl_mem all[] = {b->scene, b->image.parent ? b->image.parent : b->image.image, b->sums,
			b->flops, b->probe};
	cl_int status = clEnqueueMigrateMemObjects(dev->queue, sizeof(all) / sizeof(all[0]), all,
						   0, 0, NULL, NULL);

	if (status == CL_SUCCESS)
		status = clFinish(dev->queue);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "placing the scene and image buffers on %s failed: %s",
			 dev->name, cl_error_name(status));
		return -1;
	}
	return 0;
}

int buffers_clear(struct device *dev, const struct render_settings *s, struct render_buffers *b,
		  char *err, size_t err_size)
{
	cl_ulong zero = 0;
	cl_int status = checks_poison(dev, s, &b->image);

	if (status == CL_SUCCESS)
		status = probe_clear(dev, s, b->probe);

	if (status == CL_SUCCESS && s->count_flops)
		status = clEnqueueFillBuffer(dev->queue, b->flops, &zero, sizeof(zero), 0,
					     pixel_flops_bytes(s), 0, NULL, NULL);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "clEnqueueFillBuffer failed: %s", cl_error_name(status));
		return -1;
	}
	return 0;
}

cl_int buffers_add_item_counts(struct device *dev, struct render_buffers *b, cl_mem from,
			       size_t offset, size_t items, uint64_t *flops)
{
	cl_ulong *counts = malloc(items * RT_ITEM_COUNTS * sizeof(cl_ulong));
	cl_int status;

	if (!counts)
		return CL_OUT_OF_HOST_MEMORY;
	status = clEnqueueReadBuffer(dev->queue, from, CL_TRUE, offset,
				     items * RT_ITEM_COUNTS * sizeof(cl_ulong), counts, 0, NULL,
				     NULL);
	for (size_t i = 0; status == CL_SUCCESS && i < items; i++) {
		const cl_ulong *c = counts + RT_ITEM_COUNTS * i;
		flops[i] += c[RT_ITEM_FLOPS];
		b->counts.rays += c[RT_ITEM_RAYS];
		b->counts.node_visits += c[RT_ITEM_NODE_VISITS];
		b->counts.leaf_visits += c[RT_ITEM_LEAF_VISITS];
		b->counts.prim_tests += c[RT_ITEM_PRIM_TESTS];
		for (int p = 0; p < RT_SIMD_PHASES; p++) {
			b->counts.lane_steps[p] += c[RT_ITEM_LANE_STEPS(p)];
			b->counts.warp_steps[p] += c[RT_ITEM_WARP_STEPS(p)];
		}
		path_counts_add_item(&b->counts.paths, c);
	}
	free(counts);
	return status;
}

/* Reads the per-pixel flops and hands over the per-work-item sums. */
static cl_int read_counts(struct device *dev, const struct render_settings *s,
			  struct render_buffers *b, struct render_result *res)
{
	res->pixel_flops = malloc(pixel_flops_bytes(s));
	if (!res->pixel_flops)
		return CL_OUT_OF_HOST_MEMORY;
	res->item_flops = b->item_flops;
	res->item_count = b->item_count;
	b->item_flops = NULL;
	res->total_flops = 0;
	for (size_t i = 0; i < res->item_count; i++)
		res->total_flops += res->item_flops[i];
	res->total_rays = b->counts.rays;
	res->total_node_visits = b->counts.node_visits;
	res->total_leaf_visits = b->counts.leaf_visits;
	res->total_prim_tests = b->counts.prim_tests;
	res->simd_measured = dev->simd_measurable; /* the counting build measured */
	for (int p = 0; p < RT_SIMD_PHASES; p++) {
		res->lane_steps[p] = b->counts.lane_steps[p];
		res->warp_steps[p] = b->counts.warp_steps[p];
	}
	res->paths = b->counts.paths;
	return clEnqueueReadBuffer(dev->queue, b->flops, CL_TRUE, 0, pixel_flops_bytes(s),
				   res->pixel_flops, 0, NULL, NULL);
}

int buffers_read_back(struct device *dev, const struct render_settings *s, struct render_buffers *b,
		      struct render_result *res, char *err, size_t err_size)
{
	cl_int status = clEnqueueReadBuffer(dev->queue, b->image.image, CL_TRUE, 0,
					    image_float_bytes(s->width, s->height), res->rgb, 0,
					    NULL, NULL);

	if (status == CL_SUCCESS && s->count_flops) {
		status = read_counts(dev, s, b, res);
		if (status == CL_OUT_OF_HOST_MEMORY) {
			snprintf(err, err_size, "out of host memory for the flop counts");
			return -1;
		}
	}
	if (status == CL_SUCCESS)
		status = checks_read_guards(dev, s, &b->image, res);
	if (status == CL_SUCCESS)
		status = probe_read(dev, s, b->probe, res);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "reading the results back failed (kernel '%s' on %s): %s",
			 s->kernel->name, dev->name, cl_error_name(status));
		return -1;
	}
	return 0;
}

int buffers_read_rows(struct device *dev, const struct render_settings *s,
		      const struct render_buffers *b, const struct rt_piece *p, float *to,
		      int packed, char *err, size_t err_size)
{
	size_t pixel = 3 * sizeof(float), image_row = (size_t)s->width * pixel;
	cl_int status = CL_SUCCESS;

	for (int v = p->y0; v < p->y0 + p->height && status == CL_SUCCESS;) {
		int y = rt_piece_row(p, v), rows = 1;
		while (v + rows < p->y0 + p->height && rt_piece_row(p, v + rows) == y + rows)
			rows++;
		size_t buffer_origin[3] = {(size_t)p->x0 * pixel, (size_t)y, 0};
		size_t host_origin[3] = {packed ? 0 : (size_t)p->x0 * pixel,
					 packed ? (size_t)(v - p->y0) : (size_t)y, 0};
		size_t region[3] = {(size_t)p->width * pixel, (size_t)rows, 1};
		size_t host_row = packed ? (size_t)p->width * pixel : image_row;
		status = clEnqueueReadBufferRect(dev->queue, b->image.image, CL_FALSE, buffer_origin,
						 host_origin, region, image_row, 0, host_row, 0, to,
						 0, NULL, NULL);
		v += rows;
	}
	cl_int done = clFinish(dev->queue);
	if (status == CL_SUCCESS)
		status = done;
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "reading the image back failed (%s): %s", dev->name,
			 cl_error_name(status));
		return -1;
	}
	return 0;
}

int buffers_read_sums(struct device *dev, const struct render_buffers *b, cl_long *to,
		      size_t first, size_t count, cl_event *event, char *err, size_t err_size)
{
	size_t pixel = 4 * sizeof(cl_long);
	cl_int status = clEnqueueReadBuffer(dev->queue, b->sums, event ? CL_FALSE : CL_TRUE,
					    first * pixel, count * pixel, to + 4 * first, 0, NULL,
					    event);

	if (status == CL_SUCCESS && event)
		status = clFlush(dev->queue);
	if (status != CL_SUCCESS) {
		snprintf(err, err_size, "reading the sample sums back failed (%s): %s", dev->name,
			 cl_error_name(status));
		return -1;
	}
	return 0;
}

void buffers_release(struct render_buffers *b)
{
	cl_mem buffers[] = {b->probe, b->flops, b->sums, b->scene};

	free(b->item_flops);
	free(b->scene_block);
	checks_release_image(&b->image);
	for (size_t i = 0; i < sizeof(buffers) / sizeof(buffers[0]); i++)
		if (buffers[i])
			clReleaseMemObject(buffers[i]);
	if (b->program)
		clReleaseProgram(b->program);
}

cl_int buffers_append_item_counts(struct device *dev, struct render_buffers *b, cl_mem from,
				  size_t items, size_t *alloc)
{
	if (b->item_count + items > *alloc) {
		size_t grown_alloc = (b->item_count + items) * 2;
		uint64_t *grown = realloc(b->item_flops, grown_alloc * sizeof(uint64_t));
		if (!grown)
			return CL_OUT_OF_HOST_MEMORY;
		b->item_flops = grown;
		*alloc = grown_alloc;
	}
	memset(b->item_flops + b->item_count, 0, items * sizeof(uint64_t));
	cl_int status =
		buffers_add_item_counts(dev, b, from, 0, items, b->item_flops + b->item_count);
	if (status == CL_SUCCESS)
		b->item_count += items;
	return status;
}
