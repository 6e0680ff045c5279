/* The work map (see workmap.h): viridis colours, the scale bar and its
 * bitmap font. */
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/version.h"
#include "base/files.h"
#include "output/image.h"
#include "base/quote.h"
#include "output/workmap.h"

/* Bar layout, in font pixels (multiplied by the font scale): a margin, the
 * gradient strip, ticks hanging from it, a gap, the line of labels, a gap,
 * the line naming the unit and a margin again. */
#define BAR_MARGIN 4
#define STRIP_HEIGHT 10
#define TICK_HEIGHT 3
#define LABEL_GAP 2
#define UNIT_GAP 3
#define GLYPH_HEIGHT 7
#define BAR_HEIGHT                                                                                 \
	(BAR_MARGIN + STRIP_HEIGHT + TICK_HEIGHT + LABEL_GAP + GLYPH_HEIGHT + UNIT_GAP +           \
	 GLYPH_HEIGHT + BAR_MARGIN)
/* Least space between two labels, in font pixels. */
#define LABEL_SPACING 3
/* Image width per step of the font scale: 1x below 800 pixels, 3x at 2000. */
#define WIDTH_PER_SCALE 800

static const float bar_background[3] = {0.08f, 0.08f, 0.08f};
static const float label_colour[3] = {1.0f, 1.0f, 1.0f};

/* The unit line under the labels, by scale. */
static const char unit_linear[] = "flops per pixel, linear scale";
static const char unit_log[] = "flops per pixel, log scale";

/* A 5×7 font ('.', ',' and ' ' are narrower) for the labels: '#' is ink.
 * Only what the bar prints: format_count()'s digits, '.' and suffixes k, M,
 * G, and the letters of the unit lines. */
