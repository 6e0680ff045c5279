#include "output/schedmap.h"

#include <stdio.h>
#include <stdlib.h>

#include "base/version.h"
#include "output/image.h"
#include "rtcl_shared.h"

/* A 32-bit integer hash with good avalanche (Wellons' lowbias32), so that
 * groups next to each other get unrelated colours. */
static uint32_t mix(uint32_t x)
{
	x ^= x >> 16;
	x *= 0x7feb352du;
	x ^= x >> 15;
	x *= 0x846ca68bu;
	x ^= x >> 16;
	return x;
}

void schedmap_group_colour(uint32_t group, float rgb[3])
{
	uint32_t h = mix(group);
	float brightest = 0;

	for (int c = 0; c < 3; c++) {
		rgb[c] = group == 0xffffffffu ? 0.0f
					      : 0.15f + 0.8f * (float)((h >> (8 * c)) & 0xff) / 255.0f;
		brightest = rgb[c] > brightest ? rgb[c] : brightest;
	}
	/* A dark colour is lifted until its brightest channel is
	 * SCHEDMAP_MIN_BRIGHTEST: no group is near the black of a pixel no
	 * group started or the grey (40, 40, 40) of one the replay has not
	 * reached yet (rtcl-schedule-replay), which one looked like before. */
	if (group != 0xffffffffu && brightest < SCHEDMAP_MIN_BRIGHTEST)
		for (int c = 0; c < 3; c++)
			rgb[c] += SCHEDMAP_MIN_BRIGHTEST - brightest;
}

int schedmap_stage(struct staged_file *staged, const char *path, const uint32_t *schedule,
		   int width, int height, char *err, size_t err_size)
{
	size_t pixels = (size_t)width * (size_t)height;
	float *rgb = malloc(pixels * 3 * sizeof(float));
	char description[128];
	struct image_meta meta = {"rtcl " RTCL_VERSION, description, IMAGE_DISPLAY, 0};

	if (!rgb) {
		snprintf(err, err_size, "out of host memory for the schedule map");
		return -1;
	}
	for (size_t p = 0; p < pixels; p++)
		schedmap_group_colour(schedule[RT_SCHEDULE_WORDS * p + RT_SCHEDULE_GROUP],
				      rgb + 3 * p);
	snprintf(description, sizeof(description),
		 "schedule map: each pixel coloured by the work-group that traced it");
	int status = image_stage(staged, path, rgb, width, height, &meta, err, err_size);
	free(rgb);
	return status;
}
