/* Image output (host/output/image.h), with whichever implementation is linked:
 * image_oiio.cpp or image_ppm.c. Tests for formats other than .ppm/.pfm
 * run only when the build can write them. */
#define _GNU_SOURCE /* unshare, mount: the full-disk tests */

#include <criterion/criterion.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <sched.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <unistd.h>

#include "output/image.h"

#define ERR_SIZE 512

static const struct image_meta test_meta = {"rtcl test", "scene: test\nline two", IMAGE_LINEAR, 0};

/* A fresh empty directory; remove_dir() deletes it and its files. */
static char *make_dir(void)
{
	char *dir = strdup("/tmp/rtcl-test-image-XXXXXX");

	cr_assert(dir && mkdtemp(dir), "mkdtemp: %s", strerror(errno));
	return dir;
}

static void remove_dir(char *dir)
{
	DIR *d = opendir(dir);
	struct dirent *e;
	char path[4096];

	while (d && (e = readdir(d))) {
		if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
			snprintf(path, sizeof(path), "%s/%s", dir, e->d_name);
			if (unlink(path))
				rmdir(path);
		}
	}
	if (d)
		closedir(d);
	rmdir(dir);
	free(dir);
}

/* Asserts that dir holds exactly the `expected` entries (NULL-terminated),
 * so no temporary file was left behind. */
static void assert_dir_holds(const char *dir, const char *const *expected)
{
	DIR *d = opendir(dir);
	struct dirent *e;
	int found = 0, wanted = 0, i;

	cr_assert(d, "opendir %s: %s", dir, strerror(errno));
	while ((e = readdir(d))) {
		int known = 0;

		if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
			continue;
		for (i = 0; expected[i]; i++)
			known |= !strcmp(e->d_name, expected[i]);
		cr_expect(known, "unexpected file %s/%s", dir, e->d_name);
		found++;
	}
	closedir(d);
	while (expected[wanted])
		wanted++;
	cr_assert_eq(found, wanted, "%s holds %d entries, expected %d", dir, found, wanted);
}

static const char *const nothing[] = {NULL};

static char *join(const char *dir, const char *name)
{
	char *path = malloc(strlen(dir) + strlen(name) + 2);

	cr_assert(path);
	sprintf(path, "%s/%s", dir, name);
	return path;
}

static unsigned char *read_file(const char *path, size_t *size)
{
	FILE *f = fopen(path, "rb");
	unsigned char *data;
	long length;

	cr_assert(f, "fopen %s: %s", path, strerror(errno));
	fseek(f, 0, SEEK_END);
	length = ftell(f);
	rewind(f);
	data = malloc((size_t)length + 1);
	cr_assert(data);
	cr_assert_eq(fread(data, 1, (size_t)length, f), (size_t)length);
	fclose(f);
	data[length] = '\0';
	*size = (size_t)length;
	return data;
}

static void write_text(const char *path, const char *text)
{
	FILE *f = fopen(path, "w");

	cr_assert(f, "fopen %s: %s", path, strerror(errno));
	fputs(text, f);
	cr_assert_eq(fclose(f), 0);
}

static void assert_file_is(const char *path, const char *text)
{
	size_t size;
	unsigned char *data = read_file(path, &size);

	cr_assert_str_eq((char *)data, text, "%s was changed", path);
	free(data);
}

/* Parses a netpbm header: magic, optional "#" comment lines, width,
 * height, one more token (maxval or PFM scale), one whitespace byte.
 * Returns the offset of the pixel data; comments land in comments[]. */
