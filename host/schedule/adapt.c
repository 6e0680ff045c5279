#include "schedule/adapt.h"

#include <math.h>
#include <string.h>

static double min_d(double a, double b)
{
	return a < b ? a : b;
}

/* A probe: small against the image and a device's share of it. */
static double probe_size(const struct adapt_view *v)
{
	return min_d(ADAPT_PROBE_PIXEL_SAMPLES, v->total / (16.0 * v->devices));
}

/* Guided: 1/ADAPT_GUIDE of the device's share of what is left, not under
 * ADAPT_FLOOR_MS of its time. A device still probing counts as fast as this
 * one, so the first to know its rate does not take half the image. */
/* The device's rate-weighted share of what is left and of the others'
 * work in flight; a device still probing counts as fast as this one. */
static double rate_share(const struct adapt_view *v)
{
	double all = v->rate * (1 + v->unknown) + v->others_rate;

	return (v->remaining + v->others_backlog) * v->rate / all;
}

static double guided_size(const struct adapt_view *v)
{
	double size = rate_share(v) / ADAPT_GUIDE;

	return size > v->rate * ADAPT_FLOOR_MS ? size : v->rate * ADAPT_FLOOR_MS;
}

long long adapt_piece_cells(const struct adapt_view *v)
{
	double size, cells_left;

	if (v->remaining <= 0 || v->unit <= 0)
		return 0;
	cells_left = ceil(v->remaining / v->unit);
	size = v->rate > 0 ? guided_size(v) : probe_size(v);
	if (v->largest > 0)
		size = min_d(size, ADAPT_GROWTH * v->largest);
	double least = v->min_size;
	if (v->rate > 0 && v->fill_size > 0)
		least = min_d(v->fill_size, rate_share(v));
	if (size < least)
		size = least;
	if (v->remaining - size < ADAPT_REST_FRACTION * v->min_size) /* no sliver left */
		size = v->remaining;
	if (v->rate > 0 && v->front_unknown)
		return 0;
	if (v->rate > 0 && v->rate * ADAPT_TAIL_SLOWER < v->others_fastest && v->others_rate > 0) {
		/* The tail rule, for a much slower device: done no later than
		 * the others could be with all the rest, with a margin for the
		 * pixels' costs. */
		double others_done_ms = (v->remaining + v->others_backlog) / v->others_rate;
		size = min_d(size, ADAPT_TAIL_MARGIN * v->rate * others_done_ms);
		if (min_d(v->unit, v->remaining) > size)
			return 0;
	}
	size = floor(size / v->unit);
	return size < 1 ? 1 : size > cells_left ? (long long)cells_left : (long long)size;
}

void adapt_init(struct adapt *a, int width, int height, int samples, int cell_w, int cell_h,
		int devices)
{
	memset(a, 0, sizeof(*a));
	a->width = width;
	a->height = height;
	a->samples = samples > 0 ? samples : 1;
	a->cell_w = cell_w > 0 ? cell_w : 1;
	a->cell_h = cell_h > 0 ? cell_h : 1;
	a->cells_x = (width + a->cell_w - 1) / a->cell_w;
	a->cells_y = (height + a->cell_h - 1) / a->cell_h;
	a->devices = devices;
	a->end_cell = (long long)a->cells_x * a->cells_y;
}

void adapt_new_frame(struct adapt *a)
{
	a->next_cell = 0;
	a->end_cell = (long long)a->cells_x * a->cells_y;
	a->handed = 0;
	for (int k = 0; k < a->devices; k++) {
		a->dev[k].inflight = 0;
		a->dev[k].retired = 0;
		a->dev[k].asked = 0;
	}
}

static double rate_of(const struct adapt_device *d)
{
	return d->busy_ms > 0 ? d->done / d->busy_ms : 0;
}

/* What device k sees at now_ms. */
static struct adapt_view adapt_view_of(const struct adapt *a, int k, double now_ms)
{
	struct adapt_view v = {.total = (double)a->width * a->height * a->samples,
			       .unit = (double)a->cell_w * a->cell_h * a->samples,
			       .rate = rate_of(&a->dev[k]),
			       .largest = a->dev[k].largest};

	v.min_size = a->dev[k].min_pixels * a->samples;
	v.fill_size = a->dev[k].fill_pixels * a->samples;

