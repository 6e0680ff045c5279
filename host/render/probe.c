#include "render/probe.h"

#include <stdlib.h>

#include "rtcl_shared.h"
#include "render/launch.h" /* UNUSED_BUFFER_BYTES */

/* The words the probe holds for s: 0 when it is a placeholder. */
static size_t probe_words(const struct render_settings *s)
{
	size_t pixels = (size_t)s->width * s->height;

	if (s->check_writes)
		return pixels;
	if (s->record_schedule)
		return RT_SCHEDULE_WORDS * pixels + 1; /* the ticket counter last */
	return 0;
}

cl_mem probe_create(struct device *dev, const struct render_settings *s, char *err,
		    size_t err_size)
{
	size_t words = probe_words(s);
	const char *what = s->check_writes ? "write counts" : "schedule map";

	return device_create_buffer(dev, CL_MEM_READ_WRITE,
				    words ? words * sizeof(cl_uint) : UNUSED_BUFFER_BYTES, NULL,
				    words ? what : "probe", err, err_size);
}

cl_int probe_clear(struct device *dev, const struct render_settings *s, cl_mem probe)
{
	size_t words = probe_words(s);
	cl_uint zero = 0, unvisited = 0xffffffffu;
	cl_int status;

	if (!words)
		return CL_SUCCESS;
	if (s->check_writes)
		return clEnqueueFillBuffer(dev->queue, probe, &zero, sizeof(zero), 0,
					   words * sizeof(cl_uint), 0, NULL, NULL);
	status = clEnqueueFillBuffer(dev->queue, probe, &unvisited, sizeof(unvisited), 0,
				     (words - 1) * sizeof(cl_uint), 0, NULL, NULL);
	if (status == CL_SUCCESS)
		status = clEnqueueFillBuffer(dev->queue, probe, &zero, sizeof(zero),
					     (words - 1) * sizeof(cl_uint), sizeof(cl_uint), 0,
					     NULL, NULL);
	return status;
}

cl_int probe_read(struct device *dev, const struct render_settings *s, cl_mem probe,
		  struct render_result *res)
{
	size_t words = probe_words(s);
	uint32_t **into = s->check_writes ? &res->write_counts : &res->schedule;

	if (!words)
		return CL_SUCCESS;
	if (s->record_schedule && !s->check_writes)
		words--; /* not the ticket counter */
	*into = malloc(words * sizeof(uint32_t));
	if (!*into)
		return CL_OUT_OF_HOST_MEMORY;
	return clEnqueueReadBuffer(dev->queue, probe, CL_TRUE, 0, words * sizeof(cl_uint), *into, 0,
				   NULL, NULL);
}
