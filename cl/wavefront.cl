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
