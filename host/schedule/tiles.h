/* One image over several devices (--devices with more than one, --mpi): the
 * image cut into pieces (renderer.h), each carrying every sample of its
 * pixels: with the dynamic split in one process, rectangles sized per device
 * by adapt.h's policy; with --split static, --piece-rows or
 * --mpi, row bands handed out by dispenser.h. Rectangles and bands are of
 * split rows, which the row order (--row-order, below) maps to image rows, so
 * that equal devices get pieces of equal cost. Each device opens
 * its renderer once, renders the bands it is given into its own full-size
 * buffers, reads them back once at the end; the host copies each band from
 * the device that rendered it. A band's samples all run on one device, in
 * order, so the image is byte-identical to a one-device render. */
#ifndef RTCL_TILES_H
#define RTCL_TILES_H

#include <pthread.h>
#include <stddef.h>
#include <stdint.h>

#include "schedule/adapt.h"
#include "schedule/multidev.h"
#include "render/renderer.h"

/* Bands per device when bands are used and --piece-rows is not given: many, since a band costs
 * only a launch and its wait (0.01 to 0.05 ms on PoCL,
 * docs/results/multidevice) while the last band a slow device takes can end
 * after the fast one is done: with n devices a device k times slower than
 * the fastest delays the end by at most k / (32 n) of the fast device's time
 * for the image. */
#define TILES_PER_DEVICE 32

/* A GPU's smallest adaptive piece, in launches' worth of the work-items it
 * keeps in flight. A launch ends with its slowest work-item, and a pixel
 * behind glass takes ~0.2 ms alone, so small pieces leave a GPU idle: on an
 * H100 at 1024 spp, 2000x2000 in bands of 100, 250, 500, 1000 and 2000 rows
 * took 2.7, 1.7, 1.3, 1.2 and 1.0 times the whole image's kernel time
 * (docs/results/h100-batch6). 16 lets one GPU keep a 2000x2000 image whole
 * beside a CPU; several GPUs split it (set_min_pieces caps it at a share). */
#define TILES_GPU_LAUNCHES 16

/* How long a CPU waits for the GPUs beside it to ask for their first piece
 * of a frame (tiles_take_piece): their threads start together, so this is
 * only a bound. */
#define TILES_FRONT_WAIT_MS 200

/* What a GPU's share of the pixels costs beyond that share of the whole
 * image's time, at the least: a share's launches have fewer pixels, and each
 * ends with its slowest work-items (the idle end). Measured on H200s
 * (docs/results/multidevice, batch 66): one GPU rendering the two
 * interleaved halves of the default scene one after the other took 4.8 %
 * more than the whole image, the lake's halves 6.5 %; smaller shares (more
 * devices) cost more. The default split weighs it against the sample
 * split's fixed cost (tiles_prefer_samples). */
#define TILES_SHARE_PENALTY 0.048

/* The most threads that add devices' sums (tiles_add_sums, and the image
 * of the sample split after its frames): the adds of four 2000x2000 images'
 * sums (512 MB read) are bound by the host's memory, of which 8 threads
 * use a part on a 64-core host (four H100s, batch 95). */
#define TILES_SUM_THREADS 32

/* The order in which pieces take the image's rows (--row-order;
 * docs/GUIDE.md, "How the rows are ordered"): a piece is a rectangle of split
 * rows, and split row v is image row rt_piece_row(v) (cl/rtcl_shared.h).
 *  ROWS_INTERLEAVE: bands of a work-group's height dealt to S classes
 *               (tiles_row_classes, or --row-order interleave:S), a class's
 *               bands top to bottom: an equal share is every S-th band;
 *  ROWS_SCAN:   split row v is image row v: contiguous pieces. */
enum row_order { ROWS_INTERLEAVE, ROWS_SCAN };

/* The most classes --row-order interleave:S takes. */
#define ROWS_CLASSES_MAX 4096

/* The height of the bands ROWS_INTERLEAVE deals: the work-group's height
 * (8 when the device chooses it), which is also the adaptive dispenser's cell
 * height, so that a cell row is one band. */
int tiles_row_band(const struct render_settings *s);

/* The classes ROWS_INTERLEAVE deals to by default: the GPUs among devs (the
 * devices that take an equal share each; a CPU beside them takes small
 * pieces from the image's end), else every device. */
int tiles_row_classes(const struct device *devs, int count);

/* Sets map's row map (its row_* fields) for an image of settings s in
 * `order`, dealing to `classes` classes (interleave:S, else
 * tiles_row_classes). */
void tiles_row_map(struct rt_piece *map, const struct render_settings *s, enum row_order order,
		   int classes);

