/* The single-pass renderer (serial, naive, cyclic, dynamic, persistent). */
#ifndef RTCL_SINGLEPASS_H
#define RTCL_SINGLEPASS_H

#include "render/renderer.h"

/* renderer.h's functions for the kernels that render a piece in one launch
 * of cl/KERNEL.cl's `render`. */
extern const struct renderer_ops singlepass_ops;

#endif
