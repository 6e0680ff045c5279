#include "render/checks.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "render/launch.h"

int checks_create_image(struct device *dev, const struct render_settings *s,
			struct guarded_image *g, char *err, size_t err_size)
{
	size_t image_bytes = image_float_bytes(s->width, s->height);
	cl_int status;

	g->guard_bytes = 0;
	if (s->check_writes)
		g->guard_bytes = dev->mem_base_addr_align > 4096 ? dev->mem_base_addr_align : 4096;
	g->parent = device_create_buffer(dev, CL_MEM_READ_WRITE, image_bytes + 2 * g->guard_bytes,
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

void checks_release_image(struct guarded_image *g)
{
	if (g->image)
		clReleaseMemObject(g->image);
	if (g->parent)
		clReleaseMemObject(g->parent);
	g->image = g->parent = NULL;
}

cl_int checks_poison(struct device *dev, const struct render_settings *s,
		     const struct guarded_image *g)
{
	cl_uint poison = POISON_WORD;

	if (!s->check_writes)
		return CL_SUCCESS;
	return clEnqueueFillBuffer(dev->queue, g->parent, &poison, sizeof(poison), 0,
				   image_float_bytes(s->width, s->height) + 2 * g->guard_bytes, 0,
				   NULL, NULL);
}

cl_int checks_read_guards(struct device *dev, const struct render_settings *s,
			  const struct guarded_image *g, struct render_result *res)
{
	cl_uint *guard;
	cl_int status = CL_SUCCESS;

	if (!s->check_writes)
		return CL_SUCCESS;
	guard = malloc(g->guard_bytes);
	if (!guard)
		return CL_OUT_OF_HOST_MEMORY;
	res->guards_intact = 1;
	for (int side = 0; status == CL_SUCCESS && side < 2; side++) {
		size_t offset = side ? g->guard_bytes + image_float_bytes(s->width, s->height) : 0;
		status = clEnqueueReadBuffer(dev->queue, g->parent, CL_TRUE, offset, g->guard_bytes,
					     guard, 0, NULL, NULL);
		for (size_t i = 0; status == CL_SUCCESS && i < g->guard_bytes / sizeof(cl_uint);
		     i++)
			res->guards_intact &= guard[i] == POISON_WORD;
	}
	free(guard);
	return status;
}
