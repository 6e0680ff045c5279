/* Files embedded into the binary at build time (tools/build/embed.py writes
 * build/embedded.c): the OpenCL sources of cl/ and the default scene. */
#ifndef RTCL_EMBEDDED_H
#define RTCL_EMBEDDED_H

/* Returns the text of the embedded file with this base name (e.g.
 * "tracer.cl", "paper60.json"), or NULL. */
const char *embedded_file(const char *name);

#endif
