/* The OpenImageIO backend, loaded when an image needs it. image_oiio.cpp is
 * built into a module of its own (rtcl-oiio.so) because OpenImageIO pulls in
 * some 260 shared libraries (codecs, OpenCV, GDAL, ...) whose loading and
 * relocation took about 0.2 s of every rtcl run, and 30-40 ms more of PoCL's
 * device set-up, whatever the output: .ppm, .pfm and .png, which rtcl writes
 * itself, now never load it. The module is looked for beside the installed
 * program (BINDIR/../lib/rtcl/) and then in the build folder (libdir.h). */
#include <dlfcn.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "output/image_backend.h"
#include "base/libdir.h"

#define MODULE_NAME "rtcl-oiio.so"

typedef int (*check_format_fn)(const char *, const char *, char *, size_t);
typedef int (*encode_fn)(const char *, const char *, int, const float *, int, int,
			 const struct image_meta *, char *, size_t);
typedef int (*verify_fn)(const char *, const char *, int, int, char *, size_t);

static struct {
	int tried;
	void *handle;
	check_format_fn check_format;
	encode_fn encode;
	verify_fn verify;
	char error[PATH_MAX + 128]; /* why it did not load */
} module;

static void *open_module(void)
{
	char path[PATH_MAX + 64];
	void *handle = NULL;

	if (libdir_find(MODULE_NAME, path, sizeof(path))) {
		snprintf(module.error, sizeof(module.error), "%s", path);
		return NULL;
	}
	handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
	if (!handle) {
		const char *why = dlerror();
		snprintf(module.error, sizeof(module.error), "%s", why ? why : path);
	}
	return handle;
}

/* Loads the module once; returns 0, or -1 (the reason in module.error). */
static int load(void)
{
	if (!module.tried) {
		module.tried = 1;
		module.handle = open_module();
		if (module.handle) {
			*(void **)&module.check_format =
				dlsym(module.handle, "image_backend_check_format");
			*(void **)&module.encode = dlsym(module.handle, "image_backend_encode");
			*(void **)&module.verify = dlsym(module.handle, "image_backend_verify");
			if (!module.check_format || !module.encode || !module.verify)
				snprintf(module.error, sizeof(module.error),
					 "%s lacks the backend's functions", MODULE_NAME);
		}
	}
	return module.handle && module.check_format && module.encode && module.verify ? 0 : -1;
}

int image_backend_check_format(const char *path, const char *ext, char *err, size_t err_size)
{
	if (load()) {
		image_set_error(err, err_size,
				"%s: cannot load OpenImageIO for \"%s\" files (%s); .ppm, .pfm and "
				".png need no OpenImageIO",
				path, ext, module.error);
		return -1;
	}
	return module.check_format(path, ext, err, err_size);
}

int image_backend_encode(const char *path, const char *tmp_path, int tmp_fd, const float *rgb,
			 int width, int height, const struct image_meta *meta, char *err,
			 size_t err_size)
{
	if (load()) {
		image_set_error(err, err_size, "%s: cannot load OpenImageIO (%s)", path,
				module.error);
		return -1;
	}
	return module.encode(path, tmp_path, tmp_fd, rgb, width, height, meta, err, err_size);
}

int image_backend_verify(const char *path, const char *tmp_path, int width, int height, char *err,
			 size_t err_size)
{
	if (load()) {
		image_set_error(err, err_size, "%s: cannot load OpenImageIO (%s)", path,
				module.error);
		return -1;
	}
	return module.verify(path, tmp_path, width, height, err, err_size);
}
