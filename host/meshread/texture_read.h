/* Textures for rtcl-meshread (docs/SCENE.md, "Textures"): the files a mesh
 * file names, read under SCENE.md's path rule, and images decoded with
 * stb_image into the RGBA texels of docs/RENDERING.md, "Textures". */
#ifndef RTCL_TEXTURE_READ_H
#define RTCL_TEXTURE_READ_H

#include <stddef.h>

#include "scene/mesh.h"

/* SCENE.md's rule for the files a mesh file names (textures, an OBJ's MTL
 * library, glTF buffers): each must resolve, every symbolic link followed,
 * to a file inside the model's folder, the folder the scene names the mesh
 * file in, itself resolved. model_folder_set resolves it for the mesh file
 * at mesh_path; returns 0, or -1 with why in reason. */
int model_folder_set(const char *mesh_path, char *reason, size_t reason_size);

/* Where path leads (it is opened as the helper's folder, rtcl's, sees it):
 * MODEL_INSIDE with its resolved form in resolved[PATH_MAX], MODEL_OUTSIDE,
 * or MODEL_MISSING (errno says why it does not resolve). */
enum { MODEL_INSIDE, MODEL_OUTSIDE, MODEL_MISSING };
int model_folder_resolve(const char *path, char *resolved);

/* Whether name, relative to the model's folder, leaves it as text, before
 * any link is followed: an absolute name (a slash either way, a drive
 * letter), or one whose ".." climb above the folder. Such a name is outside
 * even where no file answers to it. */
int model_name_leaves(const char *name);

/* A glTF URI with its %XX escapes decoded (RFC 3986, as glTF 2.0 asks)
 * after its first `keep` bytes, which stay as they are; malloc'd. NULL with
 * why in reason: out of memory, or an escaped NUL byte. A '%' without two
 * hex digits after it stays itself. */
char *model_decode_uri(const char *uri, size_t keep, char *reason, size_t reason_size);

/* The reason a file outside the model's folder is refused with (%s: the
 * mesh file's name). */
#define MODEL_OUTSIDE_REASON "it lies outside the folder of \"%s\""

/* Reads the texture `name` (as the mesh file at mesh_path names it,
 * relative to its folder; a URI when `uri`, glTF's, whose %XX escapes are
 * decoded first) into *bytes (malloc'd) and *size, and the path it opened
 * into *opened (malloc'd; NULL where it opened none). Returns 0, or -1 with
 * why in reason: outside the folder, missing, not a regular file. */
int texture_file_bytes(const char *mesh_path, const char *name, int uri, unsigned char **bytes,
		       size_t *size, char **opened, char *reason, size_t reason_size);

/* Decodes an encoded image (PNG, JPEG, ...) of size bytes into t (width,
 * height, format, bytes) and *texels (malloc'd, t->bytes of them), the alpha
 * as t->role asks. Returns 0, or -1 with why in t->reason. */
int texture_decode(const unsigned char *bytes, size_t size, struct mesh_texture *t,
		   unsigned char **texels);

/* E^-1(x), the sRGB curve's inverse (RENDERING.md, "Writing the image"), in double. */
double texture_srgb_to_linear(double x);

#endif
