/* Textures for rtcl-meshread (texture_read.h). Images are decoded with
 * stb_image (Debian's libstb-dev), compiled into the helper: one header, no
 * library for rtcl to carry to a machine (the GPU build runs where only the
 * base system is), and PNG, JPEG, TGA, BMP, PSD, GIF, HDR and PNM from files
 * and from memory (a .glb's embedded images) through one call. Its
 * decoders run inside the helper, under its memory and time limits, where a
 * crash on a malformed image refuses the mesh and never ends rtcl. */
#define _POSIX_C_SOURCE 200809L
#include "meshread/texture_read.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define STBI_NO_STDIO		/* the helper reads the files itself */
#define STB_IMAGE_IMPLEMENTATION
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#endif
#include <stb/stb_image.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

/* The model's folder and the mesh file, resolved (model_folder_set). */
static char model_folder[PATH_MAX], model_file[PATH_MAX];

int model_folder_set(const char *mesh_path, char *reason, size_t reason_size)
{
	const char *slash = strrchr(mesh_path, '/');
	char *folder = slash ? strndup(mesh_path, (size_t)(slash - mesh_path) + 1) : strdup(".");
	int ok = folder && realpath(folder, model_folder) && realpath(mesh_path, model_file);

	if (!ok)
		snprintf(reason, reason_size, "%s", folder ? strerror(errno) : "out of memory");
	free(folder);
	return ok ? 0 : -1;
}

int model_folder_resolve(const char *path, char *resolved)
{
	size_t n = strlen(model_folder);

	if (!realpath(path, resolved))
		return MODEL_MISSING;
	if (strcmp(resolved, model_file) == 0)
		return MODEL_INSIDE;
	if (strcmp(model_folder, "/") == 0)
		return resolved[1] ? MODEL_INSIDE : MODEL_OUTSIDE;
	return strncmp(resolved, model_folder, n) == 0 && resolved[n] == '/' ? MODEL_INSIDE
									     : MODEL_OUTSIDE;
}

int model_name_leaves(const char *name)
{
	int depth = 0;

	if (name[0] == '/' || name[0] == '\\' || (name[0] && name[1] == ':'))
		return 1;
	for (const char *part = name; *part;) {
		size_t n = strcspn(part, "/\\");
		if (n == 2 && part[0] == '.' && part[1] == '.') {
			if (--depth < 0)
				return 1;
		} else if (n > 0 && !(n == 1 && part[0] == '.')) {
			depth++;
		}
		part += n;
		part += *part != '\0';
	}
	return 0;
}

static int hex_digit(char c)
{
	return c >= '0' && c <= '9'   ? c - '0'
	       : c >= 'a' && c <= 'f' ? c - 'a' + 10
	       : c >= 'A' && c <= 'F' ? c - 'A' + 10
				      : -1;
}

char *model_decode_uri(const char *uri, size_t keep, char *reason, size_t reason_size)
{
	char *out = malloc(strlen(uri) + 1), *o = out;

	if (!out) {
		snprintf(reason, reason_size, "out of memory");
		return NULL;
	}
	memcpy(o, uri, keep);
	o += keep;
	for (const char *c = uri + keep; *c; c++) {
		int high = c[0] == '%' ? hex_digit(c[1]) : -1,
		    low = high >= 0 ? hex_digit(c[2]) : -1;

		if (low < 0) {
			*o++ = *c;
			continue;
		}
		if (high == 0 && low == 0) {
			snprintf(reason, reason_size, "its URI holds an escaped NUL byte (%%00)");
			free(out);
			return NULL;
		}
		*o++ = (char)(high * 16 + low);
		c += 2;
	}
	*o = '\0';
	return out;
}

int texture_file_bytes(const char *mesh_path, const char *name, int uri, unsigned char **bytes,
		       size_t *size, char **opened, char *reason, size_t reason_size)
{
	const char *slash = strrchr(mesh_path, '/');
	size_t dir = slash ? (size_t)(slash - mesh_path) + 1 : 0;
	const char *mesh_name = slash ? slash + 1 : mesh_path;
	char *decoded = uri ? model_decode_uri(name, 0, reason, reason_size) : NULL, *path = NULL;
	char resolved[PATH_MAX];
	struct stat st;
	int fd = -1, ret = -1;

	*bytes = NULL;
	*opened = NULL;
	if (uri && !decoded)
		return -1;
	name = decoded ? decoded : name;
	if (!name[0]) {
		snprintf(reason, reason_size, "the file gives it no name");
		goto out_free;
	}
	if (model_name_leaves(name)) {
		snprintf(reason, reason_size, MODEL_OUTSIDE_REASON, mesh_name);
		goto out_free;
	}
	path = malloc(dir + strlen(name) + 1);
	if (!path) {
		snprintf(reason, reason_size, "out of memory");
		goto out_free;
	}
	memcpy(path, mesh_path, dir);
	strcpy(path + dir, name);
	for (char *c = path + dir; *c; c++) /* Windows exports write a\b.png */
		if (*c == '\\')
			*c = '/';
	switch (model_folder_resolve(path, resolved)) {
	case MODEL_MISSING:
		snprintf(reason, reason_size, "%s", strerror(errno));
		goto out_free;
	case MODEL_OUTSIDE:
		snprintf(reason, reason_size, MODEL_OUTSIDE_REASON, mesh_name);
		goto out_free;
	}
	/* The resolved path, so that what was checked is what is read; without
	 * blocking: a FIFO there must not hang the import. */
	fd = open(resolved, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOFOLLOW);
	if (fd < 0 || fstat(fd, &st) != 0) {
		snprintf(reason, reason_size, "%s", strerror(errno));
		goto out_free;
	}
	if (!S_ISREG(st.st_mode)) {
		snprintf(reason, reason_size, "it is not a regular file");
		goto out_free;
	}
	*opened = path;
	path = NULL;
	*size = (size_t)st.st_size;
	*bytes = malloc(*size ? *size : 1);
	if (!*bytes) {
		snprintf(reason, reason_size, "out of memory for its %zu bytes", *size);
		goto out_free;
	}
	for (size_t got = 0; got < *size;) {
		ssize_t n = read(fd, *bytes + got, *size - got);
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0) {
			snprintf(reason, reason_size, "%s",
				 n < 0 ? strerror(errno) : "it ended while being read");
			free(*bytes);
			*bytes = NULL;
			goto out_free;
		}
		got += (size_t)n;
	}
	ret = 0;