/* Rows per band: piece_rows when given (> 0), else about height / (32 ×
 * devices) for the dynamic split, height / devices for the static one (each
 * device takes its share in one band: more bands would only add launches,
 * smaller ones, and with the rows interleaved one band is one device's
 * class), rounded up to a multiple of the work-group height. */
int tiles_band_rows(const struct render_settings *s, int piece_rows, int devices,
		    enum split split);

/* Band `index` of bands of `rows` rows (the last may be shorter), samples
 * [begin, end). */
struct rt_piece tiles_band(const struct render_settings *s, int rows, int index, int begin,
			   int end);

/* One device's renderer and what it read back. */
struct tiles_device {
	struct renderer renderer;
	struct render_result result;
	int open;
	int collected; /* read back */
	cl_long *sums; /* SPLIT_SAMPLES: its pixels' sums, read after each frame,
			  sums_header bytes into `block`, on a page
			  (base/pages.h), or in `pinned` (one process) */
	char *block;
	cl_mem pinned; /* the sums' pinned host memory (device_pinned_alloc) */
	double probe_ms; /* tiles_open's probe: one pass of the whole image (the
			    faster of two) */
	double probe_kernel_ms; /* that pass's profiled kernels: probe_ms less
				   them is its host time (round trips) */
	double sums_ms;	 /* tiles_open's probe: reading all the sums back */
	int probe_passes; /* the probe's passes, a write of each pixel each
			     (check_writes) */
};

/* The pieces of one image on devs[count] of this process: the bands of
 * `rows` rows, or (adaptive) the rectangles adapt.h's policy cuts each
 * frame. */
struct tiles_job {
	const struct render_settings *settings;
	const struct scene *scene;
	struct device *devs;
	int count;
	int rows, bands;
	int adaptive;		 /* pieces from `adapt`, not bands */
	int by_samples;		 /* SPLIT_SAMPLES: piece k, device k's, is the whole
				    image with a range of the samples */
	double samples_done[DEVICES_MAX], samples_ms[DEVICES_MAX]; /* by_samples:
					    each device's samples and its busy
					    time, all frames so far */
	double add_ms;			 /* tiles_open_all's probe: the host's add
					    of every device's sums */
	double sample_rate[DEVICES_MAX]; /* by_samples: each device's samples per
					    ms of busy time, all frames so far
					    (0 before the first) */
	size_t sums_header;		 /* by_samples: bytes kept before each
					    device's sums (a message's header,
					    under --mpi), a multiple of 8 */
	struct rt_piece row_map; /* the row map every piece gets (tiles_row_map) */
	int probe;		 /* tiles_open measures each device for the
				    default split (tiles_prefer_samples) */
	int sums_later;		 /* by_samples: a piece leaves its sums on the
				    device, for the caller to read (--mpi) */
	struct rt_piece *pieces; /* the last frame's pieces (the bands, in order) */
	int *owner;		 /* each piece's device (index into devs) */
	double *piece_ms;	 /* each piece's start, end (from frame_start) and
				    kernel time, 3 per piece */
	double frame_start;	 /* the frame's start (timing_now, seconds) */
	int frame_samples;	 /* by_samples: the samples of every pixel the frame's
				    pieces traced, all of them or fewer when an
				    interrupt stopped them (settings->stoppable) */
	int piece_count, piece_cap;
	uint32_t *expected; /* check_writes: each pixel's launches so far, all frames */
	struct adapt adapt;
	pthread_mutex_t lock; /* adaptive: adapt, pieces, piece_count */
	pthread_cond_t asked; /* adaptive: a device asked for its first piece */
	struct tiles_device dev[DEVICES_MAX];
};

/* Returns 0, or -1 with one message in err (out of memory). With adaptive,
 * rows is ignored and the pieces are cut per frame. Every piece takes its
 * rows by map's row map (tiles_row_map). */
int tiles_job_init(struct tiles_job *t, const struct scene *scene, const struct render_settings *s,
		   int rows, int adaptive, const struct rt_piece *map, struct device *devs,
		   int count, char *err, size_t err_size);

/* The job's band `index` (tiles_band of its rows) with its row order,
 * samples [begin, end). */
struct rt_piece tiles_job_band(const struct tiles_job *t, int index, int begin, int end);

/* Copies the pixels of piece p (x0.. of each split row, in order) from the
 * full-size image `from` to the packed rows `to` (p->width * p->height
 * pixels), or back when unpack is set. */
void tiles_pack_piece(const struct rt_piece *p, int image_width, const float *from, float *to,
		      int unpack);

/* Adaptive: the next piece for device k (its previous one done), added to
 * the job's pieces; returns its index, or -1 when there is none for k. */
int tiles_take_piece(struct tiles_job *t, int k);

/* Releases every renderer and what they read back. */
void tiles_job_free(struct tiles_job *t);

/* multidev callbacks' bodies: opens device k's renderer (once); renders band
 * on device k and records it as k's. */
