/* wavefront: every path broken into pieces (the paper's Figure 4). Rays wait in
 * a queue in global memory; each launch of wavefront_bounce traces one bounce
 * of every live ray (intersection, local shading with its shadow rays) and
 * appends the reflected and refracted rays it spawns to the next queue with an
 * atomic counter. The host launches bounces until the queue is empty or
 * max_depth is reached. Work-items take rays, not pixels, so a pixel's cost is
 * spread over as many work-items as its tree has rays.
 *
 * Contributions are added to the pixel with a compare-and-swap loop (OpenCL C
 * 1.2 has no float atomics). The order of the additions for one pixel is not
 * fixed, unlike the stack walk's, so the float sum may differ in its last bits
 * from the other kernels' (see docs/wavefront.md). */
#ifdef RTCL_COUNT_FLOPS
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#endif

/* Adds flops to pixel's cost, when counting: the work-items of several
 * bounces trace rays of one pixel. */
static void add_pixel_flops(__global ulong *pixel_flops, int pixel, ulong flops)
{
#ifdef RTCL_COUNT_FLOPS
	atom_add(&pixel_flops[pixel], flops);
#else
	(void)pixel_flops;
	(void)pixel;
	(void)flops;
#endif
}

/* *p += value, atomically. */
static void atomic_add_float(volatile __global float *p, float value)
{
	union {
		uint bits;
		float value;
	} seen, sum;

	do {
		seen.value = *p;
		sum.value = seen.value + value;
	} while (atomic_cmpxchg((volatile __global uint *)p, seen.bits, sum.bits) != seen.bits);
}

static void add_to_pixel(__global float *image, int pixel, float3 color)
{
	atomic_add_float(&image[3 * pixel], color.x);
	atomic_add_float(&image[3 * pixel + 1], color.y);
	atomic_add_float(&image[3 * pixel + 2], color.z);
}

static void store_ray(__global struct rt_ray *queue, uint slot, const struct ray_job *ray,
		      int pixel)
{
	/* The weight rides in the origin's w lane (ray_weight); a colour's
	 * other channels in weight_green and weight_blue. */
#ifdef RTCL_FRESNEL
	queue[slot].origin = (float4)(ray->origin, ray->weight.x);
	queue[slot].weight_green = ray->weight.y;
	queue[slot].weight_blue = ray->weight.z;
#else
	queue[slot].origin = (float4)(ray->origin, ray->weight);
#endif
	queue[slot].dir = (float4)(ray->dir, 0.0f);
	queue[slot].pixel = pixel;
	queue[slot].depth = ray->depth;
}

#ifdef RTCL_PATH
/* Under the path integrator a queue holds paths (struct rt_path_ray): each
 * bounce takes a path one vertex further (cl/path.cl), with its shadow ray,
 * and queues it again unless it ends; a pixel has one path per sample, so
 * its colour is read and written by one work-item per bounce, in the order
 * the single-pass kernels add the same terms: the same image. */
typedef struct rt_path_ray queue_entry;

static void store_path(__global struct rt_path_ray *queue, uint slot, const struct walk *w,
		       int pixel)
{
	queue[slot].origin = (float4)(w->ray.origin, w->beta.x);
	queue[slot].dir = (float4)(w->ray.dir, w->beta.y);
	queue[slot].x_prev = (float4)(w->x_prev, w->beta.z);
	queue[slot].pixel = pixel;
	queue[slot].vertex = w->vertex;
	queue[slot].pdf_prev = w->pdf_prev;
	queue[slot].specular = w->specular;
}

static struct walk load_path(__global const struct rt_path_ray *queue, uint i)
{
	struct walk w;
	float4 origin = queue[i].origin, dir = queue[i].dir, x_prev = queue[i].x_prev;

	w.ray = (struct ray_job){origin.xyz, dir.xyz, (ray_weight_t)(1.0f), 0};
	w.beta = (float3)(origin.w, dir.w, x_prev.w);
	w.x_prev = x_prev.xyz;
	w.vertex = queue[i].vertex;
	w.pdf_prev = queue[i].pdf_prev;
	w.specular = queue[i].specular != 0;
	w.shadow = false;
	w.done = false;
	return w;
}
#else
typedef struct rt_ray queue_entry;
#endif

