/* Packing a loaded scene into the device layout of cl/rtcl_shared.h. */
#ifndef RTCL_DEVSCENE_H
#define RTCL_DEVSCENE_H

#include <stddef.h>
#include <stdint.h>

#include "bvh.h"
#include "devmesh.h"
#include "scene.h"

/* The most the block may hold: struct rt_scene's offsets are 32-bit. */
#define DEVSCENE_MAX_BYTES ((size_t)UINT32_MAX - 15)

/* The size of the block devscene_pack makes for the scene, its triangles as
 * devmesh_build indexed them, and bvh (or NULL). */
size_t devscene_bytes(const struct scene *scene, const struct devmesh *mesh, const struct bvh *bvh);

/* Returns a malloc'd block holding struct rt_scene followed by its arrays, for
 * the scene at width×height with the given max_depth, and its size in *bytes;
 * NULL when out of memory or larger than DEVSCENE_MAX_BYTES. The camera basis
 * is computed in double precision and rounded once to float. mesh: the
 * scene's triangles from devmesh_build. bvh: the BVH of
 * the scene's spheres and triangles, or NULL for none (--accel none). */
void *devscene_pack(const struct scene *scene, const struct devmesh *mesh, const struct bvh *bvh,
		    int width, int height, int max_depth, size_t *bytes);

#endif
