/* Companion files beside the program or in the build folder (libdir.h). */
#include "base/libdir.h"

#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#ifndef PATH_MAX
#define PATH_MAX 4096
#endif

/* PATH of the installed NAME, from where this program lies (Linux's
 * /proc/self/exe; elsewhere only the build folder is looked in). */
static int installed_path(const char *name, char *path, size_t size)
{
	char exe[PATH_MAX];
	ssize_t n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
	char *slash;

	if (n <= 0)
		return -1;
	exe[n] = '\0';
	slash = strrchr(exe, '/');
	if (!slash)
		return -1;
	*slash = '\0';
	return snprintf(path, size, "%s/../lib/rtcl/%s", exe, name) < (int)size ? 0 : -1;
}

int libdir_find(const char *name, char *path, size_t size)
{
	if (installed_path(name, path, size) == 0 && access(path, F_OK) == 0)
		return 0;
	if (snprintf(path, size, "%s/%s", RTCL_MODULE_DIR, name) < (int)size &&
	    access(path, F_OK) == 0)
		return 0;
	snprintf(path, size, "%s is neither in ../lib/rtcl beside rtcl nor in the build folder %s",
		 name, RTCL_MODULE_DIR);
	return -1;
}
