/* A pixel: its samples walked (walk.cl's ray tree, or path.cl's path under
 * RTCL_PATH), summed and stored, with the counts and the schedule map the
 * instrumented builds record. Part of the tracer: built after path.cl. */

/* Counts a write of pixel, when the tests ask for it (RTCL_COUNT_WRITES):
 * probe holds one count per pixel then. */
static inline void count_write(__global uint *probe, int pixel)
{
#ifdef RTCL_COUNT_WRITES
	atomic_inc(&probe[pixel]);
#else
	(void)probe;
	(void)pixel;
#endif
}

/* With RTCL_SCHEDULE_MAP (--schedule-map): records who starts pixel, and
 * when, as its first sample begins: the work-group and the work-item in it,
 * row-major, and a ticket from the counter after the image's words
 * (docs/RENDERING.md, "The schedule map"). */
static inline void record_schedule(__global uint *probe, int pixel, int pixels,
				   const struct rt_piece *piece)
{
#ifdef RTCL_SCHEDULE_MAP
	if (piece->sample_begin > 0)
		return;
	__global uint *words = probe + RT_SCHEDULE_WORDS * pixel;
	words[RT_SCHEDULE_GROUP] = get_group_id(1) * get_num_groups(0) + get_group_id(0);
	words[RT_SCHEDULE_ITEM] = get_local_id(1) * get_local_size(0) + get_local_id(0);
	words[RT_SCHEDULE_TICKET] = atomic_inc(probe + RT_SCHEDULE_WORDS * pixels);
#else
	(void)probe;
	(void)pixel;
	(void)pixels;
	(void)piece;
#endif
}

/* Adds flops to pixel's cost, when counting. Every piece and pass that
 * traces the pixel adds its part; one work-item at a time does. */
static inline void count_pixel_flops(__global ulong *pixel_flops, int pixel, ulong flops)
{
#ifdef RTCL_COUNT_FLOPS
	pixel_flops[pixel] += flops;
#else
	(void)pixel_flops;
	(void)pixel;
	(void)flops;
#endif
}

/* Traces samples [sample_begin, sample_end) of pixel (x, y), which must lie
 * inside the image, and stores the sum of its sample colours in sums, or
 * after the last sample their mean in image (sample.cl); one sample's colour
 * goes to image as it is. */
static void render_pixel(struct tracer *tr, const struct rt_piece *piece, __global float *image,
			 __global long *sums, __global uint *probe, int x, int y)
{
	struct walk w;
	struct ray_job waiting[RAY_STACK_SIZE];
	int pixel = y * tr->scene->width + x;
	ulong flops_before = tracer_flops(tr);

	record_schedule(probe, pixel, tr->scene->width * tr->scene->height, piece);
#ifdef RTCL_ONE_SAMPLE
	/* One sample per pixel (the host builds --spp 1 with RTCL_ONE_SAMPLE):
	 * what the loop below does for it, the centre stored as it is, with no
	 * sum or sample index live across the trace (fewer registers). */
	walk_start(tr, &w, x, y, (float2)(0.5f), 0, 1);
	while (!walk_step(tr, &w, waiting))
		;
	vstore3(w.color, pixel, image);
#else
	/* Each sample's colour goes to the pixel's sum in the sums buffer (in
	 * place, or summed over the pass in registers and added after it:
	 * sample.cl); the pass that ends the pixel stores its mean, and one
	 * sample its colour as it is. */
	bool held = sample_sum_held(piece, piece->sample_begin);
	long4 sum = (long4)(0);

	for (int k = piece->sample_begin; k < piece->sample_end; k++) {
		walk_start(tr, &w, x, y, sample_offset(tr, x, y, k, piece->samples), k,
			   piece->samples);
		while (!walk_step(tr, &w, waiting))
			;
		if (piece->samples == 1)
			continue;
#ifdef RTCL_SUM_IN_PLACE
		sample_add_in_place(sums, pixel, sample_term(tr, w.color),
				    held || k > piece->sample_begin);
#else
		sum = sample_sums(sum, sample_term(tr, w.color));
#endif
	}
	if (piece->samples == 1) {
		vstore3(w.color, pixel, image);
	} else {
#ifdef RTCL_SUM_IN_PLACE
		if (sample_ends_pixel(piece, piece->sample_end))
			vstore3(sample_mean(tr, sample_read_in_place(sums, pixel), piece), pixel,
				image);
#else
		if (held)
			sum = sample_sums(sum, vload4(pixel, sums));
		if (sample_ends_pixel(piece, piece->sample_end))
			vstore3(sample_mean(tr, sum, piece), pixel, image);
		else
			vstore4(sum, pixel, sums);
#endif
	}
#endif
	count_pixel_flops(tr->pixel_flops, pixel, tracer_flops(tr) - flops_before);
	count_write(probe, pixel);
}