/* Returns what sample_flops holds for pixel, 0 when not counting (the buffer
 * is then a placeholder). */
static inline ulong sample_pixel_flops(__global const ulong *sample_flops, int pixel)
{
#ifdef RTCL_COUNT_FLOPS
	return sample_flops[pixel];
#else
	(void)sample_flops;
	(void)pixel;
	return 0;
#endif
}

/* Sets pixel's count of the sample being traced, when counting. */
static inline void start_sample_flops(__global ulong *sample_flops, int pixel, ulong flops)
{
#ifdef RTCL_COUNT_FLOPS
	sample_flops[pixel] = flops;
#else
	(void)sample_flops;
	(void)pixel;
	(void)flops;
#endif
}

/* A pass of the wavefront traces one sample of every pixel of the piece:
 * wavefront_start, wavefront_bounce until the queue is empty, then
 * wavefront_accumulate. The bounces add the sample's colour and cost into
 * sample_rgb and sample_flops, which the accumulate adds to the image's
 * running sum in sample order, as the other kernels do.
 *
 * wavefront_start: one work-item per pixel of the piece (2D NDRange over its
 * rectangle, rounded up): the primary rays of sample `sample`, in pixel order
 * within the piece, queue[dy * width + dx] for its pixel (dx, dy) (split row
 * y0 + dy, rt_piece_row); the sample's colour
 * cleared. */
__kernel void wavefront_start(__global const uint4 *scene_global, __local uint4 *scene_local,
			      __global queue_entry *queue, __global ulong *item_counts,
			      __global ulong *sample_flops, __global float *sample_rgb,
			      struct rt_piece piece, uint sample)
{
	struct tracer tr;
	int dx = get_global_id(0), dy = get_global_id(1);

	tracer_init(&tr, load_scene(scene_global, scene_local), item_counts, sample_flops);
	if (dx < piece.width && dy < piece.height) {
		int x = piece.x0 + dx, y = rt_piece_row(&piece, piece.y0 + dy);
		int pixel = y * tr.scene->width + x;
#ifdef RTCL_PATH
		struct walk w;
		walk_start(&tr, &w, x, y, sample_offset(&tr, x, y, sample, piece.samples), sample,
			   piece.samples);
		store_path(queue, dy * piece.width + dx, &w, pixel);
#else
		struct ray_job ray;

		primary_ray(&tr, x, y, sample_offset(&tr, x, y, sample, piece.samples), sample,
			    piece.samples, &ray);
		store_ray(queue, dy * piece.width + dx, &ray, pixel);
#endif
		vstore3((float3)(0.0f), pixel, sample_rgb);
		start_sample_flops(sample_flops, pixel, tracer_flops(&tr)); /* bounces add theirs */
	}
	store_counts(&tr, global_item());
}

/* One work-item per pixel of the piece, like wavefront_start: adds sample
 * `sample`'s colour to the pixel's sum in sums, or stores the mean in image
 * after the render's last sample (one sample: its colour as it is;
 * sample.cl), and the sample's cost to the pixel's. The pass's last sample
 * counts as the pixel's write. */
__kernel void wavefront_accumulate(__global const uint4 *scene_global, __local uint4 *scene_local,
				   __global float *image, __global long *sums,
				   __global const float *sample_rgb, __global ulong *item_counts,
				   __global ulong *pixel_flops, __global const ulong *sample_flops,
				   __global uint *write_counts, struct rt_piece piece, uint sample)
{
	struct tracer tr;
	int dx = get_global_id(0), dy = get_global_id(1);

	tracer_init(&tr, load_scene(scene_global, scene_local), item_counts, pixel_flops);
	if (dx < piece.width && dy < piece.height) {
		int pixel = rt_piece_row(&piece, piece.y0 + dy) * tr.scene->width + piece.x0 + dx;
		float3 color = vload3(pixel, sample_rgb);
		bool last = (int)sample == piece.sample_end - 1;

		if (piece.samples == 1) {
			vstore3(color, pixel, image);
		} else {
			long4 sum = sample_term(&tr, color);
			if (sample_sum_held(&piece, (int)sample))
				sum = sample_sums(sum, vload4(pixel, sums));
			if (last && sample_ends_pixel(&piece, piece.sample_end))
				vstore3(sample_mean(&tr, sum, &piece), pixel, image);
			else
				vstore4(sum, pixel, sums);
		}
		if (last)
			count_write(write_counts, pixel);
		count_pixel_flops(pixel_flops, pixel,
				  sample_pixel_flops(sample_flops, pixel) + tracer_flops(&tr));
	}
	store_counts(&tr, global_item());
}

