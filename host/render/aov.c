/* The auxiliary images' pass (cl/aov.cl): one launch of the aov kernel over
 * the whole image, a work-item a pixel, read back into render_result.aov. */
#include "render/aov.h"

#include <stdio.h>
#include <stdlib.h>

#include "device/clerror.h"
#include "render/launch.h"
#include "render/program.h"

int aov_render(struct device *dev, const struct render_settings *s, struct render_result *res,
	       const struct render_buffers *b, char *err, size_t err_size)
{
	size_t pixels = (size_t)s->width * s->height, bytes = pixels * AOV_FLOATS * sizeof(float);
	size_t local[2] = {res->local_size[0], res->local_size[1]};
	size_t global[2];
	cl_int samples = settings_samples(s), status = CL_SUCCESS;
	/* An interrupted image holds its first samples_done samples only. */
	cl_int done = res->samples_done > 0 && res->samples_done < samples ? res->samples_done
									 : samples;
	const char *call = "clSetKernelArg";
	double ms = 0;
	int ret = -1;
	cl_mem out = NULL;
	cl_kernel kernel = program_create_kernel(b->program, "aov", err, err_size);

	if (!kernel)
		return -1;
	for (int d = 0; d < 2; d++) {
		size_t extent = d ? (size_t)s->height : (size_t)s->width;
		global[d] = (extent + local[d] - 1) / local[d] * local[d];
	}
	res->aov = malloc(bytes);
	if (!res->aov) {
		snprintf(err, err_size, "out of host memory for the auxiliary images");
		goto out_release_kernel;
	}
	out = device_create_buffer(dev, CL_MEM_WRITE_ONLY, bytes, NULL, "auxiliary images", err,
				   err_size);
	if (!out)
		goto out_release_kernel;
	size_t local_bytes = res->scene_in_local ? res->scene_bytes : UNUSED_BUFFER_BYTES;
	if ((status = clSetKernelArg(kernel, 0, sizeof(cl_mem), &b->scene)) != CL_SUCCESS ||
	    (status = clSetKernelArg(kernel, 1, local_bytes, NULL)) != CL_SUCCESS ||
	    (status = clSetKernelArg(kernel, 2, sizeof(cl_mem), &out)) != CL_SUCCESS ||
	    (status = clSetKernelArg(kernel, 3, sizeof(samples), &samples)) != CL_SUCCESS ||
	    (status = clSetKernelArg(kernel, 4, sizeof(done), &done)) != CL_SUCCESS)
		goto out_failed;
	status = launch_run(dev, kernel, 2, global, local, NULL, &ms, &call);
	if (status != CL_SUCCESS)
		goto out_failed;
	call = "clEnqueueReadBuffer";
	status = clEnqueueReadBuffer(dev->queue, out, CL_TRUE, 0, bytes, res->aov, 0, NULL, NULL);
	if (status != CL_SUCCESS)
		goto out_failed;
	ret = 0;
	goto out_release_buffer;

out_failed:
	snprintf(err, err_size, "the auxiliary images' kernel 'aov' on %s: %s failed: %s",
		 dev->name, call, cl_error_name(status));
out_release_buffer:
	clReleaseMemObject(out);
out_release_kernel:
	clReleaseKernel(kernel);
	if (ret) {
		free(res->aov);
		res->aov = NULL;
	}
	return ret;
}