static size_t parse_netpbm(const unsigned char *data, size_t size, const char *magic, int *width,
			   int *height, double *last, char *comments, size_t comments_size)
{
	const char *p = (const char *)data;
	char *end;

	comments[0] = '\0';
	cr_assert(size > 3 && !memcmp(p, magic, 2), "magic is not %s", magic);
	p += 2;
	for (;;) {
		while (*p == ' ' || *p == '\n' || *p == '\r' || *p == '\t')
			p++;
		if (*p != '#')
			break;
		end = strchr(p, '\n');
		cr_assert(end);
		strncat(comments, p, comments_size - strlen(comments) - 1);
		p = end + 1;
	}
	*width = (int)strtol(p, &end, 10);
	*height = (int)strtol(end, &end, 10);
	*last = strtod(end, &end);
	cr_assert(*end == '\n', "header does not end in one newline");
	return (size_t)(end + 1 - (const char *)data);
}

/* A small image with values inside, outside and at the edges of [0, 1]. */
#define W 3
#define H 2
static const float small_rgb[3 * W * H] = {
	0.0f,  0.5f, 1.0f,  /* (0,0) */
	-0.5f, 2.0f, 0.25f, /* (1,0) */
	NAN,   0.1f, 0.9f,  /* (2,0) */
	1e-3f, 0.7f, 0.3f,  /* (0,1) */
	0.2f,  0.4f, 0.6f,  /* (1,1) */
	0.8f,  1.5f, -1.0f, /* (2,1) */
};

/* The sRGB curve (IEC 61966-2-1) at its end points, at the joint of its two
 * pieces and in the middle, worked out by hand. */
Test(image, srgb_curve_points)
{
	cr_assert_float_eq(image_srgb_curve(0.0), 0.0, 1e-15);
	cr_assert_float_eq(image_srgb_curve(1.0), 1.0, 1e-15);
	/* linear below the joint: 12.92 * 0.002 */
	cr_assert_float_eq(image_srgb_curve(0.002), 0.02584, 1e-15);
	/* both pieces meet at 0.0031308 (to 1e-7: the standard rounds them) */
	cr_assert_float_eq(12.92 * 0.0031308, 1.055 * pow(0.0031308, 1 / 2.4) - 0.055, 1e-7);
	/* 1.055 * 0.5^(1/2.4) - 0.055 = 0.735356983... */
	cr_assert_float_eq(image_srgb_curve(0.5), 0.7353569830524495, 1e-12);
}

Test(image, encode_8bit_srgb_and_linear)
{
	cr_assert_eq(image_encode_8bit(0.0f, IMAGE_SRGB), 0);
	cr_assert_eq(image_encode_8bit(1.0f, IMAGE_SRGB), 255);
	cr_assert_eq(image_encode_8bit(0.5f, IMAGE_SRGB), 188); /* 187.516 */
	cr_assert_eq(image_encode_8bit(0.18f, IMAGE_SRGB), 118); /* 18 % grey: 117.65 */
	cr_assert_eq(image_encode_8bit(0.002f, IMAGE_SRGB), 7);	 /* 6.589, the linear piece */
	cr_assert_eq(image_encode_8bit(-1.0f, IMAGE_SRGB), 0);
	cr_assert_eq(image_encode_8bit(2.0f, IMAGE_SRGB), 255);
	cr_assert_eq(image_encode_8bit(NAN, IMAGE_SRGB), 0);
	/* linear and display values are stored as they are */
	cr_assert_eq(image_encode_8bit(0.5f, IMAGE_LINEAR), 128);
	cr_assert_eq(image_encode_8bit(0.5f, IMAGE_DISPLAY), 128);
	cr_assert_eq(image_encode_8bit(0.18f, IMAGE_LINEAR), 46);
}

Test(image, to_8bit_edges)
{
	cr_assert_eq(image_to_8bit(0.0f), 0);
	cr_assert_eq(image_to_8bit(1.0f), 255);
	cr_assert_eq(image_to_8bit(0.5f), 128); /* 127.5 rounds up */
	cr_assert_eq(image_to_8bit(-0.25f), 0);
	cr_assert_eq(image_to_8bit(-0.0f), 0);
	cr_assert_eq(image_to_8bit(1.01f), 255);
	cr_assert_eq(image_to_8bit(1e30f), 255);
	cr_assert_eq(image_to_8bit(INFINITY), 255);
	cr_assert_eq(image_to_8bit(-INFINITY), 0);
	cr_assert_eq(image_to_8bit(NAN), 0);
	cr_assert_eq(image_to_8bit(-NAN), 0);
}

