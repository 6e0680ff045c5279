/* Packing a loaded scene into the device layout of cl/rtcl_shared.h. */
#ifndef RTCL_SCENE_BLOCK_H
#define RTCL_SCENE_BLOCK_H

#include <stddef.h>
#include <stdint.h>

#include "layout/bvh.h"
#include "layout/mesh_block.h"
#include "scene/scene.h"

/* The most the block may hold: struct rt_scene's offsets are 32-bit. */
#define DEVSCENE_MAX_BYTES ((size_t)UINT32_MAX - 15)

/* The size of the block scene_block_pack makes for the scene, its triangles as
 * mesh_block_build indexed them, and bvh (or NULL). */
size_t scene_block_bytes(const struct scene *scene, const struct mesh_block *mesh, const struct bvh *bvh);

/* The device computes in float, relative to the camera's eye
 * (scene_from_eye): an object smaller than DEVSCENE_MIN_STEPS float steps at
 * its distance from the eye (a sphere's radius, a triangle's longest edge)
 * cannot be drawn. Returns 0, or -1 with a message in err that names the
 * first such object and the numbers. */
#define DEVSCENE_MIN_STEPS 4
int scene_block_check_resolution(const struct scene *scene, char *err, size_t err_size);

/* Returns a malloc'd block holding struct rt_scene followed by its arrays, for
 * the scene at width×height with the given max_depth, and its size in *bytes;
 * NULL when out of memory or larger than DEVSCENE_MAX_BYTES. Every position
 * is taken relative to the eye in double (scene_from_eye) and rounded once
 * to float; so is the camera basis. mesh: the
 * scene's triangles from mesh_block_build. bvh: the BVH of
 * the scene's spheres and triangles, or NULL for none (--accel none). */
void *scene_block_pack(const struct scene *scene, const struct mesh_block *mesh, const struct bvh *bvh,
		    int width, int height, int max_depth, size_t *bytes);

/* scene_block_pack without the texels: the malloc'd block ends where they
 * begin, at scene_block_head_bytes of its *bytes. The environment map's
 * texels and column CDFs come first (its struct rt_path's env_texel_offset
 * and env_column_cdf_offset, from scene_block_env_rows, padded with zeros
 * to 16 bytes), then texture i's texels (scene->textures[i].texels) at the
 * offset of its struct rt_texture, each padded with zeros to 16 bytes. A
 * renderer writes them into the device's buffer from the scene, so that no
 * second copy of them is made on the host (issue 39, finding 14). */
void *scene_block_pack_head(const struct scene *scene, const struct mesh_block *mesh,
			    const struct bvh *bvh, int width, int height, int max_depth,
			    size_t *bytes);

/* The bytes of a block (whole or from scene_block_pack_head) before its
 * texels (the environment map's, else the textures'): its whole size where
 * it has neither. */
size_t scene_block_head_bytes(const void *block);

/* Rows [k0, k1) of the environment map as the block holds them: their
 * texels with the scale (struct rt_path's env_texel_offset + k0 * width
 * rt_vec4s), their column CDFs (env_column_cdf_offset + k0 * width floats). */
void scene_block_env_rows(const struct scene_environment *env, int k0, int k1, void *texels,
			  float *column_cdf);

#endif
