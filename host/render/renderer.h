/* A renderer open on one device and one scene, rendering pieces of the image
 * (struct rt_piece, cl/rtcl_shared.h): what a plain render (render.c) and a
 * multi-device render call per device.
 *
 *   renderer_open       once: plans the NDRange for the whole image, packs and
 *                       uploads the scene, builds the program, creates the
 *                       full-image buffers (image, counts, write counts)
 *   renderer_piece      any number of times: renders one piece, a rectangle
 *                       of the image and a range of its pixels' samples
 *   renderer_read_back  the whole image and the counts, into the result
 *   renderer_close      releases everything open took
 *
 * The image buffer holds, for each pixel, the running sum of the samples
 * traced so far in sample order, and the mean once the piece with the
 * render's last sample (sample_end = samples) has run: pieces of one pixel
 * must come in sample order, each starting where the last ended (the first at
 * 0). Pixels no piece covered are left as they were (poison with
 * check_writes). Flop counts add up over every piece since open: per pixel
 * on the device; per work-item on the host, work-item i of every launch added
 * together (single-pass kernels), or every launch's work-items appended
 * (wavefront). Write counts (check_writes) count one write per pixel per
 * piece that covers it. */
#ifndef RTCL_RENDERER_H
#define RTCL_RENDERER_H

#include "rtcl_shared.h"
#include "render/settings.h"

/* What one piece took. */
struct piece_result {
	double kernel_ms; /* the profiled time of its launches */
	int launches;
	int samples; /* of every pixel of the piece (renderer_all_samples): its
			whole range, or fewer when stopped (render_settings.stoppable) */
	int passes;  /* the passes that ran */
};

/* The most in-order queues one device renders with (--queues). */
#define RENDER_MAX_QUEUES 4

struct render_buffers;

struct renderer {
	const struct renderer_ops *ops; /* the kernel's: singlepass or wavefront */
	struct device *dev;
	int queues;			/* renderer_queues(): the queues open, 1 or
					   the most parts of renderer_all_samples */
	const struct render_settings *settings;
	struct render_result *result; /* the plan, scene and build facts; read_back
					 fills the image and counts */
	void *state;		      /* the renderer's own, behind ops */
	struct render_buffers *buffers; /* the whole image's, in state (buffers.h) */
	double next_checkpoint;	      /* when the next is due (settings->checkpoint),
					 on timing_now()'s clock; 0: not started */
};

/* The functions a family of kernels provides (kernel_info.ops). Each returns
 * 0, or -1 with one message in err. */
struct renderer_ops {
	int (*open)(struct renderer *r, const struct scene *scene, char *err, size_t err_size);
	int (*piece)(struct renderer *r, const struct rt_piece *piece, struct piece_result *out,
		     char *err, size_t err_size);
	/* Every sample of `count` (<= r->queues) disjoint pieces, piece i on
	 * queue i, in passes of per_pass samples; NULL: one queue only. */
	int (*passes)(struct renderer *r, const struct rt_piece *pieces, int count, int per_pass,
		      struct piece_result *out, char *err, size_t err_size);
	int (*read_back)(struct renderer *r, char *err, size_t err_size);
	int (*read_rows)(struct renderer *r, const struct rt_piece *piece, float *to, int packed,
			 char *err, size_t err_size);
	int (*read_sums)(struct renderer *r, cl_long *to, size_t first, size_t count,
			 cl_event *event, char *err, size_t err_size);
	void (*close)(struct renderer *r);
	/* The auxiliary images into result->aov (aov_render). */
	int (*aov)(struct renderer *r, char *err, size_t err_size);
};

/* Opens settings->kernel's renderer on dev for scene; result is zeroed first
 * and must outlive the renderer. On failure nothing is held by r (result may
 * hold memory: render_result_free). */
int renderer_open(struct renderer *r, struct device *dev, const struct scene *scene,
		  const struct render_settings *settings, struct render_result *result, char *err,
		  size_t err_size);

