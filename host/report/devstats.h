/* What each of several devices did (multidev.h): the summary lines and the
 * "devices" part of the --stats document. */
#ifndef RTCL_DEVSTATS_H
#define RTCL_DEVSTATS_H

#include <jansson.h>
#include <stdio.h>

#include "schedule/multidev.h"

/* One line per device (pieces, pixels, busy and set-up time) and the
 * device-level efficiency; `noun` names a piece ("tile", "frame"); ranks:
 * each device's MPI rank, or NULL without MPI. */
void devstats_print(FILE *out, const struct device *devs, const int *ranks,
		    const struct device_work *work, int count, const char *noun);

/* {"split", "piece", "devices": [{"device", "platform", "index", "pieces",
 * "pixels", "busy_ms", "setup_ms"}...], "device_efficiency"}; NULL when out of
 * memory. */
json_t *devstats_json(const struct device *devs, const int *ranks, const struct device_work *work,
		      int count, enum split split, const char *noun);

#endif
