/* The stages form of the wavefront under the path integrator
 * (--wavefront-form stages; cl/wavefront.cl's stages_* kernels,
 * docs/wavefront.md "The stages form"). */
#ifndef RTCL_STAGES_H
#define RTCL_STAGES_H

#include "render/renderer.h"

/* The pool of path slots when --paths-in-flight is not given
 * (docs/wavefront.md, "Path state"): on a GPU 2^22 (four H200s' GPU 0,
 * batch 103: the fastest of 2^18-2^23 on the Cornell box and the
 * materials scene, 16 % and 18 % faster than 2^20); on a CPU 2^15 a
 * compute unit, which keep the state in its caches (PoCL on 2 cores: 2^14
 * and 2^16 a pool 1.9 times faster than 2^20). Halved while the pool would
 * take more than an eighth of the device's memory or its state buffer more
 * than the device allocates at once, down to STAGES_LEAST_DEFAULT; never
 * more than the paths of the whole render. */
#define STAGES_GPU_PATHS (1 << 22)
#define STAGES_CPU_PATHS_PER_UNIT (1 << 15)
#define STAGES_LEAST_DEFAULT (1 << 14)
/* The most --paths-in-flight takes: 2^26 slots are 10 GiB of path state. */
#define STAGES_MAX_PATHS (1 << 26)

/* Device memory a path slot takes: its state and its queue entries. */
#define STAGES_PATH_BYTES (RT_STAGE_FIELDS * 16 + RT_STAGE_QUEUES * 4)

/* The pool of path slots for a render of `paths` paths on dev when
 * --paths-in-flight is not given (the rule above). */
unsigned stages_default_paths(const struct device *dev, unsigned long long paths);

/* The launches of the stages form, in the order of an iteration. */
enum stage {
	STAGE_BEGIN,
	STAGE_LOGIC,
	STAGE_NEW_PATH,
	STAGE_ADVANCE, /* one work-item: the paths handed out */
	STAGE_SHADE_MAPPED, /* + RT_BSDF_*: one per BSDF kind */
	STAGE_SHADE_DIFFUSE,
	STAGE_SHADE_CONDUCTOR,
	STAGE_SHADE_DIELECTRIC,
	STAGE_SHADE_PRINCIPLED,
	STAGE_EXTEND,
	STAGE_SHADOW,
	STAGE_FINISH,
	STAGE_COUNT
};

/* What --stats reports of the stages form (render_result.stages), summed
 * over every piece and frame since open. */
struct stages_stats {
	int slots;				 /* the pool of path slots */
	int launches[STAGE_COUNT];		 /* of each kernel */
	double ms[STAGE_COUNT];			 /* their profiled time */
	uint64_t items[STAGE_COUNT];		 /* the work-items that had work */
	uint64_t state_bytes[STAGE_COUNT];	 /* path state they read and wrote, at
						    most (stages_item_bytes) */
	/* Per iteration of the last frame (from its piece that begins at
	 * sample 0): the paths the logic kernel queued for shading (live), the
	 * new paths started, the segments and shadow rays traced. */
	int iterations, iteration_alloc;
	uint32_t *live, *started, *extended, *shadowed;
};

/* The name of a stage in --stats ("logic", "shade_diffuse", ...). */
const char *stages_name(enum stage stage);

/* The bytes of path state and queue entries a work-item of stage reads and
 * writes at most (docs/wavefront.md, "The stages form"). */
int stages_item_bytes(enum stage stage);

void stages_stats_free(struct stages_stats *stats);

/* renderer.h's functions for the stages form. */
extern const struct renderer_ops stages_ops;

#endif
