/* What the scheduling kernels share and nothing else uses: the scene block
 * loaded per work-group, the per-work-item counts, the global item index and
 * the chunk grid over the piece of the image being rendered (struct rt_piece).
 * Part of the tracer: built after walk.cl, before the kernel file (serial.cl,
 * naive.cl, ...). */

/* Copies the scene block into the work-group's __local memory when the scene
 * lives there, and returns the scene every work-item reads. Every work-item of
 * the group must call it (it contains a barrier). */
static scene_ptr load_scene(__global const uint4 *scene_global, __local uint4 *scene_local)
{
#ifdef RTCL_SCENE_IN_LOCAL
	uint words = ((__global const struct rt_scene *)scene_global)->total_bytes / 16;
	uint item = get_local_id(1) * get_local_size(0) + get_local_id(0);
	uint items = get_local_size(0) * get_local_size(1);

	for (uint i = item; i < words; i += items)
		scene_local[i] = scene_global[i];
	barrier(CLK_LOCAL_MEM_FENCE);
	return (scene_ptr)scene_local;
#else
	(void)scene_local;
	return (scene_ptr)scene_global;
#endif
}

/* Sets up the tracer of a single-pass kernel, whose counts buffer holds the
 * flops per pixel of the whole image, then RT_ITEM_COUNTS per work-item of
 * this launch (flops, rays, node visits): the pixels' place does not depend
 * on the launch's size. */
static void tracer_init_counts(struct tracer *tr, scene_ptr scene, __global ulong *counts)
{
	tracer_init(tr, scene, counts + (size_t)scene->width * scene->height, counts);
}

/* Stores what this work-item counted, once, at its end. */
static void store_counts(struct tracer *tr, uint item)
{
#ifdef RTCL_COUNT_FLOPS
	__global ulong *counts = tr->item_counts + RT_ITEM_COUNTS * item;

	counts[RT_ITEM_FLOPS] = tr->flops;
	counts[RT_ITEM_RAYS] = tr->rays;
	counts[RT_ITEM_NODE_VISITS] = tr->node_visits;
	counts[RT_ITEM_LEAF_VISITS] = tr->leaf_visits;
	counts[RT_ITEM_PRIM_TESTS] = tr->prim_tests;
	for (int p = 0; p < RT_SIMD_PHASES; p++) {
#ifdef RTCL_SIMD_MEASURE
		counts[RT_ITEM_LANE_STEPS(p)] = tr->lane_steps[p];
		counts[RT_ITEM_WARP_STEPS(p)] = tr->warp_steps[p];
#else
		counts[RT_ITEM_LANE_STEPS(p)] = counts[RT_ITEM_WARP_STEPS(p)] = 0;
#endif
	}
	for (int b = 0; b < RT_PATH_LENGTH_BINS; b++) {
#ifdef RTCL_PATH
		counts[RT_ITEM_PATH_LENGTHS + b] = tr->path_lengths[b];
#else
		counts[RT_ITEM_PATH_LENGTHS + b] = 0;
#endif
	}
#ifdef RTCL_PATH
	counts[RT_ITEM_PATH_MAX] = tr->path_max;
	counts[RT_ITEM_PATH_SEGMENTS] = tr->path_segments;
#else
	counts[RT_ITEM_PATH_MAX] = counts[RT_ITEM_PATH_SEGMENTS] = 0;
#endif
#else
	(void)tr;
	(void)item;
#endif
}

/* With RTCL_PROGRESS (a progress line on the host's terminal): adds the
 * pixels of finished chunks to the work counter's RT_COUNTER_DONE word, which
 * the host reads during the launch. At most one atomic per chunk, from the
 * group's first work-item, so that counting costs next to nothing against
 * tracing; nothing without RTCL_PROGRESS. */
static inline void progress_chunk_done(__global uint *work_counter, uint pixels)
{
#ifdef RTCL_PROGRESS
	if (get_local_id(0) == 0 && get_local_id(1) == 0)
		atomic_add(work_counter + RT_COUNTER_DONE, pixels);
#else
	(void)work_counter;
	(void)pixels;
#endif
}

/* Returns this work-item's index, row-major over the global NDRange: where
 * it stores its counts. */
static inline uint global_item(void)
{
	return get_global_id(1) * get_global_size(0) + get_global_id(0);
}

/* The piece's rectangle cut into chunks of the work-group's shape, the unit
 * of work the scheduling kernels hand out. The chunks at the right and bottom
 * edges may reach past the rectangle; their pixels outside it are skipped. */
struct chunk_grid {
	uint chunk_w, chunk_h; /* a chunk's size in pixels: the work-group's */
	uint across, down;     /* chunks per row and per column */
	int x0, y0;	       /* the rectangle's top-left pixel */
};

static inline struct chunk_grid chunk_grid(const struct rt_piece *piece)
{
	struct chunk_grid g;

	g.chunk_w = get_local_size(0);
	g.chunk_h = get_local_size(1);
	g.across = ((uint)piece->width + g.chunk_w - 1) / g.chunk_w;
	g.down = ((uint)piece->height + g.chunk_h - 1) / g.chunk_h;
	g.x0 = piece->x0;
	g.y0 = piece->y0;
	return g;
}

/* Returns the number of chunks, numbered row-major from 0. */
static inline uint chunk_count(const struct chunk_grid *g)
{
	return g->across * g->down;
}

/* Returns pixel (dx, dy) of the chunk in column cx and row cy of the grid:
 * its image column and split row (rt_piece_row). */
static inline int2 chunk_pixel(const struct chunk_grid *g, uint cx, uint cy, uint dx, uint dy)
{
	return (int2)(g->x0 + (int)(cx * g->chunk_w + dx), g->y0 + (int)(cy * g->chunk_h + dy));
}

/* Returns pixel (dx, dy) of chunk number chunk. */
static inline int2 numbered_chunk_pixel(const struct chunk_grid *g, uint chunk, uint dx, uint dy)
{
	return chunk_pixel(g, chunk % g->across, chunk / g->across, dx, dy);
}

/* Traces and stores pixel p (x and the split row, rt_piece_row) if it lies
 * inside the piece's rectangle. */
static inline void render_pixel_if_inside(struct tracer *tr, const struct rt_piece *piece,
					  __global float *image, __global long *sums,
					  __global uint *probe, int2 p)
{
	if (p.x < piece->x0 + piece->width && p.y < piece->y0 + piece->height)
		render_pixel(tr, piece, image, sums, probe, p.x, rt_piece_row(piece, p.y));
}
