/* A glTF 2.0 file's JSON beside Assimp (gltf_read.h). */
#define _POSIX_C_SOURCE 200809L
#include "meshread/gltf_read.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

/* The extensions rtcl reads (docs/SCENE.md, "Materials from mesh files");
 * KHR_lights_punctual, whose lights rtcl leaves out as it does every mesh
 * file's; and KHR_draco_mesh_compression, which the importer decodes
 * (Debian's Assimp 5.2 is built with Draco; one built without refuses the
 * file itself: "GLTF: Draco mesh compression not supported."). */
static const char *const supported[] = {"KHR_materials_ior",	      "KHR_materials_transmission",
					"KHR_texture_transform",      "KHR_lights_punctual",
					"KHR_draco_mesh_compression", NULL};

/* Reads count bytes at offset of fd into a malloc'd buffer, or NULL. */
static char *read_at(int fd, off_t offset, size_t count)
{
	char *buffer = malloc(count ? count : 1);

	for (size_t got = 0; buffer && got < count;) {
		ssize_t n = pread(fd, buffer + got, count - got, offset + (off_t)got);
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0) {
			free(buffer);
			return NULL;
		}
		got += (size_t)n;
	}
	return buffer;
}

static uint32_t le32(const unsigned char *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* Whether name ends in suffix, ignoring case. */
static int ends_with(const char *name, const char *suffix)
{
	size_t n = strlen(name), s = strlen(suffix);

	return n >= s && strcasecmp(name + n - s, suffix) == 0;
}

int gltf_read(const char *path, json_t **doc, char *reason, size_t reason_size)
{
	unsigned char head[20];
	struct stat st;
	json_error_t error;
	char *text = NULL;
	size_t length = 0;
	int fd, binary;
	const char *version;

	*doc = NULL;
	fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	if (fd < 0)
		return 0; /* the importer says why */
	if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
		close(fd);
		return 0;
	}
	binary = st.st_size >= 20 && pread(fd, head, 20, 0) == 20 && memcmp(head, "glTF", 4) == 0;
	if (binary) {
		/* GLB: a 12-byte header, then the JSON chunk (length, "JSON"). */
		length = le32(head + 12);
		if (memcmp(head + 16, "JSON", 4) == 0 && (off_t)length <= st.st_size - 20)
			text = read_at(fd, 20, length);
	} else if (ends_with(path, ".gltf")) {
		length = (size_t)st.st_size;
		text = read_at(fd, 0, length);
	}
	close(fd);
	if (!text)
		return 0;
	*doc = json_loadb(text, length, JSON_ALLOW_NUL, &error);
	free(text);
	if (!*doc) {
		snprintf(reason, reason_size,
			 "its glTF JSON does not parse: line %d, column %d: %s", error.line,
			 error.column, error.text);
		return -1;
	}
	version = json_string_value(json_object_get(json_object_get(*doc, "asset"), "version"));
	if (!json_is_object(*doc) || !version || version[0] != '2') {
		json_decref(*doc); /* glTF 1.0, or no glTF: the importer's matter */
		*doc = NULL;
	}
	return 0;
}

int gltf_check_required(const json_t *doc, char *reason, size_t reason_size)
{
	json_t *required = json_object_get(doc, "extensionsRequired");

	for (size_t i = 0; i < json_array_size(required); i++) {
		const char *name = json_string_value(json_array_get(required, i));
		const char *const *s = supported;

		if (!name)
			continue;
		while (*s && strcmp(*s, name) != 0)
			s++;
		if (!*s) {
			char shown[80]; /* its control bytes escaped by the message's reader */
			snprintf(shown, sizeof(shown), "%s", name);
			snprintf(
				reason, reason_size,
				"it requires the glTF extension \"%s\" (extensionsRequired), which "
				"rtcl does not read",
				shown);
			return -1;
		}
	}
	return 0;
}

/* ---- Node transforms ---- */

/* The array's n numbers into out; 0 where it is not n numbers. */
static int numbers(const json_t *array, double *out, size_t n)
{
	if (json_array_size(array) != n)
		return 0;
	for (size_t i = 0; i < n; i++) {
		const json_t *v = json_array_get(array, i);
		if (!json_is_number(v))
			return 0;
		out[i] = json_number_value(v);
	}
	return 1;
}