Test(image, to_8bit_rounds_to_nearest)
{
	for (int k = 0; k < 256; k++) {
		cr_assert_eq(image_to_8bit((float)k / 255.0f), k, "k = %d", k);
		if (k < 255) {
			cr_assert_eq(image_to_8bit((k + 0.49f) / 255.0f), k, "k = %d", k);
			cr_assert_eq(image_to_8bit((k + 0.51f) / 255.0f), k + 1, "k = %d", k);
		}
	}
}

Test(image, ppm_round_trip)
{
	char *dir = make_dir(), *path = join(dir, "out.ppm");
	char err[ERR_SIZE] = "", comments[256];
	const char *const expected[] = {"out.ppm", NULL};
	unsigned char *data;
	size_t size, offset;
	int width, height;
	double maxval;

	cr_assert_eq(image_check_writable(path, err, sizeof(err)), 0, "%s", err);
	assert_dir_holds(dir, nothing);
	cr_assert_eq(image_write(path, small_rgb, W, H, &test_meta, err, sizeof(err)), 0, "%s",
		     err);
	assert_dir_holds(dir, expected);

	data = read_file(path, &size);
	offset = parse_netpbm(data, size, "P6", &width, &height, &maxval, comments,
			      sizeof(comments));
	cr_assert_eq(width, W);
	cr_assert_eq(height, H);
	cr_assert_eq(maxval, 255.0);
	cr_assert_eq(size - offset, sizeof(small_rgb) / sizeof(float));
	for (size_t i = 0; i < size - offset; i++)
		cr_assert_eq(data[offset + i], image_to_8bit(small_rgb[i]), "byte %zu", i);
	cr_assert_eq(data[offset + 0], 0);
	cr_assert_eq(data[offset + 1], 128);
	cr_assert_eq(data[offset + 6], 0, "NaN");

	/* Metadata as comments, the description's line break made a space. */
	cr_expect(strstr(comments, "rtcl test"), "comments: %s", comments);
	cr_expect(strstr(comments, "scene: test line two"), "comments: %s", comments);
	free(data);
	free(path);
	remove_dir(dir);
}

Test(image, pfm_round_trip_bottom_up)
{
	char *dir = make_dir(), *path = join(dir, "out.PFM");
	char err[ERR_SIZE] = "", comments[256];
	const char *const expected[] = {"out.PFM", NULL};
	unsigned char *data;
	size_t size, offset;
	int width, height;
	double scale;

	cr_assert_eq(image_write(path, small_rgb, W, H, NULL, err, sizeof(err)), 0, "%s", err);
	assert_dir_holds(dir, expected);

	data = read_file(path, &size);
	offset =
		parse_netpbm(data, size, "PF", &width, &height, &scale, comments, sizeof(comments));
	cr_assert_eq(width, W);
	cr_assert_eq(height, H);
	cr_assert(scale < 0, "scale %g: not little endian", scale);
	cr_assert_eq(size - offset, sizeof(small_rgb));
	for (int y = 0; y < H; y++) {
		for (int i = 0; i < 3 * W; i++) {
			/* File row 0 is the image's bottom row. */
			const unsigned char *b =
				data + offset + 4 * (size_t)((H - 1 - y) * 3 * W + i);
			uint32_t bits = b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 |
					(uint32_t)b[3] << 24;
			uint32_t want;

			memcpy(&want, &small_rgb[y * 3 * W + i], 4);
			cr_assert_eq(bits, want, "y %d, i %d: %08x, expected %08x", y, i, bits,
				     want);
		}
	}
	free(data);
	free(path);
	remove_dir(dir);
}

