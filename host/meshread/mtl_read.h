/* The texture options of an MTL material library that Assimp 5.2 reads past
 * without keeping them: map_Kd's and map_d's -s (scale) and -o (offset), which
 * rtcl applies to the texture coordinates (docs/SCENE.md, "Textures";
 * issue 39 finding 6). */
#ifndef RTCL_MTL_READ_H
#define RTCL_MTL_READ_H

#include <stddef.h>

#include "scene/mesh.h"

/* A texture statement's transform: u' = scale[0] u + offset[0], v' =
 * scale[1] v + offset[1] (the MTL's own coordinates, v up). */
struct mtl_transform {
	char material[MESH_NAME_MAX]; /* its newmtl's name, as Assimp takes it */
	unsigned role;		      /* enum mesh_texture_role: map_Kd or map_d */
	double scale[2], offset[2];
};

/* Appends the transforms of the map_Kd and map_d statements that give -s or
 * -o in the MTL file at path to *list (*count of them, realloc'd). Returns
 * 0, or -1 when out of memory; a file that cannot be read adds nothing. */
int mtl_read_transforms(const char *path, struct mtl_transform **list, size_t *count);

#endif