/* Node's local transform (rows of a 3x4 matrix): its "matrix" (column
 * major), else translation · rotation · scale, as Assimp 5.2 composes them
 * (the quaternion taken as it is, not normalized). */
static void local_transform(const json_t *node, double m[3][4])
{
	double matrix[16], t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};

	if (numbers(json_object_get(node, "matrix"), matrix, 16)) {
		for (int i = 0; i < 3; i++)
			for (int j = 0; j < 4; j++)
				m[i][j] = matrix[4 * j + i];
		return;
	}
	numbers(json_object_get(node, "translation"), t, 3);
	numbers(json_object_get(node, "rotation"), q, 4);
	numbers(json_object_get(node, "scale"), s, 3);
	double x = q[0], y = q[1], z = q[2], w = q[3];
	double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
			  {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
			  {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
	for (int i = 0; i < 3; i++) {
		for (int j = 0; j < 3; j++)
			m[i][j] = r[i][j] * s[j];
		m[i][3] = t[i];
	}
}

/* c = a · b for 3x4 affine matrices. */
static void compose(const double a[3][4], const double b[3][4], double c[3][4])
{
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 4; j++)
			c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j] +
				  (j == 3 ? a[i][3] : 0);
}

/* What the walk over the scene's nodes gathers. */
struct placed_camera {
	size_t index; /* in the file's cameras */
	struct mesh_camera camera;
};

struct camera_walk {
	const json_t *nodes, *cameras;
	char *visited;		      /* per node: a node is placed once */
	char *held;		      /* per camera: whether a node holds it */
	struct placed_camera *placed; /* the cameras held, as the walk meets them */
	size_t placed_count;
	int out_of_memory;
};

/* Node n under the transform of its parents, then its children. */
static void walk(struct camera_walk *w, size_t n, const double parent[3][4], int depth)
{
	const json_t *node = json_array_get(w->nodes, n);
	const json_t *camera = json_object_get(node, "camera");
	const json_t *children = json_object_get(node, "children");
	double local[3][4], m[3][4];

	if (!json_is_object(node) || w->visited[n] || depth > 1000 || w->out_of_memory)
		return;
	w->visited[n] = 1;
	local_transform(node, local);
	compose(parent, local, m);
	if (json_is_integer(camera) && json_integer_value(camera) >= 0 &&
	    (size_t)json_integer_value(camera) < json_array_size(w->cameras) &&
	    !w->held[json_integer_value(camera)]) {
		size_t i = (size_t)json_integer_value(camera);
		const json_t *cam = json_array_get(w->cameras, i);
		const json_t *perspective = json_object_get(cam, "perspective");
		const char *type = json_string_value(json_object_get(cam, "type"));
		const char *name = json_string_value(json_object_get(node, "name"));
		struct placed_camera *grown =
			realloc(w->placed, (w->placed_count + 1) * sizeof(*grown));
		struct mesh_camera *c;

		if (!grown) {
			w->out_of_memory = 1;
			return;
		}
		w->placed = grown;
		memset(&grown[w->placed_count], 0, sizeof(*grown));
		grown[w->placed_count].index = i;
		c = &grown[w->placed_count++].camera;
		w->held[i] = 1;
		/* Assimp's name: the node's, or its id where it has none. */
		if (name && name[0])
			snprintf(c->name, sizeof(c->name), "%s", name);
		else
			snprintf(c->name, sizeof(c->name), "nodes[%zu]", n);
		/* Control bytes kept: messages escape them (base/quote.h). */
		c->kind = type && strcmp(type, "orthographic") == 0 ? MESH_CAMERA_ORTHOGRAPHIC
								    : MESH_CAMERA_PERSPECTIVE;
		for (int k = 0; k < 3; k++) {
			c->position[k] = m[k][3];
			c->direction[k] = -m[k][2];
			c->up[k] = m[k][1];
		}
		/* yfov as the file gives it: 0 (or none) is refused as a field
		 * of view, not taken for an orthographic camera. */
		c->fov = json_number_value(json_object_get(perspective, "yfov")) *
			 (180.0 / 3.14159265358979323846);
		c->aspect = json_number_value(json_object_get(perspective, "aspectRatio"));
	}
	for (size_t i = 0; i < json_array_size(children); i++) {
		const json_t *child = json_array_get(children, i);
		if (json_is_integer(child) && json_integer_value(child) >= 0)
			walk(w, (size_t)json_integer_value(child), m, depth + 1);
	}
}