Test(image, overwrites_existing_file)
{
	char *dir = make_dir(), *path = join(dir, "out.ppm");
	char err[ERR_SIZE] = "";
	const char *const expected[] = {"out.ppm", NULL};
	float black[3] = {0, 0, 0};
	unsigned char *data;
	size_t size;

	write_text(path, "old contents\n");
	cr_assert_eq(image_write(path, black, 1, 1, NULL, err, sizeof(err)), 0, "%s", err);
	data = read_file(path, &size);
	cr_assert_eq(size, strlen("P6\n1 1\n255\n") + 3);
	cr_assert(!memcmp(data, "P6\n1 1\n255\n\0\0\0", size));
	assert_dir_holds(dir, expected);
	free(data);
	free(path);
	remove_dir(dir);
}

Test(image, unknown_extension_refused)
{
	char *dir = make_dir(), *path = join(dir, "out.xyz");
	char err[ERR_SIZE] = "";

	cr_assert_eq(image_check_writable(path, err, sizeof(err)), -1);
	cr_expect(strstr(err, path) && strstr(err, ".xyz") && strstr(err, ".ppm"), "%s", err);
	err[0] = '\0';
	cr_assert_eq(image_write(path, small_rgb, W, H, NULL, err, sizeof(err)), -1);
	cr_expect(strstr(err, path) && strstr(err, ".xyz"), "%s", err);
	assert_dir_holds(dir, nothing);
	free(path);
	remove_dir(dir);
}

Test(image, no_extension_refused)
{
	char *dir = make_dir(), *path = join(dir, "png");
	char err[ERR_SIZE] = "";

	cr_assert_eq(image_check_writable(path, err, sizeof(err)), -1);
	cr_expect(strstr(err, path) && strstr(err, ".ppm"), "%s", err);
	cr_assert_eq(image_write(path, small_rgb, W, H, NULL, err, sizeof(err)), -1);
	assert_dir_holds(dir, nothing);
	free(path);
	remove_dir(dir);
}

Test(image, missing_directory_refused)
{
	char *dir = make_dir(), *path = join(dir, "missing/out.ppm");
	char err[ERR_SIZE] = "";

	cr_assert_eq(image_check_writable(path, err, sizeof(err)), -1);
	cr_expect(strstr(err, path) && strstr(err, "does not exist"), "%s", err);
	cr_assert_eq(image_write(path, small_rgb, W, H, NULL, err, sizeof(err)), -1);
	cr_expect(strstr(err, "does not exist"), "%s", err);
	assert_dir_holds(dir, nothing);
	free(path);
	remove_dir(dir);
}

Test(image, directory_that_is_a_file_refused)
{
	char err[ERR_SIZE] = "";

	cr_assert_eq(image_check_writable("/dev/null/x.ppm", err, sizeof(err)), -1);
	cr_expect(strstr(err, "/dev/null/x.ppm") && strstr(err, "not a directory"), "%s", err);
	cr_assert_eq(image_write("/dev/null/x.ppm", small_rgb, W, H, NULL, err, sizeof(err)), -1);
}

/* Root may write anywhere permissions allow, so as root use /proc, where no
 * one can create a regular file; otherwise a read-only directory. */
Test(image, unwritable_directory_refused)
{
	char *dir = make_dir(), *read_only = join(dir, "ro"), *path;
	char err[ERR_SIZE] = "";

	cr_assert_eq(mkdir(read_only, 0555), 0);
	path = geteuid() == 0 ? strdup("/proc/rtcl-test-image.ppm") : join(read_only, "out.ppm");
	cr_assert_eq(image_check_writable(path, err, sizeof(err)), -1);
	cr_expect(strstr(err, path) && strstr(err, "cannot create"), "%s", err);
	err[0] = '\0';
	cr_assert_eq(image_write(path, small_rgb, W, H, NULL, err, sizeof(err)), -1);
	cr_expect(strstr(err, path) && strstr(err, "cannot create"), "%s", err);
	cr_expect(access(path, F_OK) != 0, "%s was created", path);
	free(path);
	free(read_only);
	remove_dir(dir);
}