int tiles_open(struct tiles_job *t, int k, char *err, size_t err_size);
int tiles_render_band(struct tiles_job *t, int k, int band, struct piece_work *done, char *err,
		      size_t err_size);

/* Launches that cover each pixel of piece once (its samples in passes). */
int tiles_piece_launches(const struct render_settings *s, const struct rt_piece *piece, int gpu);

/* Reads back device k's image (and counts), once. */
int tiles_collect(struct tiles_job *t, int k, char *err, size_t err_size);

/* Copies piece's pixels of from's image (and per-pixel flops when both hold
 * them) into to. */
/* Copies the pixels of piece p from the full-size image `from` to the
 * full-size image `to`, each row where the row map puts it. */
void tiles_copy_rows(const struct rt_piece *p, int image_width, const float *from, float *to);

void tiles_copy_piece(const struct tiles_job *t, int piece, const struct render_result *from,
		      struct render_result *to);

/* Checks write counts: every pixel of the image counted `expected` times
 * (check_writes). Returns 0, or -1 with the first pixel that was not in err. */
int tiles_check_counts(const uint32_t *counts, int width, int height, uint32_t expected, char *err,
		       size_t err_size);

/* The plan and build facts the summary shows (work-groups, NDRange, build
 * options, set-up times), from one device's result: the first device's. */
void tiles_copy_facts(const struct render_result *from, struct render_result *to);

/* With check_writes, after one frame: device k's write counts are each
 * piece's launches in the pieces it rendered and 0 elsewhere, plus its
 * set-up probe's launches (probe_ms) everywhere. Returns 0, or -1
 * with the first pixel that was not in err. */
int tiles_check_device(const struct tiles_job *t, int k, char *err, size_t err_size);

/* How the default split was chosen by measurement (tiles_prefer_samples):
 * set-up's probes and the prediction, all in ms. */
struct split_choice {
	int measured;	   /* the choice was made by these figures */
	double pass_ms;	   /* the slowest device's probe: one pass of the whole
			      image, pass_samples of every pixel */
	int pass_samples;
	double render_ms;  /* every sample over all devices, by their probes'
			      rates: the image's time without fixed costs */
	double sums_ms;	   /* the slowest device's read-back of all its sums,
			      in each frame */
	double add_ms;	   /* the host's add of the devices' sums, once after
			      the frames: with sums_ms the sample split's
			      cost beyond render_ms */
	double overhead_ms; /* a pass's time beyond its kernels (the slowest
			       device's probe: host round trips, e.g. a
			       wavefront's per bounce) times the image's
			       passes: each device of a pixel split pays all
			       of it, of the sample split a 1/count share; so
			       the pixel split's extra is (1 - 1/count) of it */
	double move_ms;	   /* --mpi: the pixels of the other ranks' shares
			      sent to rank 0, timed before the clock; 0 in one
			      process */
	double penalty_ms; /* TILES_SHARE_PENALTY of render_ms plus
			      overhead_ms and move_ms: the pixel split's cost
			      beyond render_ms, at the least */
};

/* One image over devices of this process: which, and how it is cut. */
struct tiles_request {
	const struct scene *scene;
	struct device *devs;
	int count;
	enum split split; /* SPLIT_STATIC: bands, handed out statically */
	int piece_rows;	  /* --piece-rows: bands of this height; 0: chosen */
	enum row_order row_order; /* --row-order */
	int row_classes;	  /* --row-order interleave:S; 0: the devices */
	int measure;		  /* SPLIT_SAMPLES by default: kept only if the
				     devices' measured costs favour it
				     (tiles_prefer_samples); tiles_render then
				     sets split to what it chose and fills
				     choice */
	struct split_choice choice;
};

/* The split of one image over r's devices for --split r->split, given or
 * not (docs/GUIDE.md, "Several devices"): SPLIT_SAMPLES when asked; by
 * default SPLIT_SAMPLES with *measure set when every device is a GPU and the
 * render can split its samples (tiles_samples_fit), which tiles_render keeps
 * only if the devices' measured costs favour it (tiles_prefer_samples), else
 * the dynamic split; else r->split. Returns -1 with one message in err when
 * --split samples was asked of a render it cannot split. */
int tiles_choose_split(const struct tiles_request *r, const struct render_settings *s, int given,
		       enum split *split, int *measure, char *err, size_t err_size);