static const struct glyph {
	char ch;
	const char *rows[GLYPH_HEIGHT];
} font[] = {
	{'0', {".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."}},
	{'1', {"..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."}},
	{'2', {".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"}},
	{'3', {"#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###."}},
	{'4', {"...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."}},
	{'5', {"#####", "#....", "####.", "....#", "....#", "#...#", ".###."}},
	{'6', {"..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###."}},
	{'7', {"#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."}},
	{'8', {".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."}},
	{'9', {".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.."}},
	{'.', {"..", "..", "..", "..", "..", "##", "##"}},
	{'k', {"#....", "#....", "#..#.", "#.#..", "##...", "#.#..", "#..#."}},
	{'M', {"#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#"}},
	{'G', {".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".###."}},
	{' ', {"...", "...", "...", "...", "...", "...", "..."}},
	{',', {"..", "..", "..", "..", "..", ".#", "#."}},
	{'a', {".....", ".....", ".###.", "....#", ".####", "#...#", ".####"}},
	{'c', {".....", ".....", ".###.", "#....", "#....", "#...#", ".###."}},
	{'e', {".....", ".....", ".###.", "#...#", "#####", "#....", ".###."}},
	{'f', {"..##.", ".#..#", ".#...", "###..", ".#...", ".#...", ".#..."}},
	{'g', {".....", ".####", "#...#", "#...#", ".####", "....#", ".###."}},
	{'i', {"..#..", ".....", ".##..", "..#..", "..#..", "..#..", ".###."}},
	{'l', {".##..", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."}},
	{'n', {".....", ".....", "#.##.", "##..#", "#...#", "#...#", "#...#"}},
	{'o', {".....", ".....", ".###.", "#...#", "#...#", "#...#", ".###."}},
	{'p', {".....", ".....", "####.", "#...#", "####.", "#....", "#...."}},
	{'r', {".....", ".....", "#.##.", "##..#", "#....", "#....", "#...."}},
	{'s', {".....", ".....", ".####", "#....", ".###.", "....#", "####."}},
	{'x', {".....", ".....", "#...#", ".#.#.", "..#..", ".#.#.", "#...#"}},
};

/* Where the parts of the bar go, in image pixels. */
struct bar_layout {
	int scale;		     /* font pixel size */
	int top;		     /* first row of the bar */
	int strip_left, strip_right; /* inclusive columns of the gradient strip */
	int strip_top, label_top;
};

/* A label's columns, [left, right). */
struct span {
	int left, right;
};

/* Viridis at t in [0, 1]: the degree-6 polynomial fit by mattz (CC0),
 * clamped to [0, 1]. */
static void viridis(double t, float rgb[3])
{
	static const double c[7][3] = {
		{0.2777273272234177, 0.005407344544966578, 0.3340998053353061},
		{0.1050930431085774, 1.404613529898575, 1.384590162594685},
		{-0.3308618287255563, 0.214847559468213, 0.09509516302823659},
		{-4.634230498983486, -5.799100973351585, -19.33244095627987},
		{6.228269936347081, 14.17993336680509, 56.69055260068105},
		{4.776384997670288, -13.74514537774601, -65.35303263337234},
		{-5.435455855934631, 4.645852612178535, 26.3124352495832},
	};
	int i, k;

	for (k = 0; k < 3; k++) {
		double v = c[6][k];

		for (i = 5; i >= 0; i--)
			v = c[i][k] + t * v;
		rgb[k] = (float)(v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v);
	}
}

/* Prints a count in at most 4 significant characters plus a suffix:
 * "0", "0.5", "999", "1.23k", "45.6M", "789G", "12345G". */
static void format_count(double value, char *text, size_t size)
{
	static const char suffixes[] = "kMG";
	int s = -1;

	if (value < 999.5) {
		snprintf(text, size, value == (double)(uint64_t)value ? "%.0f" : "%.1f", value);
		return;
	}
	while (s < 2 && value >= 999.5) {
		value /= 1000.0;
		s++;
	}
	snprintf(text, size, "%.*f%c",
		 value >= 99.95	  ? 0
		 : value >= 9.995 ? 1
				  : 2,
		 value, suffixes[s]);
}

static const struct glyph *find_glyph(char ch)
{
	size_t i;

	for (i = 0; i < sizeof(font) / sizeof(font[0]); i++)
		if (font[i].ch == ch)
			return &font[i];
	return NULL;
}

/* Returns the width in image pixels of text drawn at `scale`. */
static int text_width(const char *text, int scale)
{
	const struct glyph *g;
	int width = 0;

	for (; *text; text++)
		if ((g = find_glyph(*text)))
			width += ((int)strlen(g->rows[0]) + 1) * scale;
	return width > 0 ? width - scale : 0;
}

/* Fills columns [x0, x1) of rows [y0, y1) with colour, clipped to the image. */
static void fill_rect(float *rgb, int width, int height, int x0, int y0, int x1, int y1,
		      const float colour[3])
{
	int x, y;

	for (y = y0 < 0 ? 0 : y0; y < y1 && y < height; y++)
		for (x = x0 < 0 ? 0 : x0; x < x1 && x < width; x++)
			memcpy(&rgb[3 * ((size_t)y * (size_t)width + (size_t)x)], colour,
			       3 * sizeof(float));
}

/* Draws text with its top left corner at (x, y), each font pixel a
 * scale × scale square. */
static void draw_text(float *rgb, int width, int height, int x, int y, int scale, const char *text)
{
	const struct glyph *g;
	int row, col;

	for (; *text; text++) {
		if (!(g = find_glyph(*text)))
			continue;
		for (row = 0; row < GLYPH_HEIGHT; row++)
			for (col = 0; g->rows[row][col]; col++)
				if (g->rows[row][col] == '#')
					fill_rect(rgb, width, height, x + col * scale,
						  y + row * scale, x + (col + 1) * scale,
						  y + (row + 1) * scale, label_colour);
		x += ((int)strlen(g->rows[0]) + 1) * scale;
	}
}

static int font_scale(int width)
{
	return width / WIDTH_PER_SCALE + 1;
}

/* The unit line: wide enough for the longer of the two. */
static int unit_width(int scale)
{
	int linear = text_width(unit_linear, scale), log = text_width(unit_log, scale);

	return linear > log ? linear : log;
}

void workmap_bar_size(int width, int *bar_width, int *bar_height)
{
	int scale = font_scale(width > 0 ? width : 1);
	int least = unit_width(scale) + 2 * BAR_MARGIN * scale;

	*bar_width = width > least ? width : least;
	*bar_height = BAR_HEIGHT * scale;
}

/* The layout of a bar `width` pixels wide, drawn for a map `map_width` wide
 * (which sets the font scale). */
static struct bar_layout bar_layout(int width, int map_width)
{
	struct bar_layout bar;
	int margin;

	bar.scale = font_scale(map_width);
	margin = BAR_MARGIN * bar.scale;
	if (margin > width / 8)
		margin = width / 8; /* narrow images: keep the strip wide */
	bar.top = 0;
	bar.strip_left = margin;
	bar.strip_right = width - 1 - margin;
	bar.strip_top = BAR_MARGIN * bar.scale;
	bar.label_top = bar.strip_top + (STRIP_HEIGHT + TICK_HEIGHT + LABEL_GAP) * bar.scale;
	return bar;
}

/* Where count lies on the scale, 0 to 1 (0 when max is 0). */
static double scale_position(uint64_t count, uint64_t max, enum workmap_scale scale)
{
	if (!max)
		return 0.0;
	if (scale == WORKMAP_LOG)
		return log1p((double)count) / log1p((double)max);
	return (double)count / (double)max;
}

/* The count at position t of the scale: the inverse of scale_position. */
static double scale_value(double t, uint64_t max, enum workmap_scale scale)
{
	if (scale == WORKMAP_LOG)
		return expm1(t * log1p((double)max));
	return t * (double)max;
}

/* Colours the map. */
static void draw_map(float *rgb, const uint64_t *pixel_flops, size_t pixels, uint64_t max,
		     enum workmap_scale scale)
{
	for (size_t i = 0; i < pixels; i++)
		viridis(scale_position(pixel_flops[i], max, scale), &rgb[3 * i]);
}

/* Background, the strip from viridis(0) at its left end to viridis(1) at its
 * right end, and ticks below both ends and the middle. */
static void draw_strip(float *rgb, int width, int height, const struct bar_layout *bar)
{
	int span = bar->strip_right - bar->strip_left;
	int strip_bottom = bar->strip_top + STRIP_HEIGHT * bar->scale;
	int tick_bottom = strip_bottom + TICK_HEIGHT * bar->scale;
	int middle = bar->strip_left + span / 2 - bar->scale / 2;
	float colour[3];
	int x;

	fill_rect(rgb, width, height, 0, bar->top, width, height, bar_background);
	for (x = bar->strip_left; x <= bar->strip_right; x++) {
		viridis(span > 0 ? (double)(x - bar->strip_left) / span : 0.0, colour);
		fill_rect(rgb, width, height, x, bar->strip_top, x + 1, strip_bottom, colour);
	}
	fill_rect(rgb, width, height, bar->strip_left, strip_bottom, bar->strip_left + bar->scale,
		  tick_bottom, label_colour);
	fill_rect(rgb, width, height, middle, strip_bottom, middle + bar->scale, tick_bottom,
		  label_colour);
	fill_rect(rgb, width, height, bar->strip_right + 1 - bar->scale, strip_bottom,
		  bar->strip_right + 1, tick_bottom, label_colour);
}

/* Returns whether a label at columns [left, left + text_width) lies inside
 * the image and keeps LABEL_SPACING from every label in placed[count]. */
static int label_fits(int left, int text_width, int width, int spacing, const struct span *placed,
		      int count)
{
	int i;

	if (left < 0 || left + text_width > width)
		return 0;
	for (i = 0; i < count; i++)
		if (left < placed[i].right + spacing &&
		    placed[i].left < left + text_width + spacing)
			return 0;
	return 1;
}

/* Labels "0", max and the middle of the scale, in that order of priority; a
 * label that would leave the image or crowd one already placed is left out.
 * Below them, centred, the unit and the scale. */
static void draw_labels(float *rgb, int width, int height, const struct bar_layout *bar,
			uint64_t max, enum workmap_scale scale)
{
	const char *unit = scale == WORKMAP_LOG ? unit_log : unit_linear;
	struct span placed[3];
	char text[3][32];
	int left[3], i, w, count = 0;
	int spacing = LABEL_SPACING * bar->scale;

	format_count(0.0, text[0], sizeof(text[0]));
	format_count((double)max, text[1], sizeof(text[1]));
	format_count(scale_value(0.5, max, scale), text[2], sizeof(text[2]));
	left[0] = bar->strip_left;
	left[1] = bar->strip_right + 1 - text_width(text[1], bar->scale);
	left[2] = bar->strip_left + (bar->strip_right - bar->strip_left + 1) / 2 -
		  text_width(text[2], bar->scale) / 2;

	for (i = 0; i < 3; i++) {
		w = text_width(text[i], bar->scale);
		if (!label_fits(left[i], w, width, spacing, placed, count))
			continue;
		draw_text(rgb, width, height, left[i], bar->label_top, bar->scale, text[i]);
		placed[count].left = left[i];
		placed[count++].right = left[i] + w;
	}
	draw_text(rgb, width, height, (width - text_width(unit, bar->scale)) / 2,
		  bar->label_top + (GLYPH_HEIGHT + UNIT_GAP) * bar->scale, bar->scale, unit);
}

static uint64_t max_count(const uint64_t *pixel_flops, size_t pixels)
{
	uint64_t max = 0;
	size_t i;

	for (i = 0; i < pixels; i++)
		if (pixel_flops[i] > max)
			max = pixel_flops[i];
	return max;
}

/* Checks the map's arguments; returns 0, or -1 with one message in err. */
static int check_map(const char *name, const uint64_t *pixel_flops, int width, int height,
		     char *err, size_t err_size)
{
	if (pixel_flops && width > 0 && height > 0 &&
	    (size_t)width <= SIZE_MAX / 12 / (size_t)height)
		return 0;
	snprintf(err, err_size, "%s: invalid work map (%d x %d pixels%s)", quote_text(name), width,
		 height, pixel_flops ? "" : ", no data");
	return -1;
}

/* Stages rgb (width x height) with the work map's description. */
static int stage_picture(struct staged_file *staged, const char *path, const float *rgb, int width,
			 int height, uint64_t max, enum workmap_scale scale, char *err,
			 size_t err_size)
{
	char description[128];
	struct image_meta meta;

	snprintf(description, sizeof(description),
		 "flops per pixel, 0 (dark) to %" PRIu64 " (bright), viridis, %s scale", max,
		 scale == WORKMAP_LOG ? "log" : "linear");
	meta.software = "rtcl " RTCL_VERSION;
	meta.description = description;
	meta.encoding = IMAGE_DISPLAY; /* viridis is a scale of display colours */
	meta.samples = 0;
	return image_stage(staged, path, rgb, width, height, &meta, err, err_size);
}

int workmap_stage(struct staged_file *staged, const char *path, const uint64_t *pixel_flops,
		  int width, int height, enum workmap_scale scale, char *err, size_t err_size)
{
	const char *name = path ? path : "work map";
	size_t pixels = (size_t)width * (size_t)height;
	uint64_t max;
	float *rgb;
	int status;

	if (check_map(name, pixel_flops, width, height, err, err_size))
		return -1;
	rgb = malloc(3 * sizeof(float) * pixels);
	if (!rgb) {
		snprintf(err, err_size, "%s: out of memory for a %d x %d work map",
			 quote_text(name), width, height);
		return -1;
	}
	max = max_count(pixel_flops, pixels);
	draw_map(rgb, pixel_flops, pixels, max, scale);
	status = stage_picture(staged, path, rgb, width, height, max, scale, err, err_size);
	free(rgb);
	return status;
}

int workmap_stage_bar(struct staged_file *staged, const char *path, const uint64_t *pixel_flops,
		      int width, int height, enum workmap_scale scale, char *err, size_t err_size)
{
	const char *name = path ? path : "work map bar";
	struct bar_layout bar;
	uint64_t max;
	float *rgb;
	int bar_width, bar_height, status;

	if (check_map(name, pixel_flops, width, height, err, err_size))
		return -1;
	workmap_bar_size(width, &bar_width, &bar_height);
	rgb = malloc(3 * sizeof(float) * (size_t)bar_width * (size_t)bar_height);
	if (!rgb) {
		snprintf(err, err_size, "%s: out of memory for a %d x %d scale bar",
			 quote_text(name), bar_width, bar_height);
		return -1;
	}
	max = max_count(pixel_flops, (size_t)width * (size_t)height);
	bar = bar_layout(bar_width, width);
	draw_strip(rgb, bar_width, bar_height, &bar);
	draw_labels(rgb, bar_width, bar_height, &bar, max, scale);
	status = stage_picture(staged, path, rgb, bar_width, bar_height, max, scale, err, err_size);
	free(rgb);
	return status;
}

/* Stages with stage() and commits the one file. */
static int write_one(int (*stage)(struct staged_file *, const char *, const uint64_t *, int, int,
				  enum workmap_scale, char *, size_t),
		     const char *path, const uint64_t *pixel_flops, int width, int height,
		     enum workmap_scale scale, char *err, size_t err_size)
{
	struct staged_file staged;

	if (stage(&staged, path, pixel_flops, width, height, scale, err, err_size))
		return -1;
	return files_commit(&staged, 1, err, err_size);
}

int workmap_write(const char *path, const uint64_t *pixel_flops, int width, int height,
		  enum workmap_scale scale, char *err, size_t err_size)
{
	return write_one(workmap_stage, path, pixel_flops, width, height, scale, err, err_size);
}

int workmap_write_bar(const char *path, const uint64_t *pixel_flops, int width, int height,
		      enum workmap_scale scale, char *err, size_t err_size)
{
	return write_one(workmap_stage_bar, path, pixel_flops, width, height, scale, err, err_size);
}

enum workmap_kind workmap_kind(const char *path)
{
	const char *ext = files_extension(path);

	if (strcasecmp(ext, ".npy") == 0)
		return WORKMAP_NPY;
	if (strcasecmp(ext, ".pfm") == 0 || strcasecmp(ext, ".exr") == 0 ||
	    strcasecmp(ext, ".hdr") == 0)
		return WORKMAP_FLOATS;
	return WORKMAP_PICTURE;
}

int workmap_stage_counts(struct staged_file *staged, const char *path, const uint64_t *pixel_flops,
			 int width, int height, char *err, size_t err_size)
{
	size_t pixels = (size_t)width * (size_t)height;
	struct image_meta meta = {"rtcl " RTCL_VERSION,
				  "flops per pixel: the counts, the same in every channel",
				  IMAGE_LINEAR, 0};
	float *rgb = malloc(3 * sizeof(float) * pixels);
	int status;

	if (!rgb) {
		snprintf(err, err_size, "%s: out of memory for a %d x %d work map",
			 quote_text(path), width, height);
		return -1;
	}
	for (size_t i = 0; i < pixels; i++)
		rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = (float)pixel_flops[i];
	status = image_stage(staged, path, rgb, width, height, &meta, err, err_size);
	free(rgb);
	return status;
}
