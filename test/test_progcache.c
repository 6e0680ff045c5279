/* The program cache (host/device/progcache.h) on the first OpenCL device
 * (PoCL in CI): a program loaded from the cache is built with the options of
 * the build from source. NVIDIA's binary is PTX, compiled to the GPU's code
 * when the binary is built; built without the options (-cl-nv-maxrregcount
 * among them) it ran 7-16 % slower on an H200 (docs/results/multidevice,
 * batch 59). */
#include <criterion/criterion.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "device/device.h"
#include "device/progcache.h"

static const char *source = "kernel void k(global int *a) { a[0] = SEVEN; }\n";
static const char *options = "-cl-std=CL1.2 -DSEVEN=7";

static char *program_options(cl_program program, cl_device_id id)
{
	static char text[4096];
	size_t size = 0;

	text[0] = '\0';
	cr_assert_eq(clGetProgramBuildInfo(program, id, CL_PROGRAM_BUILD_OPTIONS, sizeof(text),
					   text, &size),
		     CL_SUCCESS);
	return text;
}

Test(progcache, a_cached_program_is_built_with_the_options_of_the_source_build)
{
	char err[4096], home[] = "/tmp/rtcl-progcache-XXXXXX";
	struct device dev;
	struct progcache cache;
	cl_int status;

	cr_assert_not_null(mkdtemp(home));
	setenv("XDG_CACHE_HOME", home, 1);
	unsetenv("RTCL_CACHE");
	cr_assert_eq(device_open(&dev, -1, -1, err, sizeof(err)), 0, "%s", err);
	progcache_init(&cache, &dev, &source, 1, options, 0);
	cr_assert_null(progcache_load(&cache, &dev), "nothing is cached yet");

	cl_program built = clCreateProgramWithSource(dev.context, 1, &source, NULL, &status);
	cr_assert_eq(status, CL_SUCCESS);
	cr_assert_eq(clBuildProgram(built, 1, &dev.id, options, NULL, NULL), CL_SUCCESS);
	progcache_save(&cache, built);
	clReleaseProgram(built);

	cl_program loaded = progcache_load(&cache, &dev);
	cr_assert_not_null(loaded, "the saved binary loads");
	/* PoCL may add its own (POCL_EXTRA_BUILD_FLAGS: make test's
	 * -cl-opt-disable) after ours; without ours it reports none of them. */
	const char *reported = program_options(loaded, dev.id);
	cr_expect(strncmp(reported, options, strlen(options)) == 0,
		  "the cached program was built with \"%s\", not \"%s\"", reported, options);
	clReleaseProgram(loaded);
	device_close(&dev);
	char command[256];
	snprintf(command, sizeof(command), "rm -rf '%s'", home);
	cr_expect_eq(system(command), 0);
}
