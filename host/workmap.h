/* The work map: an image of the flops spent on each pixel (the paper's
 * Figure 2, made from the measured counts), with a labelled scale bar. */
#ifndef RTCL_WORKMAP_H
#define RTCL_WORKMAP_H

#include <stddef.h>
#include <stdint.h>

/* Height in pixels of the scale bar that workmap_write() puts below a map
 * `width` pixels wide; it grows with the width, as the font does. */
int workmap_bar_height(int width);

/* Writes an image of the flops spent on each pixel, pixel_flops[y * width +
 * x], row 0 at the top: each pixel coloured by viridis of its count on a
 * linear scale from 0 to the largest count (all dark if that is 0). Below
 * the map, a scale bar: a horizontal viridis strip with ticks and the
 * labels "0" (left end), the midpoint (middle) and the largest count (right
 * end), in a built-in bitmap font scaled with the width; labels that do not
 * fit without overlapping are left out. The image is width × (height +
 * workmap_bar_height(width)) pixels, written by image_write() (format from
 * the extension), with the description "flops per pixel, 0 (dark) to MAX
 * (bright), viridis". Returns 0, or -1 with one message in err[err_size]. */
int workmap_write(const char *path, const uint64_t *pixel_flops, int width, int height, char *err,
		  size_t err_size);

/* Writes the counts themselves to a float image format (EXR, PFM, HDR): each
 * pixel's count in all three channels, as float (exact up to 2^24). Staged
 * like workmap_stage. */
int workmap_stage_counts(struct staged_file *staged, const char *path, const uint64_t *pixel_flops,
			 int width, int height, char *err, size_t err_size);

/* How a count maps to the colour scale: t = count / max, or
 * t = log(1 + count) / log(1 + max), which spreads the many cheap pixels. */
enum workmap_scale { WORKMAP_LINEAR, WORKMAP_LOG };

/* Like workmap_write (which draws the linear scale), but on the given scale,
 * and leaves the image staged for the caller to commit with the run's other
 * outputs (files.h). */
struct staged_file;
int workmap_stage(struct staged_file *staged, const char *path, const uint64_t *pixel_flops,
		  int width, int height, enum workmap_scale scale, char *err, size_t err_size);

#endif