/* Renders piece, which must lie inside the image with
 * 0 <= sample_begin < sample_end <= samples = settings->samples; sets *out
 * and adds its pixel samples to the progress line (progress.h). */
int renderer_piece(struct renderer *r, const struct rt_piece *piece, struct piece_result *out,
		   char *err, size_t err_size);

/* Reads the whole image (result->rgb) and, when counting or checking, the
 * counts accumulated since open into the result. */
int renderer_read_back(struct renderer *r, char *err, size_t err_size);

/* Reads only piece's pixels back, straight into to: at their places in an
 * image of the render's size, or packed row after row (buffers_read_rows);
 * for a piece that goes elsewhere without the whole image read first. */
int renderer_read_rows(struct renderer *r, const struct rt_piece *piece, float *to, int packed,
		       char *err, size_t err_size);

/* Reads the fixed-point sums of every pixel (buffers_read_sums) into to:
 * what pieces whose samples are split between devices leave
 * (rt_piece.sum_begin). */
int renderer_read_sums(struct renderer *r, cl_long *to, char *err, size_t err_size);

/* Reads the sums of pixels [first, first + count) to the same places of to
 * (a host copy of every pixel's sums), as buffers_read_sums: done on return
 * with event NULL, else only enqueued, *event saying when it is done (the
 * caller releases it). */
int renderer_read_sums_part(struct renderer *r, cl_long *to, size_t first, size_t count,
			    cl_event *event, char *err, size_t err_size);

void renderer_close(struct renderer *r);

/* Renders the auxiliary images (cl/aov.cl) into r->result->aov; the
 * settings must ask for them (settings.aov). */
int renderer_aov(struct renderer *r, char *err, size_t err_size);

/* Returns the piece of rows [y0, y0 + height), the image's whole width, with
 * samples [begin, end) of settings_samples(s). */
struct rt_piece renderer_rows(const struct render_settings *s, int y0, int height, int begin,
			      int end);

/* Sets piece's row map (rt_piece_row, cl/rtcl_shared.h; docs/GUIDE.md,
 * "How the rows are ordered") to deal the whole bands of `band` rows of an
 * image `height` rows high to `classes` classes; fewer than 2 classes, band 0
 * or more classes than bands: scan order, split row v is image row v. */
void renderer_interleave_rows(struct rt_piece *p, int height, int band, int classes);

/* Returns piece as a kernel takes it: with its mean_scale set
 * (settings_mean_scale of its samples). */
struct rt_piece renderer_launch_piece(const struct rt_piece *piece);

/* Returns the piece of the whole image with samples [begin, end). */
struct rt_piece renderer_whole_image(const struct render_settings *s, int begin, int end);

/* Returns how many passes renderer_all_samples() makes over piece on a GPU
 * (gpu != 0) or another device. */
int renderer_pass_count(const struct render_settings *s, const struct rt_piece *piece, int gpu);

/* Returns how many in-order queues a renderer of settings on dev opens:
 * settings->queues if given, else RENDER_GPU_QUEUES_SHARE on a GPU and 1 on
 * other devices; 1 for a kernel of one work-item (serial), a renderer
 * without `passes` (wavefront), and the counting and recording builds,
 * whose counts are read after every launch. */
int renderer_queues(const struct render_settings *settings, const struct device *dev);

/* The queues a GPU renders a piece of several passes with by default
 * (docs/GUIDE.md, --queues): 2 for the whole image, 4 for a share of it
 * (several devices). Measured on H200s (docs/results/multidevice, batches
 * 64-66): a whole image took 1556 ms on 2, 1583 on 4 (default scene, 2048
 * spp), a GPU's half 842 on 2 and 813 on 4. A share has fewer pixels, so a
 * launch gives each resident work-group fewer chunks and its end is a
 * larger part of it: more queues overlap more of the ends. */
