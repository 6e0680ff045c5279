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

/* A pixel being traced by a work-item: where, the sample it is at, and
 * what its samples add up to so far. render_pixel keeps it across the
 * pixel's samples; a regenerating work-item (persistent.cl) keeps it while
 * it steps the pixel's paths one intersection at a time. Both go through
 * the functions below, so that a pixel is summed and stored one way. */
struct pixel_trace {
	int x, y, pixel;
	int k;		    /* the sample being traced */
	ulong flops_before; /* the work-item's flops when the pixel began */
#ifndef RTCL_ONE_SAMPLE
	bool held; /* the sums buffer holds the pixel's sum before this pass */
	long4 sum; /* the pass's samples, when summed in registers */
#endif
};

/* Begins pixel (x, y), which must lie inside the image: its first sample
 * of the piece is the next. */
static void pixel_begin(struct tracer *tr, const struct rt_piece *piece, __global uint *probe,
			int x, int y, struct pixel_trace *p)
{
	p->x = x;
	p->y = y;
	p->pixel = y * tr->scene->width + x;
	p->flops_before = tracer_flops(tr);
	record_schedule(probe, p->pixel, tr->scene->width * tr->scene->height, piece);
#ifdef RTCL_ONE_SAMPLE
	p->k = 0;
#else
	p->k = piece->sample_begin;
	p->held = sample_sum_held(piece, piece->sample_begin);
	p->sum = (long4)(0);
#endif
}

/* Whether the pixel has a sample of the piece left to trace. */
static inline bool pixel_samples_left(const struct rt_piece *piece, const struct pixel_trace *p)
{
#ifdef RTCL_ONE_SAMPLE
	(void)piece;
	return p->k < 1;
#else
	return p->k < piece->sample_end;
#endif
}

/* Starts the walk of the pixel's next sample. */
static inline void pixel_sample_start(struct tracer *tr, const struct rt_piece *piece,
				      const struct pixel_trace *p, struct walk *w)
{
#ifdef RTCL_ONE_SAMPLE
	/* One sample per pixel (the host builds --spp 1 with RTCL_ONE_SAMPLE):
	 * the centre, with no sum or sample index live across the trace
	 * (fewer registers). */
	(void)piece;
	walk_start(tr, w, p->x, p->y, (float2)(0.5f), 0, 1);
#else
	walk_start(tr, w, p->x, p->y, sample_offset(tr, p->x, p->y, p->k, piece->samples), p->k,
		   piece->samples);
#endif
}

/* Adds the colour of the sample whose walk w ended to the pixel's sum (in
 * the sums buffer in place, or in registers over the pass: sample.cl), and
 * moves on to the next sample. One sample's colour is stored as it is, by
 * pixel_end. */
static inline void pixel_sample_add(struct tracer *tr, const struct rt_piece *piece,
				    __global long *sums, struct pixel_trace *p, const struct walk *w)
{
#ifndef RTCL_ONE_SAMPLE
	if (piece->samples > 1) {
#ifdef RTCL_SUM_IN_PLACE
		sample_add_in_place(sums, p->pixel, sample_term(tr, w->color),
				    p->held || p->k > piece->sample_begin);
#else
		p->sum = sample_sums(p->sum, sample_term(tr, w->color));
#endif
	}
#else
	(void)tr;
	(void)piece;
	(void)sums;
	(void)w;
#endif
	p->k++;
}

/* Ends the pixel after its last sample of the piece (w: that sample's
 * walk): stores the sum of its samples in sums, or after the render's last
 * sample their mean in image; one sample's colour goes to image as it is. */
static void pixel_end(struct tracer *tr, const struct rt_piece *piece, __global float *image,
		      __global long *sums, __global uint *probe, const struct pixel_trace *p,
		      const struct walk *w)
{
	int pixel = p->pixel;

#ifdef RTCL_ONE_SAMPLE
	(void)piece;
	(void)sums;
	vstore3(w->color, pixel, image);
#else
	if (piece->samples == 1) {
		vstore3(w->color, pixel, image);
	} else {
#ifdef RTCL_SUM_IN_PLACE
		if (sample_ends_pixel(piece, piece->sample_end))
			vstore3(sample_mean(tr, sample_read_in_place(sums, pixel), piece), pixel,
				image);
#else
		long4 sum = p->sum;
		if (p->held)
			sum = sample_sums(sum, vload4(pixel, sums));
		if (sample_ends_pixel(piece, piece->sample_end))
			vstore3(sample_mean(tr, sum, piece), pixel, image);
		else
			vstore4(sum, pixel, sums);
#endif
	}
#endif
	count_pixel_flops(tr->pixel_flops, pixel, tracer_flops(tr) - p->flops_before);
	count_write(probe, pixel);
}

/* Traces samples [sample_begin, sample_end) of pixel (x, y), which must lie
 * inside the image, each walked to its end before the next begins, and
 * stores the pixel (pixel_end). */
static void render_pixel(struct tracer *tr, const struct rt_piece *piece, __global float *image,
			 __global long *sums, __global uint *probe, int x, int y)
{
	struct walk w;
	struct ray_job waiting[RAY_STACK_SIZE];
	struct pixel_trace p;

	pixel_begin(tr, piece, probe, x, y, &p);
	for (; pixel_samples_left(piece, &p); pixel_sample_add(tr, piece, sums, &p, &w)) {
		pixel_sample_start(tr, piece, &p, &w);
		while (!walk_step(tr, &w, waiting))
			;
	}
	pixel_end(tr, piece, image, sums, probe, &p, &w);
}
