/* persistent: the "fully dynamic" scheduling the paper thought impossible on a
 * GPU. Persistent work-groups whose work-items each fetch their own work from a
 * global counter with atomic_add, RTCL_BATCH pixels at a time, with no barrier
 * and no lock: a work-item that drew cheap pixels simply fetches again, while
 * its neighbours are still tracing. (Aila & Laine 2009 fetch per warp through
 * a __local batch; OpenCL C 1.2 has no sub-groups, so each work-item fetches
 * for itself.)
 *
 * Pixels are numbered through the chunks of the work-group's shape, row-major
 * within a chunk and chunks in row-major order, so that work-items fetching at
 * the same time trace neighbouring pixels. Numbers that fall outside the image
 * (partial chunks at the right and bottom edges) are skipped. The host resets
 * next_pixel_counter, the number of the next pixel to hand out, to 0 before
 * every launch; it is the work counter's word RT_COUNTER_NEXT, which the host
 * also reads for the progress line (the pixels handed out). */
#ifndef RTCL_BATCH
#define RTCL_BATCH 1
#endif

#ifdef RTCL_REFILL
/* Refill (issue 25, a lane-aware trial; RTCL_BUILD_OPTIONS=-DRTCL_REFILL):
 * each work-item steps its pixel's walk one intersection at a time
 * (walk_step) and, the moment its pixel is done, fetches the next one and goes
 * on, so that its warp's other lanes never wait at the end of a pixel for the
 * longest one. One pixel per fetch (RTCL_BATCH is not read). The same
 * functions as render_pixel, in the same order for each pixel: the same image
 * and counts. */

/* Fetches the next pixel inside the piece into *p; false when none is left. */
static bool fetch_pixel(__global uint *counter, const struct chunk_grid *grid,
			const struct rt_piece *piece, uint pixels, int2 *p)
{
	uint chunk_pixels = grid->chunk_w * grid->chunk_h;

	for (uint i = atomic_inc(counter); i < pixels; i = atomic_inc(counter)) {
		uint within = i % chunk_pixels;
		*p = numbered_chunk_pixel(grid, i / chunk_pixels, within % grid->chunk_w,
					  within / grid->chunk_w);
		if (p->x < piece->x0 + piece->width && p->y < piece->y0 + piece->height)
			return true;
	}
	return false;
}

/* A pixel being traced: render_pixel's state, kept across fetches. */
struct pixel_state {
	int2 p;
	int pixel;
	int k; /* its sample being walked */
	float3 sum;
	ulong flops_before;
};

/* Starts pixel ps->p: render_pixel's opening, then its first sample's walk. */
static void pixel_begin(struct tracer *tr, const struct rt_piece *piece, __global float *image,
			__global uint *probe, struct pixel_state *ps, struct walk *w)
{
	int x = ps->p.x, y = ps->p.y;

	ps->pixel = y * tr->scene->width + x;
	ps->flops_before = tracer_flops(tr);
	record_schedule(probe, ps->pixel, tr->scene->width * tr->scene->height, piece);
#ifdef RTCL_ONE_SAMPLE
	walk_start(tr, w, x, y, (float2)(0.5f));
#else
	ps->sum = piece->sample_begin > 0 ? vload3(ps->pixel, image) : (float3)(0.0f);
	ps->k = piece->sample_begin;
	walk_start(tr, w, x, y, sample_offset(tr, x, y, ps->k, piece->samples));
#endif
}

/* A walk of ps is done: on to its next sample (returns false), or stores the
 * pixel as render_pixel does (returns true). */
static bool pixel_sample_done(struct tracer *tr, const struct rt_piece *piece,
			      __global float *image, __global uint *probe, struct pixel_state *ps,
			      struct walk *w)
{
#ifdef RTCL_ONE_SAMPLE
	vstore3(w->color, ps->pixel, image);
#else
	ps->sum = sample_add(tr, ps->sum, w->color, ps->k);
	if (++ps->k < piece->sample_end) {
		walk_start(tr, w, ps->p.x, ps->p.y,
			   sample_offset(tr, ps->p.x, ps->p.y, ps->k, piece->samples));
		return false;
	}
	vstore3(sample_finish(tr, ps->sum, piece), ps->pixel, image);
#endif
	count_pixel_flops(tr->pixel_flops, ps->pixel, tracer_flops(tr) - ps->flops_before);
	count_write(probe, ps->pixel);
	return true;
}

__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global uint *next_pixel_counter,
		     __global ulong *counts, __global uint *probe, struct rt_piece piece)
{
	struct tracer tr;
	struct walk w;
	struct ray_job waiting[RAY_STACK_SIZE];
	struct pixel_state ps;

	tracer_init_counts(&tr, load_scene(scene_global, scene_local), counts);
	struct chunk_grid grid = chunk_grid(&piece);
	uint pixels = chunk_count(&grid) * grid.chunk_w * grid.chunk_h;
	bool busy = fetch_pixel(next_pixel_counter, &grid, &piece, pixels, &ps.p);

	if (busy)
		pixel_begin(&tr, &piece, image, probe, &ps, &w);
	while (busy) {
		if (!walk_step(&tr, &w, waiting) ||
		    !pixel_sample_done(&tr, &piece, image, probe, &ps, &w))
			continue;
		busy = fetch_pixel(next_pixel_counter, &grid, &piece, pixels, &ps.p);
		if (busy)
			pixel_begin(&tr, &piece, image, probe, &ps, &w);
	}
	store_counts(&tr, global_item());
}
#else
__kernel void render(__global const uint4 *scene_global, __local uint4 *scene_local,
		     __global float *image, __global uint *next_pixel_counter,
		     __global ulong *counts, __global uint *probe, struct rt_piece piece)
{
	struct tracer tr;

	tracer_init_counts(&tr, load_scene(scene_global, scene_local), counts);
	struct chunk_grid grid = chunk_grid(&piece);
	uint chunk_pixels = grid.chunk_w * grid.chunk_h;
	uint pixels = chunk_count(&grid) * chunk_pixels; /* the edge chunks' overhang included */

	for (uint first = atomic_add(next_pixel_counter, RTCL_BATCH); first < pixels;
	     first = atomic_add(next_pixel_counter, RTCL_BATCH)) {
		uint end = min(first + RTCL_BATCH, pixels);
		for (uint i = first; i < end; i++) {
			uint within = i % chunk_pixels;
			render_pixel_if_inside(&tr, &piece, image, probe,
					       numbered_chunk_pixel(&grid, i / chunk_pixels,
								    within % grid.chunk_w,
								    within / grid.chunk_w));
		}
	}
	store_counts(&tr, global_item());
}
#endif
