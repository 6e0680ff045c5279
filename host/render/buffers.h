/* What both renderers (singlepass.c, wavefront.c) hold for the whole image,
 * and the steps they take alike: creating the buffers, clearing the counts
 * before the first piece, adding up a launch's per-work-item counts, reading
 * the image and the counts back, releasing. Each renderer keeps its kernels
 * and launch buffers around this, behind renderer_ops (renderer.h). */
#ifndef RTCL_BUFFERS_H
#define RTCL_BUFFERS_H

#include "render/checks.h"
#include "render/probe.h"

/* What the counting build counts per work-item besides its flops
 * (RT_ITEM_*), summed. */
struct trace_counts {
	uint64_t rays, node_visits, leaf_visits, prim_tests;
	uint64_t lane_steps[RT_SIMD_PHASES], warp_steps[RT_SIMD_PHASES]; /* simd_measured */
	struct path_counts paths; /* under the path integrator */
};

struct render_buffers {
	cl_program program;
	void *scene_block; /* the packed scene but its texels (launch_setup), till buffers_create */
	cl_mem scene;
	struct guarded_image image;
	cl_mem sums;	      /* each pixel's fixed-point sum of its samples' colours
				 between passes, 4 cl_long (samples > 1; cl/sample.cl) */
	cl_mem flops;	      /* the per-pixel flop counts at its head (count_flops) */
	cl_mem probe;	      /* write counts or the schedule map (probe.h) */
	uint64_t *item_flops; /* per work-item, as the renderer lays them out */
	size_t item_count;
	struct trace_counts counts; /* summed over every work-item read back */
};

/* Creates the scene buffer from b->scene_block (freed then: the device
 * holds it) and the scene's texels, the image, the flop-count buffer
 * `flops_what` of flops_bytes (a placeholder without count_flops) and the
 * write counts, and places them all on the device before it returns.
 * Returns 0, or -1 with one message in err. */
int buffers_create(struct device *dev, const struct scene *scene, const struct render_settings *s,
		   const struct render_result *res, struct render_buffers *b, size_t flops_bytes,
		   const char *flops_what, char *err, size_t err_size);

/* Zeroes the per-pixel flop counts and, with check_writes, poisons the image:
 * the pieces add to what the buffers hold. Returns 0, or -1 with one message
 * in err. */
int buffers_clear(struct device *dev, const struct render_settings *s, struct render_buffers *b,
		  char *err, size_t err_size);

/* Reads the counts of `items` work-items (RT_ITEM_COUNTS each) from `from` at
 * byte `offset`, adds their flops to flops[0 .. items) and their rays and node
 * visits to b's sums. */
cl_int buffers_add_item_counts(struct device *dev, struct render_buffers *b, cl_mem from,
			       size_t offset, size_t items, uint64_t *flops);

/* Appends the counts of a launch's `items` work-items, read from `from`, to
 * b's per-work-item flops (b->item_flops, grown as needed: *alloc is its
 * room), as the wavefront's launches do one after the other. The new
 * entries are zeroed first, since buffers_add_item_counts adds (a retried
 * sample appends over the attempt it drops). */
cl_int buffers_append_item_counts(struct device *dev, struct render_buffers *b, cl_mem from,
				  size_t items, size_t *alloc);

/* Reads the image into res->rgb and, when counting, the per-pixel flops and
 * the per-work-item sums (handed over to res), when checking, the write
 * counts and guard zones. Returns 0, or -1 with one message in err. */
int buffers_read_back(struct device *dev, const struct render_settings *s, struct render_buffers *b,
		      struct render_result *res, char *err, size_t err_size);

/* Reads piece's pixels (its rectangle of split rows, rt_piece_row) from the
 * device's image into to: at their places in an image of the render's size,
 * or packed, row after row of the piece (packed != 0). One read per run of
 * rows that lie one after another in the image. Returns 0, or -1 with one
 * message in err. */
int buffers_read_rows(struct device *dev, const struct render_settings *s,
		      const struct render_buffers *b, const struct rt_piece *piece, float *to,
		      int packed, char *err, size_t err_size);

/* Reads the fixed-point sums (4 cl_long a pixel, cl/sample.cl) of pixels
 * [first, first + count) into the same places of to, a host copy of every
 * pixel's: what the passes of a piece whose samples are split between
 * devices leave (rt_piece.sum_begin). With event NULL the read is done on
 * return; else it is only enqueued (and flushed), *event says when it is
 * done, and the caller releases it. Returns 0, or -1 with one message in
 * err. */
int buffers_read_sums(struct device *dev, const struct render_buffers *b, cl_long *to,
		      size_t first, size_t count, cl_event *event, char *err, size_t err_size);

/* Releases what b holds, the program last. */
void buffers_release(struct render_buffers *b);

#endif
