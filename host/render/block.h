/* The scene block of a render on one device: the BVH built (--accel bvh),
 * the scene packed in cl/rtcl_shared.h's layout, checked to fit in one
 * buffer, and whether it lives in __local memory. */
#ifndef RTCL_BLOCK_H
#define RTCL_BLOCK_H

#include "render/settings.h"

/* Bytes of __local memory the kernels need besides the scene. */
#define LOCAL_MEM_RESERVE 256
/* The scene goes into __local memory when it takes at most 1/LOCAL_MEM_SHARE
 * of it (block_prepare_scene says why). */
#define LOCAL_MEM_SHARE 3

struct bvh;
struct mesh_block;

/* Refuses a scene whose device block (scene_block_bytes, with its indexed
 * triangles and bvh or NULL) is larger than one buffer on dev may be, naming
 * the size and the limit. */
int block_check_scene_fits(const struct device *dev, const struct scene *scene,
			   const struct mesh_block *mesh, const struct bvh *bvh, char *err,
			   size_t err_size);

/* Builds the BVH (--accel bvh), packs the scene into *block
 * (scene_block_pack_head: all but its texels, result->scene_bytes with
 * them), allocates result->rgb and decides whether the scene
 * lives in __local memory. */
int block_prepare_scene(struct device *dev, const struct scene *scene,
			const struct render_settings *settings, struct render_result *result,
			void **block, char *err, size_t err_size);

#endif
