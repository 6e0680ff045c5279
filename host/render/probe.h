/* The probe buffer every single-pass kernel takes (cl/rtcl_shared.h): with
 * check_writes (the kernel tests) one write count per pixel; with
 * record_schedule (--schedule-map, docs/RENDERING.md) each pixel's work-group,
 * work-item and ticket, then the ticket counter; otherwise a placeholder. */
#ifndef RTCL_PROBE_H
#define RTCL_PROBE_H

#include "render/settings.h"

/* Creates the probe buffer for s. Returns it, or NULL with one message in
 * err. */
cl_mem probe_create(struct device *dev, const struct render_settings *s, char *err,
		    size_t err_size);

/* Before the first piece: zeroes the write counts, or marks every pixel of
 * the schedule map unvisited (all ones) and zeroes the ticket counter. */
cl_int probe_clear(struct device *dev, const struct render_settings *s, cl_mem probe);

/* Reads the write counts into result->write_counts, or the schedule map into
 * result->schedule; nothing without either. */
cl_int probe_read(struct device *dev, const struct render_settings *s, cl_mem probe,
		  struct render_result *result);

#endif