/* A device, directory or pipe at the path is never replaced by a file. */
Test(image, non_regular_target_refused)
{
	char *dir = make_dir(), *path = join(dir, "sub.ppm");
	char err[ERR_SIZE] = "";
	const char *const expected[] = {"sub.ppm", NULL};
	struct stat st;

	cr_assert_eq(mkdir(path, 0755), 0);
	cr_assert_eq(image_check_writable(path, err, sizeof(err)), -1);
	cr_expect(strstr(err, path) && strstr(err, "not a regular file"), "%s", err);
	cr_assert_eq(image_write(path, small_rgb, W, H, NULL, err, sizeof(err)), -1);
	cr_assert(stat(path, &st) == 0 && S_ISDIR(st.st_mode));
	assert_dir_holds(dir, expected);

	cr_assert_eq(image_check_writable("/dev/full", err, sizeof(err)), -1);
	free(path);
	remove_dir(dir);
}

Test(image, invalid_image_leaves_existing_file)
{
	char *dir = make_dir(), *path = join(dir, "out.ppm");
	char err[ERR_SIZE] = "";
	const char *const expected[] = {"out.ppm", NULL};

	write_text(path, "keep me\n");
	cr_assert_eq(image_write(path, small_rgb, 0, H, NULL, err, sizeof(err)), -1);
	cr_expect(strstr(err, path), "%s", err);
	cr_assert_eq(image_write(path, NULL, W, H, NULL, err, sizeof(err)), -1);
	assert_file_is(path, "keep me\n");
	assert_dir_holds(dir, expected);
	free(path);
	remove_dir(dir);
}

/* Mounts a 16 KiB tmpfs on a fresh directory, in a mount namespace of this
 * test's own (Criterion runs each test in a child process, so the mount
 * goes away with it). Skips the test where that is not allowed. */
static char *make_small_disk(void)
{
	char *dir = make_dir();

	if (unshare(CLONE_NEWNS) || mount(NULL, "/", NULL, MS_REC | MS_PRIVATE, NULL) ||
	    mount("tmpfs", dir, "tmpfs", 0, "size=16k")) {
		rmdir(dir);
		free(dir);
		cr_skip_test("cannot mount a small tmpfs here: %s", strerror(errno));
	}
	return dir;
}

/* Noise, so that no format compresses it into 16 KiB. */
static float *make_noise(int width, int height)
{
	float *rgb = malloc(3 * sizeof(float) * (size_t)width * (size_t)height);
	uint32_t state = 12345;

	cr_assert(rgb);
	for (size_t i = 0; i < 3 * (size_t)width * (size_t)height; i++) {
		state = state * 1664525u + 1013904223u;
		rgb[i] = (float)(state >> 8) / 16777216.0f;
	}
	return rgb;
}

static void check_full_disk(const char *name)
{
	char *dir = make_small_disk(), *path = join(dir, name);
	char err[ERR_SIZE] = "";
	const char *const expected[] = {name, NULL};
	float *rgb = make_noise(200, 200);

	write_text(path, "keep me\n");
	cr_assert_eq(image_check_writable(path, err, sizeof(err)), 0, "%s", err);
	cr_assert_eq(image_write(path, rgb, 200, 200, &test_meta, err, sizeof(err)), -1,
		     "writing %s to a full disk succeeded", name);
	cr_log_info("full disk, %s: %s", name, err);
	cr_expect(strstr(err, path), "%s", err);
	assert_file_is(path, "keep me\n");
	assert_dir_holds(dir, expected);
	free(rgb);
	umount(dir);
	free(path);
	remove_dir(dir);
}

Test(image, full_disk_ppm)
{
	check_full_disk("out.ppm");
}

Test(image, full_disk_pfm)
{
	check_full_disk("out.pfm");
}

/* Formats only OpenImageIO builds write; refused clearly otherwise. */
static int can_write(const char *ext)
{
	char path[64], err[ERR_SIZE];

	snprintf(path, sizeof(path), "/tmp/x%s", ext);
	return image_check_writable(path, err, sizeof(err)) == 0;
}

