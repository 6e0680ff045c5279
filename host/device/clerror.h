/* OpenCL error codes as names (CL_OUT_OF_RESOURCES, never -5). */
#ifndef RTCL_CLERROR_H
#define RTCL_CLERROR_H

#ifndef CL_TARGET_OPENCL_VERSION
#define CL_TARGET_OPENCL_VERSION 120
#endif
#include <CL/cl.h>

#ifndef CL_PLATFORM_NOT_FOUND_KHR
#define CL_PLATFORM_NOT_FOUND_KHR -1001 /* cl_khr_icd, from CL/cl_ext.h */
#endif

/* Returns the name of an OpenCL error code, e.g. "CL_OUT_OF_RESOURCES", or
 * "unknown OpenCL error" for a code no version of the standard defines. */
const char *cl_error_name(cl_int code);

#endif
