/* The work map: an image of the flops spent on each pixel (the paper's
 * Figure 2, made from the measured counts), and its labelled scale bar in a
 * file of its own. */
#ifndef RTCL_WORKMAP_H
#define RTCL_WORKMAP_H

#include <stddef.h>
#include <stdint.h>

struct staged_file;

/* How a count maps to the colour scale: t = count / max, or
 * t = log(1 + count) / log(1 + max), which spreads the many cheap pixels. */
enum workmap_scale { WORKMAP_LINEAR, WORKMAP_LOG };

/* What --work-map FILE writes, by FILE's extension. */
enum workmap_kind {
	WORKMAP_PICTURE, /* the viridis picture (any image format but these) */
	WORKMAP_NPY,	 /* .npy: the counts, uint64, for numpy */
	WORKMAP_FLOATS,	 /* .exr, .pfm, .hdr: the counts as floats */
};
enum workmap_kind workmap_kind(const char *path);

/* The size of the scale bar of a map `width` pixels wide: as wide as the map
 * (wider when the map is too narrow for the unit line, 170 pixels at the
 * 1x font), BAR_HEIGHT (40) font pixels high; the font is 1x below 800
 * pixels of map width, 2x below 1600 and so on. */
void workmap_bar_size(int width, int *bar_width, int *bar_height);

/* Stages (files.h) a picture of the flops spent on each pixel, pixel_flops[y
 * * width + x], row 0 at the top: exactly width × height pixels, each
 * coloured by viridis of its count on the given scale from 0 to the largest
 * count (all dark if that is 0), in the format of path's extension, with the
 * description "flops per pixel, 0 (dark) to MAX (bright), viridis, SCALE
 * scale". Returns 0, or -1 with one message in err[err_size]. */
int workmap_stage(struct staged_file *staged, const char *path, const uint64_t *pixel_flops,
		  int width, int height, enum workmap_scale scale, char *err, size_t err_size);

/* Stages the picture's scale bar (workmap_bar_size): a horizontal viridis
 * strip with ticks, the labels "0" (left end), the middle of the scale and
 * the largest count (right end) in a built-in 5×7 bitmap font scaled with the
 * width (labels that would overlap are left out), and under them, centred,
 * "flops per pixel, linear scale" or "flops per pixel, log scale". Same
 * description as the picture. */
int workmap_stage_bar(struct staged_file *staged, const char *path, const uint64_t *pixel_flops,
		      int width, int height, enum workmap_scale scale, char *err, size_t err_size);

/* workmap_stage and workmap_stage_bar, committed at once (for one file). */
int workmap_write(const char *path, const uint64_t *pixel_flops, int width, int height,
		  enum workmap_scale scale, char *err, size_t err_size);
int workmap_write_bar(const char *path, const uint64_t *pixel_flops, int width, int height,
		      enum workmap_scale scale, char *err, size_t err_size);

/* Writes the counts themselves to a float image format (EXR, PFM, HDR): each
 * pixel's count in all three channels, as float (exact up to 2^24). Staged
 * like workmap_stage. */
int workmap_stage_counts(struct staged_file *staged, const char *path, const uint64_t *pixel_flops,
			 int width, int height, char *err, size_t err_size);

#endif
