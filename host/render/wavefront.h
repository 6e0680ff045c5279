/* The multi-pass wavefront renderer (cl/wavefront.cl). */
#ifndef RTCL_WAVEFRONT_H
#define RTCL_WAVEFRONT_H

#include "render/renderer.h"

/* renderer.h's functions for the wavefront: per sample of a piece, one launch
 * for the primary rays, one per bounce over a queue of live rays, and one
 * that adds the sample to the image. */
extern const struct renderer_ops wavefront_ops;

#endif
