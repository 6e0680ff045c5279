/* What the scheduling kernels share and nothing else uses: the scene block
 * loaded per work-group, the per-work-item counts, the global item index and
 * the chunk grid. Part of the tracer: built after walk.cl, before the kernel
 * file (serial.cl, naive.cl, ...). */

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

/* Stores what this work-item counted, once, at its end. */
static void store_counts(struct tracer *tr, __global ulong *counts, uint item)
{
#ifdef RTCL_COUNT_FLOPS
	counts[RT_ITEM_COUNTS * item] = tr->flops;
	counts[RT_ITEM_COUNTS * item + 1] = tr->rays;
	counts[RT_ITEM_COUNTS * item + 2] = tr->node_visits;
#else
	(void)tr;
	(void)counts;
	(void)item;
#endif
}

/* Returns this work-item's index, row-major over the global NDRange: where
 * it stores its counts. */
static inline uint global_item(void)
{
	return get_global_id(1) * get_global_size(0) + get_global_id(0);
}

/* The image cut into chunks of the work-group's shape, the unit of work the
 * scheduling kernels hand out. The chunks at the right and bottom edges may
 * reach past the image; their pixels outside it are skipped. */
struct chunk_grid {
	uint chunk_w, chunk_h; /* a chunk's size in pixels: the work-group's */
	uint across, down;     /* chunks per row and per column */
};

static inline struct chunk_grid chunk_grid(scene_ptr scene)
{
	struct chunk_grid g;

	g.chunk_w = get_local_size(0);
	g.chunk_h = get_local_size(1);
	g.across = (scene->width + g.chunk_w - 1) / g.chunk_w;
	g.down = (scene->height + g.chunk_h - 1) / g.chunk_h;
	return g;
}

/* Returns the number of chunks, numbered row-major from 0. */
static inline uint chunk_count(const struct chunk_grid *g)
{
	return g->across * g->down;
}

/* Returns pixel (dx, dy) of the chunk in column cx and row cy of the grid. */
static inline int2 chunk_pixel(const struct chunk_grid *g, uint cx, uint cy, uint dx, uint dy)
{
	return (int2)(cx * g->chunk_w + dx, cy * g->chunk_h + dy);
}

/* Returns pixel (dx, dy) of chunk number chunk. */
static inline int2 numbered_chunk_pixel(const struct chunk_grid *g, uint chunk, uint dx, uint dy)
{
	return chunk_pixel(g, chunk % g->across, chunk / g->across, dx, dy);
}

/* Traces and stores pixel p if it lies inside the image. */
static inline void render_pixel_if_inside(struct tracer *tr, __global float *image,
					  __global uint *write_counts, int2 p)
{
	if (p.x < tr->scene->width && p.y < tr->scene->height)
		render_pixel(tr, image, write_counts, p.x, p.y);
}
