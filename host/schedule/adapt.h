/* Adaptive pieces of one image (tiles.h: the dynamic split in one process,
 * without --piece-rows): the size and place of each device's next piece, from
 * measured rates. tiles.c asks it, under its lock, from the thread pool's
 * take_piece (multidev.h).
 *
 * The policy (guided self-scheduling weighted by measured throughput):
 *  - the image is cut, in scan order of its split rows (tiles.h's row
 *    order: a cell row is one band of the interleaved order), into cells of
 *    one work-group (cell_w x cell_h pixels); a piece is a run of whole
 *    cells that stays a rectangle: part of one cell row, or whole cell rows
 *    (a full-width band) when it starts at a row's beginning. Every piece carries all the samples
 *    of its pixels, so the image stays byte-identical to one device's.
 *  - a device whose rate is not yet known gets a probe: at most
 *    ADAPT_PROBE_PIXEL_SAMPLES and at most 1/16 of a device's fair share,
 *    so a device 220x slower than the fastest (a CPU next to a GPU) costs
 *    the image at most one small piece before its rate is known.
 *  - a device of measured rate r (pixel-samples per ms of busy time, all its
 *    pieces so far) out of a total R gets 1/ADAPT_GUIDE of its fair share of
 *    what is left (remaining work plus the others' work in flight, times
 *    r / R): large pieces first, shrinking towards the end; never less than
 *    ADAPT_FLOOR_MS of its own time (launch overhead and a GPU's occupancy:
 *    on an H200 that is about 10 M pixel-samples), never less than the
 *    device's smallest piece (or, with rates known, the lesser of what
 *    fills it over several launches and its rate-weighted share), never less
 *    than a cell, never past the remaining work, never leaving a rest under
 *    ADAPT_REST_FRACTION of the device's smallest piece (it takes that rest
 *    too: a GPU given a few leftover rows at 1024 spp spent 80 ms on them,
 *    latency-bound), and
 *    never more than ADAPT_GROWTH times
 *    the device's largest piece so far (not its last: a piece cut short at
 *    the end of a cell row must not stop the growth): a rate measured early (a first launch's
 *    set-up, a fast device whose first large piece is still running) must
 *    not hand a slow device a huge piece.
 *  - the tail rule: a device more than ADAPT_TAIL_SLOWER times slower than
 *    the fastest other still working never gets a piece it would finish
 *    after the others could have finished all the remaining work (their
 *    work in flight included) without it; its piece shrinks to what it can
 *    finish by then, and when not even one cell fits it retires for this
 *    frame. The fastest device never retires, so every cell is handed out. Until every device that keeps more pixels
 *    in flight (a GPU, whose first piece may be most of the image) has a
 *    rate, a device with a rate gets nothing more: nothing tells when the
 *    GPU will be done, and a CPU piece of a second or more would hold the
 *    end (docs/results/h100-batch6).
 * Rates persist over the frames of one job (-r N), so later frames need no
 * probe. Times are the caller's (ms), so the policy runs in simulated time
 * in the unit tests. */
#ifndef RTCL_ADAPT_H
#define RTCL_ADAPT_H

#include "rtcl_shared.h"
#include "device/devices.h"

#define ADAPT_PROBE_PIXEL_SAMPLES (1 << 20)
#define ADAPT_FLOOR_MS 4.0
#define ADAPT_GUIDE 2
#define ADAPT_GROWTH 2
/* The tail rule plans a slow device's piece to end by this fraction of the
 * time the others need: its rate was measured on other pixels, and on an
 * H100's Xeon the image's end cost 1.5 times what its probe had
 * (docs/results/h100-batch6). */
#define ADAPT_TAIL_MARGIN 0.5
/* The tail rule holds back only a device this many times slower than the
 * fastest other (a CPU beside a GPU): between devices of about one speed
 * the rates, measured on other pixels, differ by a few per cent, and the
 * rule cut one GPU's share of two short and left a rest that took both
 * GPUs latency-bound pieces (two H200s, batch 60: 1188-1253 ms against
 * 1050 in one piece each). */
#define ADAPT_TAIL_SLOWER 2.0
/* A device takes the rest of the image too when that rest would be less
 * than this fraction of its smallest piece: a GPU given a few leftover rows
 * at 1024 spp spent 80 ms on them, latency-bound. */
