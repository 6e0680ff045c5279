/* rtcl's version and exit statuses, which every layer may report. */
#ifndef RTCL_VERSION_H
#define RTCL_VERSION_H

#define RTCL_VERSION "0.1.0"

/* Exit statuses. */
#define EXIT_USAGE 2  /* a bad option, or outputs that name one file */
#define EXIT_FAILED 1 /* a bad scene, a device, build or file error */

#endif