Test(image, other_formats_refused_without_oiio)
{
	char err[ERR_SIZE] = "";

	if (can_write(".tif"))
		cr_skip_test("this build has OpenImageIO");
	cr_assert_eq(image_check_writable("/tmp/x.tif", err, sizeof(err)), -1);
	cr_expect(strstr(err, "OpenImageIO") && strstr(err, ".ppm, .pfm and .png"), "%s", err);
}

/* Some OIIO writers ignore short writes on their own (PNG in 2.4). */
Test(image, full_disk_oiio_formats)
{
	static const char *const names[] = {"out.png", "out.exr", "out.tif",
					    "out.jpg", "out.hdr", "out.bmp"};
	int tried = 0;

	for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++) {
		if (can_write(strrchr(names[i], '.'))) {
			check_full_disk(names[i]);
			tried++;
		}
	}
	if (!tried)
		cr_skip_test("no OpenImageIO in this build");
}

static uint32_t big_endian32(const unsigned char *b)
{
	return (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | b[3];
}

/* Checks what can be checked without inflating: signature, size, 8-bit
 * RGB, and the Software text chunk. */
Test(image, png_header_and_metadata)
{
	char *dir, *path;
	char err[ERR_SIZE] = "";
	const char *const expected[] = {"out.png", NULL};
	static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
	unsigned char *data;
	size_t size;

	if (!can_write(".png"))
		cr_skip_test("no PNG in this build");
	dir = make_dir();
	path = join(dir, "out.png");
	cr_assert_eq(image_write(path, small_rgb, W, H, &test_meta, err, sizeof(err)), 0, "%s",
		     err);
	assert_dir_holds(dir, expected);

	data = read_file(path, &size);
	cr_assert(size > 33 && !memcmp(data, signature, 8), "not a PNG");
	cr_assert(!memcmp(data + 12, "IHDR", 4));
	cr_assert_eq(big_endian32(data + 16), W);
	cr_assert_eq(big_endian32(data + 20), H);
	cr_assert_eq(data[24], 8, "bit depth %d", data[24]);
	cr_assert_eq(data[25], 2, "colour type %d, not RGB", data[25]);
	cr_expect(memmem(data, size, "Software\0rtcl test", 18), "no Software text chunk");
	free(data);
	free(path);
	remove_dir(dir);
}

/* Checks the magic number, that every channel is stored as 32-bit float
 * (pixel type 2), and the Software attribute. */
Test(image, exr_stores_float)
{
	char *dir, *path;
	char err[ERR_SIZE] = "";
	const char *const expected[] = {"out.exr", NULL};
	static const unsigned char magic[4] = {0x76, 0x2f, 0x31, 0x01};
	static const char chlist[] = "channels\0chlist";
	const unsigned char *p;
	unsigned char *data;
	size_t size;
	int channels = 0;

	if (!can_write(".exr"))
		cr_skip_test("no EXR in this build");
	dir = make_dir();
	path = join(dir, "out.exr");
	cr_assert_eq(image_write(path, small_rgb, W, H, &test_meta, err, sizeof(err)), 0, "%s",
		     err);
	assert_dir_holds(dir, expected);

	data = read_file(path, &size);
	cr_assert(size > 8 && !memcmp(data, magic, 4), "not an OpenEXR file");
	p = memmem(data, size, chlist, sizeof(chlist));
	cr_assert(p, "no channel list");
	p += sizeof(chlist) + 4; /* and the attribute's size */
	while (*p) {		 /* name, pixel type, linear, reserved, x and y sampling */
		const unsigned char *type = p + strlen((const char *)p) + 1;

		cr_assert_eq(type[0], 2, "channel %s has pixel type %d", p, type[0]);
		p = type + 16;
		channels++;
	}
	cr_assert_eq(channels, 3);
	cr_expect(memmem(data, size, "rtcl test", 9), "no Software attribute");
	free(data);
	free(path);
	remove_dir(dir);
}
