/* A glTF 2.0 file's JSON, read by rtcl-meshread itself (jansson) beside
 * Assimp, for what Assimp 5.2 does not check or does not keep (issue 39):
 * the JSON's syntax, said where it fails (Assimp: "No suitable reader
 * found"); extensionsRequired (Assimp ignores all but Draco); the camera a
 * node holds (Assimp names a camera by its node and finds the first node of
 * that name; a perspective camera of yfov 0 it keeps as orthographic); and
 * KHR_texture_transform's texCoord. Assimp's glTF materials are in the
 * order its reader first met them, not the file's: they are matched by name. */
#ifndef RTCL_GLTF_READ_H
#define RTCL_GLTF_READ_H

#include <stddef.h>

#include <jansson.h>

#include "scene/mesh.h"

/* Reads path's JSON when it is a glTF 2.0 file (a .gltf, or a .glb's JSON
 * chunk) into *doc (json_decref it); *doc NULL for other files, and for
 * glTF files that are not 2.0 or whose binary container is malformed (the
 * importer's matter). Returns 0, or -1 with why in reason: JSON that does
 * not parse, with its line and column. */
int gltf_read(const char *path, json_t **doc, char *reason, size_t reason_size);

/* Returns 0, or -1 with why in reason when extensionsRequired names an
 * extension rtcl does not read (docs/SCENE.md lists those it does). */
int gltf_check_required(const json_t *doc, char *reason, size_t reason_size);

/* The cameras that a node of the default scene holds, in the order of the
 * file's cameras, each placed by the node that holds it (its transform and
 * its parents'), named by that node. Returns -1 when out of memory. */
int gltf_read_cameras(const json_t *doc, struct mesh_data *out);

/* The texCoord that KHR_texture_transform gives the base colour texture of
 * the file's one material called name, or -1 where it gives none (or the
 * name is not one material's). Assimp 5.2 keeps the extension's offset,
 * rotation and scale, not this. */
int gltf_transform_texcoord(const json_t *doc, const char *name);

/* The index of the file's first image whose uri is a data: URI that is not
 * base64 (Assimp 5.2 keeps no bytes and no name for one), or -1. */
long gltf_plain_data_image(const json_t *doc);

#endif
