/* Packing a loaded scene into the device layout of cl/rtcl_shared.h. */
#ifndef RTCL_DEVSCENE_H
#define RTCL_DEVSCENE_H

#include <stddef.h>
#include "bvh.h"
#include "scene.h"

/* Returns a malloc'd block holding struct rt_scene followed by its arrays, for
 * the scene at width×height with the given max_depth, and its size in *bytes;
 * NULL when out of memory. The camera basis is computed in double precision
 * and rounded once to float. bvh: the spheres' BVH, or NULL for none
 * (--accel none). */
void *devscene_pack(const struct scene *scene, const struct bvh *bvh, int width, int height,
		    int max_depth, size_t *bytes);

#endif
