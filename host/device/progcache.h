/* rtcl's cache of built OpenCL programs: the binary of each build
 * (CL_PROGRAM_BINARIES) under $XDG_CACHE_HOME/rtcl (default ~/.cache/rtcl),
 * named by a hash of everything that changes it: the platform, the device and
 * its driver and OpenCL versions, rtcl's version, every source text, the
 * build options and PoCL's build settings from the environment
 * (POCL_EXTRA_BUILD_FLAGS, POCL_WORK_GROUP_SPECIALIZATION). RTCL_CACHE=0
 * turns it off. Any trouble with the cache (a
 * missing, short, corrupt or foreign file, a device that refuses the binary,
 * a folder that cannot be written) means a build from source, never an
 * error; with -v it is said once on stderr. */
#ifndef RTCL_PROGCACHE_H
#define RTCL_PROGCACHE_H

#include <stdint.h>

#include "device/device.h"

struct progcache {
	int enabled;
	int verbose;
	uint64_t key;	     /* the hash of the build's inputs */
	const char *options; /* the build options, kept: a binary is built with them too */
	char path[4096]; /* DIR/KEY.bin; empty when there is no folder to use */
};

/* Works out the build's key and the cache file's path. */
void progcache_init(struct progcache *cache, const struct device *dev, const char *const *texts,
		    int count, const char *options, int verbose);

/* A program made from the cached binary and built with the same options as
 * from source, or NULL (none cached, or it did not load: then the caller
 * builds from source). The options matter for a binary too: NVIDIA's is PTX,
 * whose compilation to the GPU's code reads them (-cl-nv-maxrregcount); a
 * cached program built without them ran 7-16 % slower on an H200 (batch 59,
 * docs/results/multidevice). */
cl_program progcache_load(const struct progcache *cache, const struct device *dev);

/* Saves the binary of a program built from source; failures are only
 * reported with -v. */
void progcache_save(const struct progcache *cache, cl_program program);

#endif