	v.remaining = v.total - a->handed;
	for (int j = 0; j < a->devices; j++) {
		const struct adapt_device *d = &a->dev[j];
		double r = rate_of(d);
		if (d->retired)
			continue;
		v.devices++;
		if (j == k)
			continue;
		v.others_rate += r;
		v.others_fastest = r > v.others_fastest ? r : v.others_fastest;
		v.unknown += r <= 0;
		v.front_unknown |= r <= 0 && d->min_pixels > a->dev[k].min_pixels;
		if (d->inflight > 0 && r > 0) /* what it has left of its piece */
			v.others_backlog += fmax(0, d->inflight - r * (now_ms - d->start_ms));
	}
	return v;
}

/* A rectangle of cells: columns [col, col + cols) of rows [row, row + rows). */
static struct rt_piece cell_rect(const struct adapt *a, int col, int row, int cols, int rows)
{
	struct rt_piece p = {0};

	p.x0 = col * a->cell_w;
	p.y0 = row * a->cell_h;
	p.width = (int)min_d(cols * a->cell_w, a->width - p.x0);
	p.height = (int)min_d(rows * a->cell_h, a->height - p.y0);
	p.sample_begin = 0;
	p.sample_end = p.samples = a->samples;
	return p;
}

/* The next `cells` cells from the front cursor as a rectangle: whole rows
 * when it stands at a row's start, else the rest of its row (fewer cells
 * when the row or the cells not yet handed out end first). */
static struct rt_piece cut_front(struct adapt *a, long long cells)
{
	long long left = a->end_cell - a->next_cell;
	int col = (int)(a->next_cell % a->cells_x), row = (int)(a->next_cell / a->cells_x);
	long long rows = min_d((double)cells, (double)left) / a->cells_x;

	if (col == 0 && rows >= 1) {
		a->next_cell += rows * a->cells_x;
		return cell_rect(a, 0, row, a->cells_x, (int)rows);
	}
	int cols = (int)min_d(min_d((double)cells, (double)left), a->cells_x - col);
	a->next_cell += cols;
	return cell_rect(a, col, row, cols, 1);
}

/* The last `cells` cells before the back cursor, the same way from the end. */
static struct rt_piece cut_back(struct adapt *a, long long cells)
{
	long long left = a->end_cell - a->next_cell;
	int col_end = (int)(a->end_cell % a->cells_x), row_end = (int)(a->end_cell / a->cells_x);
	long long rows = min_d((double)cells, (double)left) / a->cells_x;

	if (col_end == 0 && rows >= 1) {
		a->end_cell -= rows * a->cells_x;
		return cell_rect(a, 0, row_end - (int)rows, a->cells_x, (int)rows);
	}
	if (col_end == 0) { /* the row above the cursor, from its end */
		col_end = a->cells_x;
		row_end--;
	}
	int cols = (int)min_d(min_d((double)cells, (double)left), col_end);
	a->end_cell -= cols;
	return cell_rect(a, col_end - cols, row_end, cols, 1);
}

/* Whether device k takes its pieces from the image's end: it keeps fewer
 * pixels in flight than another device. */
static int takes_from_back(const struct adapt *a, int k)
{
	for (int j = 0; j < a->devices; j++)
		if (a->dev[j].min_pixels > a->dev[k].min_pixels)
			return 1;
	return 0;
}

int adapt_fronts_asked(const struct adapt *a, int k)
{
	for (int j = 0; j < a->devices; j++)
		if (a->dev[j].min_pixels > a->dev[k].min_pixels && !a->dev[j].asked)
			return 0;
	return 1;
}

void adapt_set_min_pixels(struct adapt *a, int k, double pixels)
{
	a->dev[k].min_pixels = pixels;
}

void adapt_set_fill_pixels(struct adapt *a, int k, double pixels)
{
	a->dev[k].fill_pixels = pixels;
}

int adapt_take(struct adapt *a, int k, double now_ms, struct rt_piece *piece)
{
	struct adapt_device *d = &a->dev[k];
	long long cells;

	d->asked = 1;
	if (d->inflight > 0) {
		d->done += d->inflight;
		d->busy_ms += now_ms - d->start_ms;
		d->largest = d->inflight > d->largest ? d->inflight : d->largest;
		d->inflight = 0;
	}
	if (d->retired || a->next_cell >= a->end_cell)
		return 0;
	struct adapt_view v = adapt_view_of(a, k, now_ms);
	cells = adapt_piece_cells(&v);
	if (cells == 0) {
		d->retired = 1;
		return 0;
	}
	*piece = takes_from_back(a, k) ? cut_back(a, cells) : cut_front(a, cells);
	d->inflight = (double)piece->width * piece->height * a->samples;
	d->start_ms = now_ms;
	a->handed += d->inflight;
	return 1;
}