/* One work-item per queued ray (1D NDRange, rounded up); image and
 * pixel_flops are the sample's (sample_rgb, sample_flops), and each ray
 * carries its pixel, so the bounce needs no piece: only which sample of how
 * many it traces, for the light samples. Spawned rays go to
 * next[atomic_inc(next_count)]; one that finds the queue full sets *overflow
 * and is dropped, and the host renders the frame again with larger queues. */
__kernel void wavefront_bounce(__global const uint4 *scene_global, __local uint4 *scene_local,
			       __global const queue_entry *queue, uint queued,
			       __global queue_entry *next, __global uint *next_count,
			       uint capacity, __global uint *overflow, __global float *image,
			       __global ulong *item_counts, __global ulong *pixel_flops,
			       uint sample, uint samples)
{
	struct tracer tr;
	uint i = get_global_id(0);

	tracer_init(&tr, load_scene(scene_global, scene_local), item_counts, pixel_flops);
#ifdef RTCL_PATH
	if (i < queued) {
		struct walk w = load_path(queue, i);
		int pixel = queue[i].pixel;

		tracer_set_sample(&tr, pixel % tr.scene->width, pixel / tr.scene->width, sample,
				  samples);
		/* walk_step's two steps, the segment and its shadow ray, on the
		 * pixel's colour so far */
		w.color = vload3(pixel, image);
		bool done = walk_step(&tr, &w, NULL);
		if (w.shadow)
			done = walk_step(&tr, &w, NULL);
		vstore3(w.color, pixel, image);
		if (!done) {
			uint slot = atomic_inc(next_count);
			if (slot < capacity)
				store_path(next, slot, &w, pixel);
			else
				atomic_or(overflow, 1u);
		}
		add_pixel_flops(pixel_flops, pixel, tracer_flops(&tr));
	}
#else
	if (i < queued) {
		float4 origin = queue[i].origin;
#ifdef RTCL_FRESNEL
		ray_weight_t weight = (float3)(ray_weight(origin), queue[i].weight_green,
					       queue[i].weight_blue);
#else
		ray_weight_t weight = ray_weight(origin);
#endif
		struct ray_job ray = {origin.xyz, queue[i].dir.xyz, weight, queue[i].depth};
		int pixel = queue[i].pixel;
		struct ray_job children[2];
		int spawned;

		tracer_set_sample(&tr, pixel % tr.scene->width, pixel / tr.scene->width, sample,
				  samples);

		add_to_pixel(image, pixel, trace_one(&tr, &ray, children, &spawned));
		COUNT_FLOPS(&tr, FLOPS_ADD3);
		for (int c = 0; c < spawned; c++) {
			uint slot = atomic_inc(next_count);
			if (slot < capacity)
				store_ray(next, slot, &children[c], pixel);
			else
				atomic_or(overflow, 1u);
		}
		add_pixel_flops(pixel_flops, pixel, tracer_flops(&tr));
	}
#endif
	store_counts(&tr, global_item());
}

