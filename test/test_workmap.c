/* The work map and its scale bar (host/output/workmap.h), written as .ppm and read
 * back. */
#include <criterion/criterion.h>
#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "output/image.h"
#include "output/workmap.h"

#define ERR_SIZE 512

/* viridis(0) and viridis(1) in 8 bits: round(255 · c0) and round(255 · the
 * sum of the polynomial's coefficients), worked out by hand from the table. */
static const unsigned char viridis0[3] = {71, 1, 85};
static const unsigned char viridis1[3] = {252, 231, 33};
static const unsigned char white[3] = {255, 255, 255};

struct ppm {
	int width, height;
	unsigned char *pixels; /* 3 bytes a pixel, row 0 at the top */
	char comments[512];
};

static char *make_dir(void)
{
	char *dir = strdup("/tmp/rtcl-test-workmap-XXXXXX");

	cr_assert(dir && mkdtemp(dir), "mkdtemp: %s", strerror(errno));
	return dir;
}

/* Removes path (if any) and the directory, and frees both names. */
static void remove_dir(char *dir, char *path)
{
	unlink(path);
	cr_expect_eq(rmdir(dir), 0, "rmdir %s: %s (a file left behind?)", dir, strerror(errno));
	free(path);
	free(dir);
}

static char *join(const char *dir, const char *name)
{
	char *path = malloc(strlen(dir) + strlen(name) + 2);

	cr_assert(path);
	sprintf(path, "%s/%s", dir, name);
	return path;
}

/* Skips whitespace and "#" comment lines, keeping the comments. */
static void skip_space(FILE *f, struct ppm *image)
{
	char line[256];
	int c;

	while ((c = fgetc(f)) != EOF) {
		if (c == '#') {
			cr_assert(fgets(line, sizeof(line), f));
			strncat(image->comments, line,
				sizeof(image->comments) - strlen(image->comments) - 1);
		} else if (c != ' ' && c != '\n' && c != '\r' && c != '\t') {
			ungetc(c, f);
			return;
		}
	}
}

static struct ppm read_ppm(const char *path)
{
	struct ppm image = {0};
	FILE *f = fopen(path, "rb");
	size_t size;
	int maxval;

	cr_assert(f, "fopen %s: %s", path, strerror(errno));
	cr_assert(fgetc(f) == 'P' && fgetc(f) == '6', "%s is not a P6 file", path);
	skip_space(f, &image);
	cr_assert_eq(fscanf(f, "%d", &image.width), 1);
	skip_space(f, &image);
	cr_assert_eq(fscanf(f, "%d", &image.height), 1);
	skip_space(f, &image);
	cr_assert_eq(fscanf(f, "%d", &maxval), 1);
	cr_assert_eq(maxval, 255);
	fgetc(f); /* the one whitespace byte before the pixels */
	size = 3 * (size_t)image.width * (size_t)image.height;
	image.pixels = malloc(size);
	cr_assert(image.pixels);
	cr_assert_eq(fread(image.pixels, 1, size, f), size, "%s is short", path);
	fclose(f);
	return image;
}

static const unsigned char *pixel(const struct ppm *image, int x, int y)
{
	return &image->pixels[3 * ((size_t)y * image->width + x)];
}

static int same(const unsigned char *a, const unsigned char *b)
{
	return !memcmp(a, b, 3);
}

