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

/* Whether name, relative to the mesh file's folder, stays inside it: not
 * absolute, and no ".." that climbs above the folder. */
static int inside_folder(const char *name)
{
	int depth = 0;

	if (name[0] == '/' || name[0] == '\\' || (name[0] && name[1] == ':'))
		return 0;
	for (const char *part = name; *part;) {
		size_t n = strcspn(part, "/\\");
		if (n == 2 && part[0] == '.' && part[1] == '.') {
			if (--depth < 0)
				return 0;
		} else if (n > 0 && !(n == 1 && part[0] == '.')) {
			depth++;
		}
		part += n;
		part += *part != '\0';
	}
	return 1;
}

int texture_file_bytes(const char *mesh_path, const char *name, unsigned char **bytes,
		       size_t *size, char *reason, size_t reason_size)
{
	const char *slash = strrchr(mesh_path, '/');
	size_t dir = slash ? (size_t)(slash - mesh_path) + 1 : 0;
	const char *mesh_name = slash ? slash + 1 : mesh_path;
	char *path = malloc(dir + strlen(name) + 1);
	struct stat st;
	int fd = -1, ret = -1;

	*bytes = NULL;
	if (!path) {
		snprintf(reason, reason_size, "out of memory");
		return -1;
	}
	if (!inside_folder(name)) {
		snprintf(reason, reason_size, "it lies outside the folder of \"%s\"", mesh_name);
		goto out_free;
	}
	memcpy(path, mesh_path, dir);
	strcpy(path + dir, name);
	for (char *c = path + dir; *c; c++) /* Windows exports write a\b.png */
		if (*c == '\\')
			*c = '/';
	/* Without blocking: a FIFO there must not hang the import. */
	fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	if (fd < 0 || fstat(fd, &st) != 0) {
		snprintf(reason, reason_size, "%s", strerror(errno));
		goto out_free;
	}
	if (!S_ISREG(st.st_mode)) {
		snprintf(reason, reason_size, "it is not a regular file");
		goto out_free;
	}
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
				out[i] = (float)(c == 3 || t->role == MESH_TEXTURE_DATA
							 ? x
							 : texture_srgb_to_linear(x));
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