#if defined(RTCL_PATH) && defined(cl_khr_int64_base_atomics)
/* The stages form (docs/wavefront.md, "The stages form"), after Laine,
 * Karras and Aila (2013): a fixed pool of `slots` paths in
 * structure-of-arrays (rtcl_shared.h, RT_STAGE_*), and one kernel per stage
 * over a compacted queue of slots, each calling the piece of path.cl's walk
 * that the single-pass kernels' walk_step calls at that point:
 *
 *   stages_logic       each path that ended (done at a hit, or its
 *                      segment missed): the light of its last shadow ray,
 *                      the environment, its sample added to its pixel; the
 *                      slot pushed on the free stack (in a piece's first
 *                      iteration: every slot, all free)
 *   stages_new_path    free slots off the stack: the next (pixel, sample),
 *                      its primary ray queued for extension (stages_advance,
 *                      one work-item, then counts the paths handed out)
 *   stages_shade_KIND  at a hit of that kind: the light of the last shadow
 *                      ray, then path_vertex: emission, the light sample
 *                      (its shadow ray queued), the BSDF sample and the
 *                      roulette (the next segment queued, or the path to
 *                      the logic)
 *   stages_extend      each queued segment: its nearest hit; the path
 *                      queued by the BSDF kind hit, or to the logic
 *   stages_shadow      each queued shadow ray: any hit
 *
 * A path's colour gathers the same terms in the same order as walk_step's
 * (the emission and light sample of vertex i, its shadow ray's light, then
 * vertex i + 1's), and its sample's fixed-point term goes to the pixel's
 * sum with 64-bit atomic adds, which do not depend on the order: the image
 * is the single-pass kernels', byte for byte, and so are the flops and
 * rays each pixel gets. */

static inline __global float4 *stage_field(__global float4 *state, uint slots, int field)
{
	return state + (size_t)field * slots;
}

/* Appends slot to queue q. */
static inline void stage_push(__global uint *queues, __global uint *counts, uint slots, int q,
			      uint slot)
{
	queues[(size_t)q * slots + atomic_inc(&counts[q])] = slot;
}

static inline uint stage_queued(__global const uint *queues, uint slots, int q, uint j)
{
	return queues[(size_t)q * slots + j];
}

/* The walk of slot i as path.cl keeps it between two steps, with
 * path = its RT_STAGE_PATH word. */
static struct walk stage_load_walk(__global float4 *state, uint slots, uint i, int4 path)
{
	struct walk w;
	float4 origin = stage_field(state, slots, RT_STAGE_RAY_O)[i];
	float4 dir = stage_field(state, slots, RT_STAGE_RAY_D)[i];
	float4 prev = stage_field(state, slots, RT_STAGE_PREV)[i];
	float4 color = stage_field(state, slots, RT_STAGE_COLOR)[i];

	w.ray = (struct ray_job){origin.xyz, dir.xyz, (ray_weight_t)(1.0f), 0};
	w.beta = (float3)(origin.w, dir.w, prev.w);
	w.x_prev = prev.xyz;
	w.color = color.xyz;
	w.pdf_prev = color.w;
	w.vertex = path.z;
	w.specular = (path.w & RT_PATH_SPECULAR) != 0;
	w.shadow = false;
	w.done = false;
	return w;
}

static void stage_store_walk(__global float4 *state, uint slots, uint i, const struct walk *w)
{
	stage_field(state, slots, RT_STAGE_RAY_O)[i] = (float4)(w->ray.origin, w->beta.x);
	stage_field(state, slots, RT_STAGE_RAY_D)[i] = (float4)(w->ray.dir, w->beta.y);
	stage_field(state, slots, RT_STAGE_PREV)[i] = (float4)(w->x_prev, w->beta.z);
	stage_field(state, slots, RT_STAGE_COLOR)[i] = (float4)(w->color, w->pdf_prev);
}

static inline int4 stage_path(__global float4 *state, uint slots, uint i)
{
	return as_int4(stage_field(state, slots, RT_STAGE_PATH)[i]);
}

/* Adds flops to the cost of slot i's pixel, when counting (the ray kernels,
 * which otherwise never read the path's word). */
static inline void add_slot_flops(__global ulong *pixel_flops, __global float4 *state,
				  uint slots, uint i, ulong flops)
{
#ifdef RTCL_COUNT_FLOPS
	add_pixel_flops(pixel_flops, stage_path(state, slots, i).x, flops);
#else
	(void)pixel_flops;
	(void)state;
	(void)slots;
	(void)i;
	(void)flops;
#endif
}

static inline void stage_set_path(__global float4 *state, uint slots, uint i, int4 path)
{
	stage_field(state, slots, RT_STAGE_PATH)[i] = as_float4(path);
}