#define RENDER_GPU_QUEUES_WHOLE 2
#define RENDER_GPU_QUEUES_SHARE 4

/* Renders piece's samples [sample_begin, sample_end) of every pixel (all of
 * them but where the samples are split between devices, rt_piece.sum_begin)
 * in passes of renderer_pass_samples() samples, in sample order on this one
 * renderer, so that the sums stay in its buffer; sets *out to the
 * passes' kernel time and launches. With several queues (--queues, or by
 * default on a GPU for a piece of two passes or more, RENDER_GPU_QUEUES_*)
 * the piece's columns are cut into that many parts of whole work-groups, each
 * rendered on its own queue, launches alternating: a queue's next launch
 * fills the device while another's ends, and the host enqueues ahead
 * instead of waiting between passes. A pixel's samples still come in order,
 * so the image is the same; kernel_ms is then the time any launch of the
 * piece ran (launch_busy_ms), not the sum of the launches' times. Between
 * passes it writes the checkpoints that are due and stops where
 * renderer_stopping() says, out->samples then telling how many samples of
 * every pixel were traced. */
int renderer_all_samples(struct renderer *r, const struct rt_piece *piece, struct piece_result *out,
			 char *err, size_t err_size);

/* Between two passes of renderer_all_samples: whether the render stops
 * there (settings->stoppable and an interrupt asked it to). */
int renderer_stopping(const struct renderer *r);

/* Whether a checkpoint (settings->checkpoint) is due between two passes. */
int renderer_checkpoint_due(const struct renderer *r);

/* Writes a checkpoint of the whole image, `samples` samples of every pixel
 * done and no launch in flight, and sets when the next is due. Returns 0,
 * or -1 with one message in err. */
int renderer_checkpoint(struct renderer *r, int samples, char *err, size_t err_size);

/* The mean of every pixel's first `samples` samples (1 < samples <=
 * settings_samples()), from its fixed-point sum on the device, into rgb
 * (width × height × 3 floats): the image of a render stopped after that
 * many, by the kernels' rule (docs/RENDERING.md, "Samples per pixel").
 * Returns 0, or -1 with one message in err. */
int renderer_read_mean(struct renderer *r, int samples, float *rgb, char *err, size_t err_size);

/* The mean of `pixels` fixed-point sums (4 cl_long each, cl/sample.cl) of
 * `samples` samples each into rgb: a saturated channel is +inf. */
void renderer_mean_of_sums(const cl_long *sums, size_t pixels, int samples, float *rgb);

/* A pass of a long render traces about this many samples in all (pixels ×
 * samples of the pass), at least one sample of every pixel: on an H100 a few
 * milliseconds, on a CPU a few seconds, so that progress moves. */
#define RENDER_PASS_PIXEL_SAMPLES (1 << 22)

/* On a GPU a pass takes at least this many samples (when there are as many):
 * fewer, longer launches, whose ends the queues overlap. Measured on H200s
 * (docs/results/multidevice, batches 65-66, 2000x2000): the default scene
 * at 2048 spp took 1557 ms per frame in passes of 1 sample (about 2^22
 * pixel-samples), 1507 in passes of 2 and 1484 in passes of 4; a GPU's half
 * of it on 4 queues 813 in passes of 2 and 800 in passes of 4; passes of 8
 * were slower (863-867 ms for a half on 2 queues). */
#define RENDER_GPU_PASS_SAMPLES 4

/* Returns how many samples of every pixel one pass over a piece of `pixels`
 * pixels traces on a GPU (gpu != 0) or another device:
 * settings->samples_per_pass, else about RENDER_PASS_PIXEL_SAMPLES in all and
 * on a GPU at least RENDER_GPU_PASS_SAMPLES; at least 1, at most
 * settings_samples(). The last pass takes what is left. The image does not
 * depend on it. */
int renderer_pass_samples(const struct render_settings *settings, long long pixels, int gpu);

#endif