/* Whether the default split takes the samples, from set-up's probes: every
 * device's sums read back (sums_ms[k]), one pass of pass_samples samples of
 * the whole image rendered (pass_ms[k], of which its kernels took
 * kernel_ms[k]), and the host's add of all the sums (add_ms); under --mpi
 * the time the other ranks' shares of the pixels take to reach rank 0
 * (move_ms, else 0). The sample split costs the image's time on all
 * devices (render_ms: the samples over the sum of the devices' rates) plus
 * the slowest read-back and the add; a split of the pixels costs
 * TILES_SHARE_PENALTY more than render_ms at the least, plus the passes'
 * host time that each of its devices pays whole (overhead_ms) and move_ms.
 * Fills c; returns 1 for the samples when sums_ms + add_ms <= penalty_ms. */
int tiles_prefer_samples(const double *pass_ms, const double *kernel_ms, const double *sums_ms,
			 int count, int pass_samples, int samples, double add_ms, double move_ms,
			 struct split_choice *c);

/* --split samples asked of `count` devices: 0 when the render has a sample
 * for each (and 2 or more), else -1 with one message in err (which may be
 * NULL with err_size 0). */
int tiles_check_sample_split(const struct render_settings *s, int count, char *err,
			     size_t err_size);

/* Whether a render of settings s can split its samples over `count` devices
 * (SPLIT_SAMPLES): 2 samples or more and one for each device, nothing
 * counted or recorded per pixel, no --piece-rows. */
int tiles_samples_fit(const struct render_settings *s, int count, int piece_rows);

/* SPLIT_SAMPLES: makes the job's pieces 0..total-1 the whole image, each
 * with a range of every pixel's samples (sum_begin its first), in whole
 * passes of `unit` samples (1 when there are fewer passes than pieces),
 * shared by rate[] (NULL: equally), each piece at least one; the ranges
 * follow one another from sample 0. Piece k is global device k's: under
 * --mpi, of every rank's devices. Returns 0, or -1 when out of memory. */
int tiles_split_samples(struct tiles_job *t, int total, int unit, const double *rate);

/* The largest renderer_pass_samples of the whole image among devs (a GPU's
 * passes take at least RENDER_GPU_PASS_SAMPLES): the unit of the sample
 * split, so that each device's passes are whole. */
int tiles_sample_unit(const struct render_settings *s, const struct device *devs, int count);

/* Opens every device's renderer (tiles_open), each in its own thread (build
 * and upload overlap), before the timed frames; each one's time in
 * setup[k].setup_ms. Returns 0, or -1 with the first failed device's message
 * in err (a device that failed stays closed: tiles_open tries again). */
int tiles_open_all(struct tiles_job *t, struct device_work *setup, char *err, size_t err_size);

/* SPLIT_SAMPLES: device k's host copy of its sums (t->sums_header bytes into
 * its block), allocated and touched once: tiles_open does it, or the caller
 * before, to keep it out of a timed render. Returns 0, or -1 with one
 * message in err. */
int tiles_alloc_sums(struct tiles_job *t, int k, char *err, size_t err_size);

/* Adds from's sums of `pixels` pixels to to's (cl/sample.cl: 4 cl_long a
 * pixel, the channels' sums added, their saturation bits joined). */
void tiles_add_sums(cl_long *to, const cl_long *from, size_t pixels);

/* The job splits no samples after all (the measured choice took the
 * pixels): by_samples cleared, each device's sums freed. */
void tiles_drop_sums(struct tiles_job *t);

/* The sum of `count` parts' sums of `pixels` pixels into to (which may be
 * one of the parts), as tiles_add_sums, over up to `threads` threads. */
void tiles_sum_parts(const cl_long *const *parts, int count, cl_long *to, size_t pixels,
		     int threads);

/* The image's mean colours from every pixel's sum of all its samples
 * (docs/RENDERING.md, "Samples per pixel"): float(S) times the mean's
 * scale, as a kernel's last pass takes it; +inf where a channel saturated. */
void tiles_mean_of_sums(const struct render_settings *s, const cl_long *sums, float *rgb);

/* tiles_mean_of_sums of the sum of count parts' sums (each a range of every
 * pixel's samples, together all of them), in one pass over up to
 * TILES_SUM_THREADS threads. */
void tiles_mean_of_parts(const struct render_settings *s, const cl_long *const *parts, int count,
			 float *rgb);

/* Whether the pieces come from the adaptive dispenser (multidev.h): unless
 * --split static or --piece-rows (a fixed band height) asks for bands. */
int tiles_adaptive(enum split split, int piece_rows);

/* Bands of `rows` rows in an image of `height` rows. */
int tiles_band_count(int height, int rows);

/* One image with settings s over r's devices into out (-r: one warm-up, N
 * timed frames, each the whole image over every device), and what each
 * device did into work[r->count]. With r->measure, the devices are probed at
 * set-up and r->split becomes the split chosen (r->choice says why). Returns 0, or -1 with one message in err
 * and nothing held in out. */
int tiles_render(struct tiles_request *r, const struct render_settings *s,
		 struct device_work *work, struct render_result *out, char *err, size_t err_size);

#endif