/* Sets the sample of path (its RT_STAGE_PATH word) as the one traced. */
static inline void stage_set_sample(struct tracer *tr, int4 path, uint samples)
{
	tracer_set_sample(tr, path.x % tr->scene->width, path.x / tr->scene->width, (uint)path.y,
			  samples);
}

/* The light of the shadow ray queued at the path's last vertex (flags:
 * its RT_PATH_* flags), whether it was clear (RT_STAGE_HIT_PRIM's third
 * int, read only when there was one), added to w->color as walk_step adds
 * it: the first thing the kernel that next takes the path does. What it
 * brings is read only when it arrives. */
static void stage_light_arrives(struct tracer *tr, struct walk *w, __global float4 *state,
				uint slots, uint i, uint flags)
{
	if (!(flags & RT_PATH_SHADOW))
		return;
	bool clear = ((__global const int *)(stage_field(state, slots, RT_STAGE_HIT_PRIM) + i))[2];
	if (clear)
		w->shadow_color = stage_field(state, slots, RT_STAGE_SHADOW_C)[i].xyz;
	path_light_arrives(tr, w, clear);
}

/* The queue kernels below take the items of their queue j = get_global_id(0),
 * j + get_global_size(0), ... below their count: the host launches either
 * exactly the count it read (one item each) or a grid that fills the device
 * (RTCL_STAGES_LAUNCH=device, docs/wavefront.md), whose work-items read the
 * count on the device. Each item's flops go to its path's pixel. `limit`
 * caps the count (the host's, or UINT_MAX). */
static inline uint stage_count(__global const uint *counts, int q, uint limit)
{
	return min(counts[q], limit);
}

/* The paths of the piece handed out so far: a 64-bit word after the
 * queue counters. */
static inline __global ulong *stage_handed_out(__global uint *counts)
{
	return (__global ulong *)(counts + RT_STAGE_COUNTERS);
}

/* stages_logic: over the paths that ended last iteration (the decide
 * queue: the shade kernels queue a path done at its hit, stages_extend one
 * whose segment missed), or, when `every` (a piece's first iteration), over
 * every slot, all of them free then since the piece before ended all its
 * paths. A path that ended gets the light of its last shadow ray and, when
 * it missed, the environment (path_missed); its colour goes to image as it
 * is when the render has one sample, else its fixed-point term to the
 * pixel's sum (image and sums are the render's). Its slot, and every free
 * one, is pushed on the free stack. */
__kernel void stages_logic(__global const uint4 *scene_global, __local uint4 *scene_local,
			   __global float4 *state, uint slots, __global uint *queues,
			   __global uint *counts, __global float *image, __global long *sums,
			   __global ulong *item_counts, __global ulong *pixel_flops, uint samples,
			   uint every)
{
	struct tracer tr;
	uint count = every ? slots : counts[RT_STAGE_QUEUE_DECIDE];

	tracer_init(&tr, load_scene(scene_global, scene_local), item_counts, pixel_flops);
	for (uint j = get_global_id(0); j < count; j += get_global_size(0)) {
		ulong before = tracer_flops(&tr);
		uint i = every ? j : stage_queued(queues, slots, RT_STAGE_QUEUE_DECIDE, j);

		if (!every) {
			int4 path = stage_path(state, slots, i);
			uint flags = (uint)path.w;
			struct walk w;

			stage_set_sample(&tr, path, samples);
			if (flags & RT_PATH_DONE) {
				w.color = stage_field(state, slots, RT_STAGE_COLOR)[i].xyz;
				stage_light_arrives(&tr, &w, state, slots, i, flags);
			} else {
				w = stage_load_walk(state, slots, i, path);
				stage_light_arrives(&tr, &w, state, slots, i, flags);
				path_missed(&tr, &w);
			}
			if (samples == 1)
				vstore3(w.color, path.x, image);
			else
				sample_add_atomic(sums, path.x, sample_term(&tr, w.color));
			/* the slot free: its flags alone written */
			((__global int *)(stage_field(state, slots, RT_STAGE_PATH) + i))[3] = 0;
			add_pixel_flops(pixel_flops, path.x, tracer_flops(&tr) - before);
		}
		stage_push(queues, counts, slots, RT_STAGE_QUEUE_NEW, i);
	}
	store_counts(&tr, global_item());
}