static double luminance(const unsigned char *p)
{
	return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

/* Writes the map (or with bar, its scale bar) to DIR/map.ppm and reads it
 * back. */
static struct ppm write_scale(const uint64_t *flops, int width, int height, int bar,
			      enum workmap_scale scale)
{
	char *dir = make_dir(), *path = join(dir, "map.ppm");
	char err[ERR_SIZE] = "";
	struct ppm image;

	cr_assert_eq((bar ? workmap_write_bar : workmap_write)(path, flops, width, height, scale,
							       err, sizeof(err)),
		     0, "%s", err);
	image = read_ppm(path);
	remove_dir(dir, path);
	return image;
}

static struct ppm write_and_read(const uint64_t *flops, int width, int height)
{
	return write_scale(flops, width, height, 0, WORKMAP_LINEAR);
}

/* count = 1000 · x + y: rising to the right, largest at the bottom right. */
static uint64_t *gradient(int width, int height)
{
	uint64_t *flops = malloc(sizeof(*flops) * (size_t)width * (size_t)height);
	int x, y;

	cr_assert(flops);
	for (y = 0; y < height; y++)
		for (x = 0; x < width; x++)
			flops[(size_t)y * width + x] = 1000 * (uint64_t)x + (uint64_t)y;
	return flops;
}

static struct ppm gradient_image(int width, int height, int bar, enum workmap_scale scale)
{
	uint64_t *flops = gradient(width, height);
	struct ppm image = write_scale(flops, width, height, bar, scale);

	free(flops);
	return image;
}

static struct ppm gradient_map(int width, int height)
{
	return gradient_image(width, height, 0, WORKMAP_LINEAR);
}

/* The scale bar of the gradient map. */
static struct ppm gradient_bar(int width, int height)
{
	return gradient_image(width, height, 1, WORKMAP_LINEAR);
}

/* The first row of the bar's strip: the bar row holding viridis(1). */
static int strip_row(const struct ppm *image, int map_height)
{
	int x, y;

	for (y = map_height; y < image->height; y++)
		for (x = 0; x < image->width; x++)
			if (same(pixel(image, x, y), viridis1))
				return y;
	cr_assert_fail("no viridis(1) in the bar");
	return -1;
}

/* The first row of the labels: below the strip and its ticks, after a row
 * of nothing but background. */
static int label_row(const struct ppm *image, int map_height)
{
	const unsigned char *background = pixel(image, 0, image->height - 1);
	int x, y = strip_row(image, map_height), empty = 0;

	for (; y < image->height; y++) {
		int blank = 1;

		for (x = 0; x < image->width; x++)
			blank &= same(pixel(image, x, y), background);
		if (blank)
			empty = 1;
		else if (empty)
			return y;
	}
	return -1;
}

/* Whether any label pixel is white in columns [x0, x1). */
static int white_in_labels(const struct ppm *image, int map_height, int x0, int x1)
{
	int y = label_row(image, map_height), x;

	for (; y >= 0 && y < image->height; y++)
		for (x = x0; x < x1; x++)
			if (same(pixel(image, x, y), white))
				return 1;
	return 0;
}

Test(workmap, picture_is_the_render_size)
{
	static const int sizes[][2] = {{1, 1}, {64, 32}, {13, 77}, {801, 3}};

	for (size_t i = 0; i < sizeof(sizes) / sizeof(sizes[0]); i++) {
		struct ppm image = gradient_map(sizes[i][0], sizes[i][1]);

		cr_expect_eq(image.width, sizes[i][0]);
		cr_expect_eq(image.height, sizes[i][1]);
		free(image.pixels);
	}
}

/* 40 font pixels high, as wide as the map but never narrower than the unit
 * line needs (170 pixels at 1x); the font grows every 800 pixels of width. */
Test(workmap, bar_size)
{
	static const int cases[][3] = {
		{64, 170, 40},	{170, 170, 40},	   {300, 300, 40}, {799, 799, 40},
		{800, 800, 80}, {1600, 1600, 120}, {1, 170, 40},
	};

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		struct ppm image = gradient_bar(cases[i][0], 2);
		int w, h;

		workmap_bar_size(cases[i][0], &w, &h);
		cr_expect_eq(w, cases[i][1], "width %d: bar %d wide", cases[i][0], w);
		cr_expect_eq(h, cases[i][2], "width %d: bar %d high", cases[i][0], h);
		cr_expect_eq(image.width, w);
		cr_expect_eq(image.height, h);
		free(image.pixels);
	}
}

Test(workmap, ends_are_viridis_0_and_1)
{
	struct ppm image = gradient_map(64, 32);
	const unsigned char *zero = pixel(&image, 0, 0), *max = pixel(&image, 63, 31);

	cr_assert(same(zero, viridis0), "zero count: %d %d %d", zero[0], zero[1], zero[2]);
	cr_assert(same(max, viridis1), "max count: %d %d %d", max[0], max[1], max[2]);
	free(image.pixels);
}

Test(workmap, luminance_rises_with_count)
{
	struct ppm image = gradient_map(64, 32);
	int x;

	for (x = 1; x < 64; x++)
		cr_expect_gt(luminance(pixel(&image, x, 0)), luminance(pixel(&image, x - 1, 0)),
			     "x = %d", x);
	free(image.pixels);
}

Test(workmap, description_names_the_max)
{
	struct ppm image = gradient_map(64, 32);

	cr_assert(strstr(image.comments, "flops per pixel, 0 (dark) to 63031 (bright), viridis"),
		  "comments: %s", image.comments);
	free(image.pixels);
}

Test(workmap, strip_runs_from_viridis_0_to_1)
{
	struct ppm image = gradient_bar(200, 32);
	const unsigned char *background = pixel(&image, 0, image.height - 1);
	int y = strip_row(&image, 0), left = 0, right = 199, x;

	while (left < 200 && same(pixel(&image, left, y), background))
		left++;
	while (right > left && same(pixel(&image, right, y), background))
		right--;
	cr_assert(right - left > 100, "strip %d..%d is short", left, right);
	cr_assert(same(pixel(&image, left, y), viridis0), "left end");
	cr_assert(same(pixel(&image, right, y), viridis1), "right end");
	for (x = left + 1; x <= right; x++)
		cr_expect_geq(luminance(pixel(&image, x, y)), luminance(pixel(&image, x - 1, y)),
			      "x = %d", x);
	free(image.pixels);
}