#define ADAPT_REST_FRACTION 0.25

/* What the sizing of one device's next piece sees. */
struct adapt_view {
	double remaining;      /* pixel-samples of the image not yet handed out */
	double total;	       /* pixel-samples of the whole image */
	double unit;	       /* pixel-samples of one cell (the smallest piece) */
	double rate;	       /* this device's pixel-samples per ms; 0: unknown */
	double others_rate;    /* the sum of the other working devices' known rates */
	double others_fastest; /* the highest of them */
	double others_backlog; /* pixel-samples the others still have in flight */
	int unknown;	       /* other working devices with no rate yet */
	double largest;	       /* this device's largest piece so far; 0: none */
	int devices;	       /* working devices, this one included */
	double min_size;       /* pixel-samples of the smallest piece that keeps
				  this device busy (adapt_set_min_pixels); 0: none */
	double fill_size;      /* pixel-samples that keep it busy over several
				  launches (adapt_set_fill_pixels); 0: none */
	int front_unknown;     /* a working device that keeps more pixels in flight
				  (a GPU beside this CPU) has no rate yet */
};

/* Pure: the size of the device's next piece in cells (>= 1 and no more
 * cells than the remaining work needs), or 0 when it must take none (the
 * tail rule). */
long long adapt_piece_cells(const struct adapt_view *v);

struct adapt_device {
	double done, busy_ms; /* pixel-samples rendered, in this much busy time */
	double inflight;      /* pixel-samples of the piece it holds, 0: none */
	double largest;	      /* pixel-samples of its largest piece so far */
	double start_ms;      /* when it took that piece */
	int retired;	      /* the tail rule stopped it for this frame */
	int asked;	      /* it has asked for a piece this frame */
	double min_pixels;    /* the pixels one launch keeps in flight on it */
	double fill_pixels;   /* adapt_set_fill_pixels */
};

struct adapt {
	int width, height, samples, cell_w, cell_h, cells_x, cells_y, devices;
	long long next_cell; /* the first cell not yet handed out, in scan order */
	long long end_cell;  /* one past the last cell not yet handed out */
	double handed;	     /* pixel-samples handed out this frame */
	struct adapt_device dev[DEVICES_MAX];
};

void adapt_init(struct adapt *a, int width, int height, int samples, int cell_w, int cell_h,
		int devices);

/* A new frame of the same image: every cell again, the rates kept. */
void adapt_new_frame(struct adapt *a);

/* Sets device k's smallest piece in pixels: its pieces (the probe too) are
 * at least that large, unless the tail rule shrinks them or the image ends.
 * tiles.c sets it from what the device keeps in flight (TILES_GPU_LAUNCHES:
 * small pieces leave a GPU idle at each launch's end). */
void adapt_set_min_pixels(struct adapt *a, int k, double pixels);

/* Sets the pixels that keep device k busy over several launches, which may
 * be more than its smallest piece (tiles.c caps that at the device's equal
 * share, so that several GPUs all get work). Once its rate is known, its
 * piece is at least min(these, its rate-weighted share of what is left),
 * not the equal share: of two GPUs whose halves differ in cost, the faster
 * takes more (batch 63: the default scene's odd bands cost 1.8 % more than
 * its even ones, and each GPU took exactly its half). */
void adapt_set_fill_pixels(struct adapt *a, int k, double pixels);

/* Whether every device that keeps more pixels in flight than device k has
 * asked for a piece this frame. A CPU waits for that (tiles.c) before its
 * first piece: taking its probe first from the image's end would leave a
 * GPU the thin rest of the last cell row as an extra, latency-bound piece
 * (about 80 ms on an H100 at 1024 spp). */
int adapt_fronts_asked(const struct adapt *a, int k);

/* Device k, idle at now_ms (the piece it held, if any, done), asks for its
 * next piece. The devices that keep the most pixels in flight (the GPUs)
 * take their pieces from the image's start, the others from its end, so
 * that a GPU's pieces are whole cell rows rather than the rest of a row a
 * CPU's small piece began (docs/results/h200-batch3: those thin pieces left
 * the GPU 3x slower beside a CPU). Returns 1 with *piece (all samples), or 0: none for k. Not
 * thread-safe: the caller holds a lock. */
int adapt_take(struct adapt *a, int k, double now_ms, struct rt_piece *piece);

#endif