/* stages_new_path: off the top of the free stack, as many slots as paths
 * remain of the piece's `total`: the j-th takes path handed_out + j,
 * numbered sample by sample and, within a sample, pixel by pixel in the
 * piece's order. */
__kernel void stages_new_path(__global const uint4 *scene_global, __local uint4 *scene_local,
			      __global float4 *state, uint slots, __global uint *queues,
			      __global uint *counts, uint limit, ulong total,
			      struct rt_piece piece, __global ulong *item_counts,
			      __global ulong *pixel_flops)
{
	struct tracer tr;
	ulong first = *stage_handed_out(counts);
	ulong left = total - first;
	uint stacked = counts[RT_STAGE_QUEUE_NEW];
	uint count = (uint)min((ulong)min(stacked, limit), left);
	ulong per_sample = (ulong)piece.width * (ulong)piece.height;

	tracer_init(&tr, load_scene(scene_global, scene_local), item_counts, pixel_flops);
	for (uint j = get_global_id(0); j < count; j += get_global_size(0)) {
		ulong before = tracer_flops(&tr);
		uint slot = stage_queued(queues, slots, RT_STAGE_QUEUE_NEW, stacked - count + j);
		ulong n = first + j;
		int k = piece.sample_begin + (int)(n / per_sample);
		int r = (int)(n % per_sample);
		int x = piece.x0 + r % piece.width;
		int y = rt_piece_row(&piece, piece.y0 + r / piece.width);
		int pixel = y * tr.scene->width + x;
		struct walk w;

		walk_start(&tr, &w, x, y, sample_offset(&tr, x, y, k, piece.samples), k,
			   piece.samples);
		stage_store_walk(state, slots, slot, &w);
		stage_set_path(state, slots, slot,
			       (int4)(pixel, k, w.vertex,
				      RT_PATH_LIVE | (w.specular ? RT_PATH_SPECULAR : 0)));
		stage_push(queues, counts, slots, RT_STAGE_QUEUE_EXTEND, slot);
		add_pixel_flops(pixel_flops, pixel, tracer_flops(&tr) - before);
	}
	store_counts(&tr, global_item());
}

/* One work-item, after stages_new_path: the paths it took counted as
 * handed out, their slots taken off the free stack. */
__kernel void stages_advance(__global uint *counts, ulong total)
{
	__global ulong *handed_out = stage_handed_out(counts);

	if (get_global_id(0) == 0) {
		uint taken = (uint)min((ulong)counts[RT_STAGE_QUEUE_NEW], total - *handed_out);
		*handed_out += taken;
		counts[RT_STAGE_QUEUE_NEW] -= taken;
	}
}

/* A shade kernel: over the queue of kind's hits. A path that ends here
 * goes to the logic (the decide queue), once its shadow ray, if it made
 * one, is traced. */