Test(workmap, wide_map_has_three_labels)
{
	int width = 2000, third = width / 3;
	struct ppm image = gradient_bar(width, 8);

	cr_assert_gt(label_row(&image, 0), 0, "no labels below the strip");
	cr_expect(white_in_labels(&image, 0, 0, third), "no \"0\" label");
	cr_expect(white_in_labels(&image, 0, third, 2 * third), "no midpoint label");
	cr_expect(white_in_labels(&image, 0, 2 * third, width), "no max label");
	free(image.pixels);
}

/* A map narrower than the unit line: the bar is the unit line's width and
 * keeps its end labels inside. */
Test(workmap, narrow_map_keeps_end_labels)
{
	struct ppm image = gradient_bar(61, 4);

	cr_assert_eq(image.width, 170);
	cr_expect(white_in_labels(&image, 0, 0, 10), "no \"0\" label");
	cr_expect(white_in_labels(&image, 0, 160, 170), "no max label");
	free(image.pixels);
}

Test(workmap, tiny_map_is_written)
{
	uint64_t flops[2] = {0, 7};
	struct ppm image = write_and_read(flops, 1, 2);

	cr_assert_eq(image.width, 1);
	cr_assert(same(pixel(&image, 0, 0), viridis0));
	cr_assert(same(pixel(&image, 0, 1), viridis1));
	free(image.pixels);
}

Test(workmap, all_zero_is_all_dark)
{
	uint64_t flops[12] = {0};
	struct ppm image = write_and_read(flops, 4, 3);
	int x, y;

	for (y = 0; y < 3; y++)
		for (x = 0; x < 4; x++)
			cr_expect(same(pixel(&image, x, y), viridis0), "(%d, %d)", x, y);
	free(image.pixels);
}

Test(workmap, missing_directory_fails_cleanly)
{
	char *dir = make_dir(), *path = join(dir, "no/such/dir/map.ppm");
	uint64_t flops[4] = {1, 2, 3, 4};
	char err[ERR_SIZE] = "";
	struct stat st;

	cr_assert_eq(workmap_write(path, flops, 2, 2, WORKMAP_LINEAR, err, sizeof(err)), -1);
	cr_expect(strstr(err, path), "message does not name the file: %s", err);
	cr_expect(!strchr(err, '\n'), "message is not one line: %s", err);
	cr_expect_neq(stat(path, &st), 0, "%s was created", path);
	remove_dir(dir, path); /* fails if anything was left in dir */
}

Test(workmap, no_data_fails)
{
	char err[ERR_SIZE] = "";

	cr_assert_eq(workmap_write("/tmp/unused.ppm", NULL, 2, 2, WORKMAP_LINEAR, err, sizeof(err)),
		     -1);
	cr_expect_neq(err[0], '\0', "no message");
	cr_assert_eq(workmap_write("/tmp/unused.ppm", (uint64_t[1]){1}, 0, 2, WORKMAP_LINEAR, err,
				   sizeof(err)),
		     -1);
	cr_expect_neq(err[0], '\0', "no message");
}

/* Rows [y0, y1) of the bar as text, '#' for white (label ink), '.' else. */
static void ink_rows(const struct ppm *image, int y0, int y1, char *out)
{
	for (int y = y0; y < y1; y++) {
		for (int x = 0; x < image->width; x++)
			*out++ = same(pixel(image, x, y), white) ? '#' : '.';
		*out++ = '\n';
	}
	*out = '\0';
}

/* The unit line: 7 rows of ink, centred, below the labels, and it names the
 * scale (the two scales' lines differ; the strip and labels rows hold the
 * same "0" label). The first glyph row of "flops per pixel, ..." starts with
 * the 'f' and the 'l' (rows "..##." and ".##.." at 1x). */
Test(workmap, bar_names_the_unit_and_scale)
{
	struct ppm lin = gradient_image(300, 8, 1, WORKMAP_LINEAR);
	struct ppm log = gradient_image(300, 8, 1, WORKMAP_LOG);
	int unit_top = label_row(&lin, 0) + 7 + 3, left = 0;
	static char a[8 * 301 + 1], b[8 * 301 + 1];

	ink_rows(&lin, unit_top, unit_top + 7, a);
	ink_rows(&log, unit_top, unit_top + 7, b);
	cr_assert(strchr(a, '#') && strchr(b, '#'), "no unit line");
	cr_expect(strcmp(a, b), "the linear and log bars name the same scale");
	/* The first row: 'f' at its start, then the 'l' one column after it. */
	while (left < 300 && a[left] != '#')
		left++;
	cr_expect(!strncmp(&a[left - 2], "..##...##..", 11), "first glyph row: %.20s",
		  &a[left - 2]);
	cr_expect(left > 50 && left < 150, "unit line not centred: starts at %d", left);
	/* Below it, the bottom margin: background only. */
	ink_rows(&lin, unit_top + 7, lin.height, a);
	cr_expect(!strchr(a, '#'), "ink below the unit line");
	free(lin.pixels);
	free(log.pixels);
}
