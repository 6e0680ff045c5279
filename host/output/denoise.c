/* --denoise through Intel Open Image Denoise's C API (oidn.h, 2.x), loaded
 * with dlopen: Debian 12 has no package of it, and the library with its TBB
 * and device modules is some 90 MB that a run without --denoise should not
 * load. Only the few functions and constants below are used; they are
 * declared here rather than from oidn.h, which is not installed. */
#include "output/denoise.h"

#include <dlfcn.h>
#include <limits.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "base/test_hooks.h"

#ifndef RTCL_OIDN_DIR
#define RTCL_OIDN_DIR "/usr/local/lib/rtcl-oidn"
#endif
/* Where the pyoidn wheel keeps the library under its pip --target folder. */
#define OIDN_WHEEL_LIB RTCL_OIDN_DIR "/pyoidn/oidn/lib/libOpenImageDenoise.so.2"
#define OIDN_SONAME "libOpenImageDenoise.so.2"

/* oidn.h's values. */
#define OIDN_DEVICE_TYPE_CPU 1
#define OIDN_FORMAT_FLOAT3 3
#define OIDN_ERROR_NONE 0

typedef void *oidn_handle;

static struct {
	int tried;
	void *handle;
	oidn_handle (*new_device)(int type);
	void (*commit_device)(oidn_handle device);
	int (*get_device_error)(oidn_handle device, const char **message);
	void (*release_device)(oidn_handle device);
	oidn_handle (*new_filter)(oidn_handle device, const char *type);
	void (*set_shared_image)(oidn_handle filter, const char *name, void *ptr, int format,
				 size_t width, size_t height, size_t byte_offset,
				 size_t pixel_byte_stride, size_t row_byte_stride);
	void (*set_bool)(oidn_handle filter, const char *name, bool value);
	void (*commit_filter)(oidn_handle filter);
	void (*execute_filter)(oidn_handle filter);
	void (*release_filter)(oidn_handle filter);
	char error[PATH_MAX + 256];
} oidn;

/* Opens the library: $RTCL_OIDN_LIBRARY alone when set, else the copy
 * `make deps` installs, else the soname. */
static void *open_library(void)
{
	const char *given = getenv("RTCL_OIDN_LIBRARY");
	void *handle;

	if (given && *given) {
		handle = dlopen(given, RTLD_NOW | RTLD_LOCAL);
		if (!handle)
			snprintf(oidn.error, sizeof(oidn.error), "RTCL_OIDN_LIBRARY: %s",
				 dlerror());
		return handle;
	}
	handle = dlopen(OIDN_WHEEL_LIB, RTLD_NOW | RTLD_LOCAL);
	if (!handle)
		handle = dlopen(OIDN_SONAME, RTLD_NOW | RTLD_LOCAL);
	if (!handle)
		snprintf(oidn.error, sizeof(oidn.error), "looked for %s and %s: %s", OIDN_WHEEL_LIB,
			 OIDN_SONAME, dlerror());
	return handle;
}

/* Looks up symbol name into *fn; returns 0, or -1 naming it in oidn.error. */
static int take(void **fn, const char *name)
{
	*fn = dlsym(oidn.handle, name);
	if (!*fn)
		snprintf(oidn.error, sizeof(oidn.error),
			 "the library lacks %s (Open Image Denoise 2.x is needed)", name);
	return *fn ? 0 : -1;
}

static int load(void)
{
	if (oidn.tried)
		return oidn.handle ? 0 : -1;
	oidn.tried = 1;
	oidn.handle = open_library();
	if (!oidn.handle)
		return -1;
	if (take((void **)&oidn.new_device, "oidnNewDevice") ||
	    take((void **)&oidn.commit_device, "oidnCommitDevice") ||
	    take((void **)&oidn.get_device_error, "oidnGetDeviceError") ||
	    take((void **)&oidn.release_device, "oidnReleaseDevice") ||
	    take((void **)&oidn.new_filter, "oidnNewFilter") ||
	    take((void **)&oidn.set_shared_image, "oidnSetSharedFilterImage") ||
	    take((void **)&oidn.set_bool, "oidnSetFilterBool") ||
	    take((void **)&oidn.commit_filter, "oidnCommitFilter") ||
	    take((void **)&oidn.execute_filter, "oidnExecuteFilter") ||
	    take((void **)&oidn.release_filter, "oidnReleaseFilter")) {
		dlclose(oidn.handle);
		oidn.handle = NULL;
		return -1;
	}
	return 0;
}

int denoise_load(char *err, size_t err_size)
{
	if (load() == 0)
		return 0;
	snprintf(err, err_size,
		 "--denoise: cannot load Intel Open Image Denoise (%s); `make deps` installs "
		 "it (pip's pyoidn wheel in %s), or set RTCL_OIDN_LIBRARY to a "
		 "libOpenImageDenoise.so.2",
		 oidn.error, RTCL_OIDN_DIR);
	return -1;
}

/* Returns 0, or -1 with the device's error in err. */
static int check_device(oidn_handle device, const char *step, char *err, size_t err_size)
{
	const char *message = NULL;
	int code = oidn.get_device_error(device, &message);

	if (code == OIDN_ERROR_NONE)
		return 0;
	snprintf(err, err_size, "--denoise: Open Image Denoise failed to %s (error %d: %s)", step,
		 code, message && *message ? message : "no message");
	return -1;
}

int denoise_image(float *rgb, const float *albedo, const float *normal, int width, int height,
		  char *err, size_t err_size)
{
	size_t w = (size_t)width, h = (size_t)height, pixel = 3 * sizeof(float);
	oidn_handle device, filter;
	int ret = -1;

	if (denoise_load(err, err_size))
		return -1;
	device = oidn.new_device(OIDN_DEVICE_TYPE_CPU);
	if (!device) {
		snprintf(err, err_size, "--denoise: Open Image Denoise has no CPU device here");
		return -1;
	}
	oidn.commit_device(device);
	if (check_device(device, "start its CPU device", err, err_size))
		goto out_release_device;
	filter = oidn.new_filter(device, hook_oidn_filter() ? hook_oidn_filter() : "RT");
	if (check_device(device, "create its RT filter", err, err_size))
		goto out_release_device;
	/* The auxiliary images are const here; OIDN only reads its inputs. */
	oidn.set_shared_image(filter, "color", rgb, OIDN_FORMAT_FLOAT3, w, h, 0, pixel, 0);
	oidn.set_shared_image(filter, "albedo", (void *)albedo, OIDN_FORMAT_FLOAT3, w, h, 0, pixel,
			      0);
	oidn.set_shared_image(filter, "normal", (void *)normal, OIDN_FORMAT_FLOAT3, w, h, 0, pixel,
			      0);
	oidn.set_shared_image(filter, "output", rgb, OIDN_FORMAT_FLOAT3, w, h, 0, pixel, 0);
	oidn.set_bool(filter, "hdr", true);
	/* Averaged over the pixel's samples, the auxiliary images are free of
	 * noise but for edges: cleanAux keeps OIDN from blurring them. */
	oidn.set_bool(filter, "cleanAux", true);
	oidn.commit_filter(filter);
	if (check_device(device, "set up its RT filter", err, err_size))
		goto out_release_filter;
	oidn.execute_filter(filter);
	if (check_device(device, "denoise the image", err, err_size))
		goto out_release_filter;
	ret = 0;

out_release_filter:
	oidn.release_filter(filter);
out_release_device:
	oidn.release_device(device);
	return ret;
}