static void stages_shade(__global const uint4 *scene_global, __local uint4 *scene_local,
			 __global float4 *state, uint slots, __global uint *queues,
			 __global uint *counts, uint limit, uint samples,
			 __global ulong *item_counts, __global ulong *pixel_flops, int kind)
{
	struct tracer tr;
	uint count = stage_count(counts, RT_STAGE_QUEUE_SHADE(kind), limit);

	tracer_init(&tr, load_scene(scene_global, scene_local), item_counts, pixel_flops);
	for (uint j = get_global_id(0); j < count; j += get_global_size(0)) {
		ulong before = tracer_flops(&tr);
		uint i = stage_queued(queues, slots, RT_STAGE_QUEUE_SHADE(kind), j);
		int4 path = stage_path(state, slots, i);
		struct walk w = stage_load_walk(state, slots, i, path);
		float4 h = stage_field(state, slots, RT_STAGE_HIT)[i];
		int4 prim = as_int4(stage_field(state, slots, RT_STAGE_HIT_PRIM)[i]);
		struct hit hit = {h.x, prim.x, prim.y, as_int(h.w), h.y, h.z};

		stage_set_sample(&tr, path, samples);
		stage_light_arrives(&tr, &w, state, slots, i, (uint)path.w);
		bool done = path_vertex(&tr, &w, hit, kind);
		if (done) {
			stage_field(state, slots, RT_STAGE_COLOR)[i] = (float4)(w.color, w.pdf_prev);
			stage_push(queues, counts, slots, RT_STAGE_QUEUE_DECIDE, i);
		} else {
			stage_store_walk(state, slots, i, &w);
			stage_push(queues, counts, slots, RT_STAGE_QUEUE_EXTEND, i);
		}
		if (w.shadow) {
			stage_field(state, slots, RT_STAGE_SHADOW_O)[i] =
				(float4)(w.shadow_origin, w.shadow_max);
			stage_field(state, slots, RT_STAGE_SHADOW_D)[i] =
				(float4)(w.shadow_dir, as_float(w.shadow_sphere));
			stage_field(state, slots, RT_STAGE_SHADOW_C)[i] =
				(float4)(w.shadow_color, as_float(w.shadow_triangle));
			stage_push(queues, counts, slots, RT_STAGE_QUEUE_SHADOW, i);
		}
		path.z = w.vertex;
		path.w = (int)(RT_PATH_LIVE | (w.specular ? RT_PATH_SPECULAR : 0) |
			       (w.shadow ? RT_PATH_SHADOW : 0) | (done ? RT_PATH_DONE : 0));
		stage_set_path(state, slots, i, path);
		add_pixel_flops(pixel_flops, path.x, tracer_flops(&tr) - before);
	}
	store_counts(&tr, global_item());
}

#define STAGES_SHADE_KERNEL(name, kind)                                                            \
	__kernel void name(__global const uint4 *scene_global, __local uint4 *scene_local,         \
			   __global float4 *state, uint slots, __global uint *queues,              \
			   __global uint *counts, uint limit, uint samples,                        \
			   __global ulong *item_counts, __global ulong *pixel_flops)               \
	{                                                                                          \
		stages_shade(scene_global, scene_local, state, slots, queues, counts, limit,       \
			     samples, item_counts, pixel_flops, kind);                             \
	}

STAGES_SHADE_KERNEL(stages_shade_mapped, RT_BSDF_MAPPED)
STAGES_SHADE_KERNEL(stages_shade_diffuse, RT_BSDF_DIFFUSE)
STAGES_SHADE_KERNEL(stages_shade_conductor, RT_BSDF_CONDUCTOR)
STAGES_SHADE_KERNEL(stages_shade_dielectric, RT_BSDF_DIELECTRIC)
STAGES_SHADE_KERNEL(stages_shade_principled, RT_BSDF_PRINCIPLED)

/* stages_extend: over the extension queue (the host knows only a bound on
 * its length: the work-items read it on the device). Its hit goes to
 * RT_STAGE_HIT and the first two ints of RT_STAGE_HIT_PRIM, and the path
 * to the queue of the BSDF kind hit (path_hit_kind: the material's, no
 * arithmetic), or to the logic when the segment missed. */
__kernel void stages_extend(__global const uint4 *scene_global, __local uint4 *scene_local,
			    __global float4 *state, uint slots, __global uint *queues,
			    __global uint *counts, __global ulong *item_counts,
			    __global ulong *pixel_flops)
{
	struct tracer tr;
	uint count = counts[RT_STAGE_QUEUE_EXTEND];

	tracer_init(&tr, load_scene(scene_global, scene_local), item_counts, pixel_flops);
	for (uint j = get_global_id(0); j < count; j += get_global_size(0)) {
		ulong before = tracer_flops(&tr);
		uint i = stage_queued(queues, slots, RT_STAGE_QUEUE_EXTEND, j);
		struct walk w;

		w.ray.origin = stage_field(state, slots, RT_STAGE_RAY_O)[i].xyz;
		w.ray.dir = stage_field(state, slots, RT_STAGE_RAY_D)[i].xyz;
		struct hit hit = path_extend(&tr, &w);
		stage_field(state, slots, RT_STAGE_HIT)[i] =
			(float4)(hit.t, hit.u, hit.v, as_float(hit.triangle));
		vstore2((int2)(hit.sphere, hit.plane), 0,
			(__global int *)(stage_field(state, slots, RT_STAGE_HIT_PRIM) + i));
		stage_push(queues, counts, slots,
			   hit.t == 0.0f ? RT_STAGE_QUEUE_DECIDE
					 : RT_STAGE_QUEUE_SHADE(path_hit_kind(&tr, hit)),
			   i);
		add_slot_flops(pixel_flops, state, slots, i, tracer_flops(&tr) - before);
	}
	store_counts(&tr, global_item());
}