out_free:
	if (fd >= 0)
		close(fd);
	free(path);
	free(decoded);
	return ret;
}

double texture_srgb_to_linear(double x)
{
	return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

/* A float texel's channel as RENDERING.md takes it: NaN and negative values
 * 0, above 1e18 1e18. */
static float finite_channel(float x)
{
	return !(x > 0.0f) ? 0.0f : x > 1e18f ? 1e18f : x;
}

int texture_decode(const unsigned char *bytes, size_t size, struct mesh_texture *t,
		   unsigned char **texels)
{
	int w, h, channels;
	size_t count;

	*texels = NULL;
	if (size > INT32_MAX) {
		snprintf(t->reason, sizeof(t->reason), "it has %zu bytes, more than 2 GiB", size);
		return -1;
	}
	if (!stbi_info_from_memory(bytes, (int)size, &w, &h, &channels)) {
		snprintf(t->reason, sizeof(t->reason), "the image decoder (stb_image) says \"%s\"",
			 stbi_failure_reason());
		return -1;
	}
	if (w > MESH_TEXTURE_MAX_SIDE || h > MESH_TEXTURE_MAX_SIDE) {
		snprintf(t->reason, sizeof(t->reason),
			 "it is %dx%d texels, more than the %d a side rtcl reads", w, h,
			 MESH_TEXTURE_MAX_SIDE);
		return -1;
	}
	/* The alpha an opacity texture without an alpha channel takes from
	 * its first channel. */
	int alpha_from_first = t->role == MESH_TEXTURE_OPACITY && (channels == 1 || channels == 3);
	int wide = stbi_is_16_bit_from_memory(bytes, (int)size);
	int hdr = stbi_is_hdr_from_memory(bytes, (int)size);

	if (wide || hdr) {
		void *in = wide ? (void *)stbi_load_16_from_memory(bytes, (int)size, &w, &h,
								   &channels, 4)
				: (void *)stbi_loadf_from_memory(bytes, (int)size, &w, &h,
								 &channels, 4);
		float *out;
		if (!in) {
			snprintf(t->reason, sizeof(t->reason),
				 "the image decoder (stb_image) says \"%s\"", stbi_failure_reason());
			return -1;
		}
		count = (size_t)w * (size_t)h;
		out = malloc(count * 4 * sizeof(float));
		if (!out) {
			stbi_image_free(in);
			snprintf(t->reason, sizeof(t->reason), "out of memory for %dx%d texels", w,
				 h);
			return -1;
		}
		for (size_t i = 0; i < 4 * count; i++) {
			int c = (int)(i % 4);
			if (wide) {
				double x = ((const uint16_t *)in)[i] / 65535.0;
				if (c == 3 && alpha_from_first)
					x = ((const uint16_t *)in)[i - 3] / 65535.0;
				out[i] = (float)(c == 3 ? x : texture_srgb_to_linear(x));
			} else {
				float x = ((const float *)in)[i];
				if (c == 3 && alpha_from_first)
					x = ((const float *)in)[i - 3];
				out[i] = finite_channel(x);
			}
		}
		stbi_image_free(in);
		t->format = MESH_TEXELS_FLOAT;
		*texels = (unsigned char *)out;
	} else {
		unsigned char *in = stbi_load_from_memory(bytes, (int)size, &w, &h, &channels, 4);
		if (!in) {
			snprintf(t->reason, sizeof(t->reason),
				 "the image decoder (stb_image) says \"%s\"", stbi_failure_reason());
			return -1;
		}
		count = (size_t)w * (size_t)h;
		if (alpha_from_first)
			for (size_t i = 0; i < count; i++)
				in[4 * i + 3] = in[4 * i];
		/* stb_image's memory comes from malloc (its default STBI_MALLOC). */
		t->format = MESH_TEXELS_8;
		*texels = in;
	}
	t->width = (uint32_t)w;
	t->height = (uint32_t)h;
	t->bytes = (uint64_t)count * (t->format == MESH_TEXELS_FLOAT ? 16 : 4);
	return 0;
}