/* Orders placed cameras as the file's cameras are. */
static int by_index(const void *a, const void *b)
{
	size_t i = ((const struct placed_camera *)a)->index;
	size_t j = ((const struct placed_camera *)b)->index;

	return (i > j) - (i < j);
}

int gltf_read_cameras(const json_t *doc, struct mesh_data *out)
{
	static const double identity[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
	const json_t *scenes = json_object_get(doc, "scenes");
	const json_t *which = json_object_get(doc, "scene");
	size_t camera_count = json_array_size(json_object_get(doc, "cameras"));
	struct camera_walk w = {.nodes = json_object_get(doc, "nodes"),
				.cameras = json_object_get(doc, "cameras")};
	const json_t *scene, *roots;
	int ret = -1;

	w.visited = calloc(json_array_size(w.nodes) + 1, 1);
	w.held = calloc(camera_count + 1, 1);
	out->camera_count = 0;
	if (!w.visited || !w.held)
		goto out_free;
	/* The default scene, as Assimp 5.2 takes it: "scene", else the first. */
	scene = json_array_get(scenes, json_is_integer(which) && json_integer_value(which) >= 0
					       ? (size_t)json_integer_value(which)
					       : 0);
	roots = json_object_get(scene, "nodes");
	for (size_t i = 0; i < json_array_size(roots); i++) {
		const json_t *root = json_array_get(roots, i);
		if (json_is_integer(root) && json_integer_value(root) >= 0)
			walk(&w, (size_t)json_integer_value(root), identity, 0);
	}
	out->cameras = calloc(w.placed_count + 1, sizeof(*out->cameras));
	if (w.out_of_memory || !out->cameras)
		goto out_free;
	if (w.placed_count > 1) /* qsort must not be given NULL, even for 0 */
		qsort(w.placed, w.placed_count, sizeof(*w.placed), by_index);
	for (size_t i = 0; i < w.placed_count; i++)
		out->cameras[out->camera_count++] = w.placed[i].camera;
	ret = 0;
out_free:
	free(w.visited);
	free(w.placed);
	free(w.held);
	return ret;
}

/* ---- Texture coordinates ---- */

int gltf_transform_texcoord(const json_t *doc, const char *name)
{
	const json_t *materials = json_object_get(doc, "materials");
	const json_t *found = NULL;

	for (size_t i = 0; i < json_array_size(materials); i++) {
		const json_t *m = json_array_get(materials, i);
		const char *n = json_string_value(json_object_get(m, "name"));
		if (n && strcmp(n, name) == 0) {
			if (found)
				return -1; /* two of the name: which one is not known */
			found = m;
		}
	}
	const json_t *info =
		json_object_get(json_object_get(found, "pbrMetallicRoughness"), "baseColorTexture");
	const json_t *texcoord = json_object_get(
		json_object_get(json_object_get(info, "extensions"), "KHR_texture_transform"),
		"texCoord");
	return json_is_integer(texcoord) && json_integer_value(texcoord) >= 0 &&
			       json_integer_value(texcoord) < 8
		       ? (int)json_integer_value(texcoord)
		       : -1;
}

long gltf_plain_data_image(const json_t *doc)
{
	const json_t *images = json_object_get(doc, "images");

	for (size_t i = 0; i < json_array_size(images); i++) {
		const char *uri =
			json_string_value(json_object_get(json_array_get(images, i), "uri"));
		const char *comma = uri && strncmp(uri, "data:", 5) == 0 ? strchr(uri, ',') : NULL;

		if (comma && !(comma - uri >= 7 && strncmp(comma - 7, ";base64", 7) == 0))
			return (long)i;
	}
	return -1;
}
