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
#include <sys/resource.h>
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
	/* Refused by its size before any of it is read. */
	if ((uint64_t)st.st_size > MESH_TEXTURE_MAX_FILE_BYTES) {
		snprintf(reason, reason_size, "it has %lld bytes, more than 2 GiB",
			 (long long)st.st_size);
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

/* What the image's header says, before anything is decoded. */
struct image_header {
	int width, height, channels; /* channels in the file */
	int wide, hdr;		     /* 16 bits a channel; float (Radiance HDR) */
	int png;
};

/* The bytes of address space the helper may still take: its limit
 * (RLIMIT_AS, --mesh-memory-limit) less what it holds; 0: no limit. */
static uint64_t memory_left(uint64_t *limit)
{
	struct rlimit rl;
	unsigned long long pages = 0;
	FILE *f;

	*limit = 0;
	if (getrlimit(RLIMIT_AS, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY)
		return 0;
	*limit = (uint64_t)rl.rlim_cur;
	f = fopen("/proc/self/statm", "r");
	if (f) {
		if (fscanf(f, "%llu", &pages) != 1)
			pages = 0;
		fclose(f);
	}
	uint64_t used = (uint64_t)pages * (uint64_t)sysconf(_SC_PAGESIZE);
	return used < *limit ? *limit - used : 1;
}

/* Refuses, from its header alone, an image that rtcl could never render or
 * that the decoder could not hold (issue 39 finding 14: a 16384² 16-bit PNG
 * decoded for 49 s into 8.4 GB before a limit refused it). Returns 0, or -1
 * with why in t->reason. */
static int check_header(const struct image_header *im, size_t file_bytes, struct mesh_texture *t)
{
	uint64_t texels = (uint64_t)im->width * (uint64_t)im->height;
	int bytes_per_channel = im->hdr ? 4 : im->wide ? 2 : 1;
	uint64_t device_bytes = texels * (im->wide || im->hdr ? 16 : 4);
	/* stb_image's PNG decoder inflates the rows, each with its filter byte,
	 * into one buffer whose size is an int. */
	uint64_t raw = (uint64_t)im->height *
		       ((uint64_t)im->width * (uint64_t)im->channels * bytes_per_channel + 1);
	uint64_t decoded = texels * (uint64_t)im->channels * bytes_per_channel;
	uint64_t four = texels * 4 * bytes_per_channel;
	uint64_t limit, left = memory_left(&limit);
	/* The decoder's peak: the inflated rows and the image, or the image
	 * and its RGBA copy; then the texels (16-bit ones grow in place to
	 * floats). */
	uint64_t peak = file_bytes + (raw + decoded > decoded + four ? raw + decoded : decoded + four);

	if (im->width > MESH_TEXTURE_MAX_SIDE || im->height > MESH_TEXTURE_MAX_SIDE) {
		snprintf(t->reason, sizeof(t->reason),
			 "it is %dx%d texels, more than the %d a side rtcl reads", im->width,
			 im->height, MESH_TEXTURE_MAX_SIDE);
		return -1;
	}
	if (device_bytes > MESH_TEXTURE_MAX_BYTES) {
		snprintf(t->reason, sizeof(t->reason),
			 "it is %dx%d texels of %s, %llu bytes on the device, more than the %llu a "
			 "scene may hold",
			 im->width, im->height, im->wide ? "16 bits (16 bytes a texel as floats)"
						 : "float (16 bytes a texel)",
			 (unsigned long long)device_bytes, (unsigned long long)MESH_TEXTURE_MAX_BYTES);
		return -1;
	}
	if (im->png && raw > (uint64_t)INT32_MAX) {
		snprintf(t->reason, sizeof(t->reason),
			 "it is %dx%d texels of %d channels at %d bits, more than the image decoder "
			 "(stb_image) holds (2 GiB of rows)",
			 im->width, im->height, im->channels, 8 * bytes_per_channel);
		return -1;
	}
	if (device_bytes > peak)
		peak = device_bytes;
	if (limit && peak > left) {
		snprintf(t->reason, sizeof(t->reason),
			 "it is %dx%d texels; decoding it takes about %llu MiB, more than the "
			 "import's memory limit of %llu MiB leaves (--mesh-memory-limit or "
			 "RTCL_MESH_MEMORY_LIMIT)",
			 im->width, im->height, (unsigned long long)(peak >> 20) + 1,
			 (unsigned long long)(limit >> 20));
		return -1;
	}
	return 0;
}

/* Why stb_image returned no image: its words, or (none: a failed malloc,
 * which it does not always name) out of memory. */
static void decoder_failed(const struct image_header *im, struct mesh_texture *t)
{
	const char *why = stbi_failure_reason();

	if (why && why[0])
		snprintf(t->reason, sizeof(t->reason), "the image decoder (stb_image) says \"%s\"",
			 why);
	else
		snprintf(t->reason, sizeof(t->reason),
			 "the image decoder (stb_image) ran out of memory for its %dx%d texels",
			 im->width, im->height);
}

int texture_decode(const unsigned char *bytes, size_t size, struct mesh_texture *t,
		   unsigned char **texels)
{
	static const unsigned char png_signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
	struct image_header im;
	int w, h, channels;
	size_t count;

	*texels = NULL;
	if ((uint64_t)size > MESH_TEXTURE_MAX_FILE_BYTES) {
		snprintf(t->reason, sizeof(t->reason), "it has %zu bytes, more than 2 GiB", size);
		return -1;
	}
	if (!stbi_info_from_memory(bytes, (int)size, &im.width, &im.height, &im.channels)) {
		snprintf(t->reason, sizeof(t->reason), "the image decoder (stb_image) says \"%s\"",
			 stbi_failure_reason());
		return -1;
	}
	im.wide = stbi_is_16_bit_from_memory(bytes, (int)size);
	im.hdr = stbi_is_hdr_from_memory(bytes, (int)size);
	im.png = size >= 8 && memcmp(bytes, png_signature, 8) == 0;
	if (check_header(&im, size, t))
		return -1;
	/* stbi_info tried every format before the right one and left the
	 * last one's complaint ("no SOI", a JPEG's); a load that fails
	 * without words of its own must not show it. */
	stbi__g_failure_reason = NULL;
	/* The alpha an opacity texture without an alpha channel takes from
	 * its first channel. */
	int alpha_from_first =
		t->role == MESH_TEXTURE_OPACITY && (im.channels == 1 || im.channels == 3);

	if (im.wide || im.hdr) {
		/* Decoded as RGBA, 16-bit or float, then made floats in place
		 * (the buffer grown to 16 bytes a texel, filled from its end):
		 * no second copy of the image. */
		void *in = im.wide ? (void *)stbi_load_16_from_memory(bytes, (int)size, &w, &h,
								      &channels, 4)
				   : (void *)stbi_loadf_from_memory(bytes, (int)size, &w, &h,
								    &channels, 4);
		float *out;

		if (!in) {
			decoder_failed(&im, t);
			return -1;
		}
		count = (size_t)w * (size_t)h;
		out = im.wide ? realloc(in, count * 4 * sizeof(float)) : in;
		if (!out) {
			stbi_image_free(in);
			snprintf(t->reason, sizeof(t->reason), "out of memory for %dx%d texels", w,
				 h);
			return -1;
		}
		for (size_t i = 4 * count; i-- > 0;) {
			int c = (int)(i % 4);
			if (im.wide) {
				const uint16_t *in16 = (const uint16_t *)out;
				double x = in16[c == 3 && alpha_from_first ? i - 3 : i] / 65535.0;
				out[i] = (float)(c == 3 || t->role == MESH_TEXTURE_DATA
							 ? x
							 : texture_srgb_to_linear(x));
			} else {
				out[i] = finite_channel(out[c == 3 && alpha_from_first ? i - 3 : i]);
			}
		}
		t->format = MESH_TEXELS_FLOAT;
		*texels = (unsigned char *)out;
	} else {
		unsigned char *in = stbi_load_from_memory(bytes, (int)size, &w, &h, &channels, 4);
		if (!in) {
			decoder_failed(&im, t);
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