/* stages_shadow: over the shadow queue, as stages_extend; whether the ray
 * is clear goes to RT_STAGE_HIT_PRIM's third int (after stages_extend
 * wrote the first two for the same slot: the launches are in order). */
__kernel void stages_shadow(__global const uint4 *scene_global, __local uint4 *scene_local,
			    __global float4 *state, uint slots, __global const uint *queues,
			    __global const uint *counts, __global ulong *item_counts,
			    __global ulong *pixel_flops)
{
	struct tracer tr;
	uint count = counts[RT_STAGE_QUEUE_SHADOW];

	tracer_init(&tr, load_scene(scene_global, scene_local), item_counts, pixel_flops);
	for (uint j = get_global_id(0); j < count; j += get_global_size(0)) {
		ulong before = tracer_flops(&tr);
		uint i = stage_queued(queues, slots, RT_STAGE_QUEUE_SHADOW, j);
		float4 origin = stage_field(state, slots, RT_STAGE_SHADOW_O)[i];
		float4 dir = stage_field(state, slots, RT_STAGE_SHADOW_D)[i];
		struct walk w;

		w.shadow_origin = origin.xyz;
		w.shadow_max = origin.w;
		w.shadow_dir = dir.xyz;
		w.shadow_sphere = as_int(dir.w);
		w.shadow_triangle = as_int(stage_field(state, slots, RT_STAGE_SHADOW_C)[i].w);
		((__global int *)(stage_field(state, slots, RT_STAGE_HIT_PRIM) + i))[2] =
			path_shadow_clear(&tr, &w);
		add_slot_flops(pixel_flops, state, slots, i, tracer_flops(&tr) - before);
	}
	store_counts(&tr, global_item());
}

/* One work-item per pixel of the piece (as wavefront_start), before its
 * paths: the pixel's sum zeroed when the piece starts it (the sums buffer
 * does not hold it yet). */
__kernel void stages_begin(__global const uint4 *scene_global, __local uint4 *scene_local,
			   __global long *sums, __global ulong *item_counts,
			   struct rt_piece piece)
{
	struct tracer tr;
	int dx = get_global_id(0), dy = get_global_id(1);

	tracer_init(&tr, load_scene(scene_global, scene_local), item_counts, NULL);
	if (dx < piece.width && dy < piece.height && piece.samples > 1 &&
	    !sample_sum_held(&piece, piece.sample_begin)) {
		int pixel = rt_piece_row(&piece, piece.y0 + dy) * tr.scene->width + piece.x0 + dx;
		vstore4((long4)(0), pixel, sums);
	}
	store_counts(&tr, global_item());
}

/* One work-item per pixel of the piece, after its paths: the mean stored
 * when the piece ends the pixel (as wavefront_accumulate does), and the
 * piece's write of the pixel counted. */
__kernel void stages_finish(__global const uint4 *scene_global, __local uint4 *scene_local,
			    __global float *image, __global const long *sums,
			    __global ulong *item_counts, __global ulong *pixel_flops,
			    __global uint *write_counts, struct rt_piece piece)
{
	struct tracer tr;
	int dx = get_global_id(0), dy = get_global_id(1);

	tracer_init(&tr, load_scene(scene_global, scene_local), item_counts, pixel_flops);
	if (dx < piece.width && dy < piece.height) {
		int pixel = rt_piece_row(&piece, piece.y0 + dy) * tr.scene->width + piece.x0 + dx;

		if (piece.samples > 1 && sample_ends_pixel(&piece, piece.sample_end))
			vstore3(sample_mean(&tr, vload4(pixel, sums), &piece), pixel, image);
		count_write(write_counts, pixel);
		count_pixel_flops(pixel_flops, pixel, tracer_flops(&tr));
	}
	store_counts(&tr, global_item());
}
#endif
