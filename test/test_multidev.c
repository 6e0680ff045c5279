/* The host-side pieces of issue 13 that need no device: the --devices
 * parser, the dispenser, the device-level efficiency, the orbit and the
 * frame names, the bands of one image over several devices. */
#include <criterion/criterion.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "device/devices.h"
#include "base/files.h"
#include "output/plan.h"
#include "run/frames.h"
#include "schedule/adapt.h"
#include "schedule/dispenser.h"
#include "schedule/multidev.h"
#include "render/render.h"
#include "schedule/tiles.h"

Test(multidev, devices_list_parses_entries_in_order)
{
	struct device_list list;
	char err[256];

	cr_assert_eq(devices_parse("1:0,0:12", &list, err, sizeof(err)), 0);
	cr_assert_eq(list.count, 2);
	cr_assert_eq(list.specs[0].platform, 1);
	cr_assert_eq(list.specs[0].device, 0);
	cr_assert_eq(list.specs[1].platform, 0);
	cr_assert_eq(list.specs[1].device, 12);
	cr_assert_eq(devices_parse("all", &list, err, sizeof(err)), 0);
	cr_assert(list.all);
}

Test(multidev, devices_list_refuses_bad_entries)
{
	const char *bad[] = {"", "0", ":0", "0:", "0:0:0", "a:0", "0:0,", ",0:0", "0: 1", "+1:0"};
	struct device_list list;
	char err[256];

	for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		cr_assert_eq(devices_parse(bad[i], &list, err, sizeof(err)), -1, "%s", bad[i]);
		cr_assert(strstr(err, "--devices: expected all or a list"), "%s", err);
	}
	cr_assert_eq(devices_parse("0:1,1:0,0:1", &list, err, sizeof(err)), -1);
	cr_assert_str_eq(err, "--devices: device 0:1 is listed twice");
}

Test(multidev, static_split_covers_every_piece_once)
{
	for (int n = 1; n <= 5; n++) {
		for (int count = 0; count <= 13; count++) {
			cr_assert_eq(dispenser_static_first(0, n, count), 0);
			cr_assert_eq(dispenser_static_first(n, n, count), count);
			for (int k = 0; k < n; k++) {
				int size = dispenser_static_first(k + 1, n, count) -
					   dispenser_static_first(k, n, count);
				/* equal shares, one more for some */
				cr_assert(size == count / n || size == count / n + 1);
			}
		}
	}
}

/* Takes from devices in turn until none gets a piece: every piece once, and
 * with the static split each device its own run of pieces in order. */
static void take_all(enum split split, int pieces, int devices)
{
	struct dispenser d;
	int seen[16] = {0}, last[8], busy = devices;

	cr_assert_eq(dispenser_init(&d, pieces, devices, split), 0);
	for (int k = 0; k < devices; k++)
		last[k] = dispenser_static_first(k, devices, pieces) - 1;
	while (busy > 0) {
		busy = 0;
		for (int k = 0; k < devices; k++) {
			int piece = dispenser_take(&d, k);
			if (piece < 0)
				continue;
			busy++;
			cr_assert(piece < pieces);
			seen[piece]++;
			if (split == SPLIT_STATIC)
				cr_assert_eq(piece, last[k] + 1, "device %d of %d", k, devices);
			last[k] = piece;
		}
	}
	for (int p = 0; p < pieces; p++)
		cr_assert_eq(seen[p], 1, "piece %d of %d", p, pieces);
	cr_assert_eq(dispenser_take(&d, 0), -1);
	dispenser_free(&d);
}

Test(multidev, dispenser_hands_out_every_piece_once)
{
	for (int devices = 1; devices <= 5; devices++) {
		for (int pieces = 0; pieces <= 13; pieces++) {
			take_all(SPLIT_DYNAMIC, pieces, devices);
			take_all(SPLIT_STATIC, pieces, devices);
		}
	}
}

Test(multidev, efficiency_is_mean_over_max_busy_time)
{
	struct device_work w[3] = {{.busy_ms = 100}, {.busy_ms = 50}, {.busy_ms = 0}};

	cr_assert_float_eq(multidev_efficiency(w, 3), 50.0 / 100, 1e-12);
	cr_assert_float_eq(multidev_efficiency(w, 1), 1.0, 1e-12);
}

Test(multidev, orbit_turns_the_eye_about_up_through_look_at)
{
	struct scene_camera c = {.eye = {0, 6, -24}, .look_at = {0, 1, 0}, .up = {0, 1, 0}, .fov = 45},
			    out;

	frames_orbit(&c, 3, 3, 6, &out); /* frame A: the scene's camera, exactly */
	cr_assert(memcmp(&out, &c, sizeof(c)) == 0);
	frames_orbit(&c, 4, 3, 6, &out); /* a quarter turn, right-handed about +y */
	cr_assert_float_eq(out.eye[0], -24, 1e-12);
	cr_assert_float_eq(out.eye[1], 6, 1e-12);
	cr_assert_float_eq(out.eye[2], 0, 1e-12);
	frames_orbit(&c, 5, 3, 6, &out); /* half a turn */
	cr_assert_float_eq(out.eye[0], 0, 1e-12);
	cr_assert_float_eq(out.eye[2], 24, 1e-12);
	cr_assert(memcmp(out.look_at, c.look_at, sizeof(c.look_at)) == 0);
	cr_assert(memcmp(out.up, c.up, sizeof(c.up)) == 0);
	cr_assert_eq(out.fov, 45);
}

Test(multidev, frame_names_put_the_number_before_the_extension)
{
	char name[PATH_MAX];

	cr_assert_eq(output_frame_name("out.png", 7, name), 0);
	cr_assert_str_eq(name, "out_0007.png");
	cr_assert_eq(output_frame_name("dir.d/out", 12345, name), 0);
	cr_assert_str_eq(name, "dir.d/out_12345");
	cr_assert_eq(output_frame_name("a/.hidden.exr", 0, name), 0);
	cr_assert_str_eq(name, "a/.hidden_0000.exr");
}

/* Under --mpi rank 0 holds the frames: each arrives once, all must arrive,
 * and what does not fit in half the host's memory is refused up front. */
Test(multidev, held_frames_arrive_once_each_and_all_of_them)
{
	struct scene scene = {.source = "s.json"};
	struct job job = {.scene = &scene, .animation = 1, .first_frame = 3, .last_frame = 5};
	struct output_request request = {.image = "out.ppm"};
	struct output_plan o;
	char err[512];

	cr_assert_eq(output_plan_open(&o, &request, &job, err, sizeof(err)), 0);
	cr_assert_eq(o.frames, 3);
	cr_assert_eq(output_plan_hold(&o, 0, malloc(12), err, sizeof(err)), 0);
	cr_assert_eq(output_plan_hold(&o, 2, malloc(12), err, sizeof(err)), 0);
	cr_assert_eq(output_plan_check_held(&o, err, sizeof(err)), -1);
	cr_assert_str_eq(err, "frame out_0004.ppm never arrived");
	cr_assert_eq(output_plan_hold(&o, 2, malloc(12), err, sizeof(err)), -1);
	cr_assert_str_eq(err, "frame out_0005.ppm arrived twice");
	cr_assert_eq(output_plan_hold(&o, 1, malloc(12), err, sizeof(err)), 0);
	cr_assert_eq(output_plan_check_held(&o, err, sizeof(err)), 0);
	output_plan_close(&o); /* frees the held frames (ASan, valgrind) */
}

Test(multidev, held_frames_beyond_half_the_memory_are_refused_with_the_numbers)
{
	struct scene scene = {.source = "s.json"};
	struct job job = {.scene = &scene, .animation = 1, .first_frame = 0, .last_frame = 9};
	struct output_request request = {.image = "out.ppm"};
	struct output_plan o;
	char err[512];

	job.settings.width = 64;
	job.settings.height = 48;
	cr_assert_eq(output_plan_open(&o, &request, &job, err, sizeof(err)), 0);
	cr_assert_eq(output_plan_check_memory(&o, err, sizeof(err)), 0);
	output_plan_close(&o);
	job.last_frame = 999; /* 1000 frames of 16384x16384: 3000 GiB */
	job.settings.width = job.settings.height = 16384;
	cr_assert_eq(output_plan_open(&o, &request, &job, err, sizeof(err)), 0);
	cr_assert_eq(output_plan_check_memory(&o, err, sizeof(err)), -1);
	cr_assert(strstr(err, "1000 frames of 16384x16384 need 3000.0 GiB (12 bytes a pixel)"),
		  "%s", err);
	cr_assert(strstr(err, "half of this host's memory"), "%s", err);
	output_plan_close(&o);
}

static struct render_settings band_settings(int width, int height, int samples)
{
	struct render_settings s;

	memset(&s, 0, sizeof(s));
	s.width = width;
	s.height = height;
	s.samples = samples;
	s.workgroup[0] = s.workgroup[1] = 8;
	return s;
}

Test(multidev, band_rows_default_to_whole_work_groups_and_several_bands_per_device)
{
	struct render_settings s = band_settings(800, 600, 1);

	/* 600 / 64 = 9.4 -> 10 -> 16, a multiple of 8: 38 bands for 2 devices. */
	cr_assert_eq(tiles_band_rows(&s, 0, 2, SPLIT_DYNAMIC), 16);
	cr_assert_eq(tiles_band_rows(&s, 0, 1, SPLIT_DYNAMIC), 24); /* 18.75 -> 19 -> 24 */
	cr_assert_eq(tiles_band_rows(&s, 7, 2, SPLIT_DYNAMIC), 7);  /* --piece-rows as given */
	cr_assert_eq(tiles_band_rows(&s, 5000, 2, SPLIT_DYNAMIC), 600);
	/* Static: one band per device, its share. */
	cr_assert_eq(tiles_band_rows(&s, 0, 2, SPLIT_STATIC), 304); /* 300 -> 304 */
	cr_assert_eq(tiles_band_rows(&s, 0, 7, SPLIT_STATIC), 88); /* 85.7 -> 86 -> 88 */
	cr_assert_eq(tiles_band_rows(&s, 7, 2, SPLIT_STATIC), 7);
	s.height = 5; /* never more than the image */
	cr_assert_eq(tiles_band_rows(&s, 0, 4, SPLIT_DYNAMIC), 5);
}

/* The smallest adaptive piece tiles_job_init gives each of devs. */
static void min_pieces(const struct device *devs, int count, int width, int height, double *out)
{
	struct render_settings s = band_settings(width, height, 1024);
	struct tiles_job t;
	char err[256];

	struct rt_piece map = {0};
	tiles_row_map(&map, &s, ROWS_INTERLEAVE, tiles_row_classes(devs, count));
	cr_assert_eq(
		tiles_job_init(&t, NULL, &s, 8, 1, &map, (struct device *)devs, count, err,
			       sizeof(err)),
		0, "%s", err);
	for (int k = 0; k < count; k++)
		out[k] = t.adapt.dev[k].min_pixels;
	tiles_job_free(&t);
}

Test(multidev, adaptive_gpu_pieces_are_many_launches_but_at_most_a_share)
{
	struct device gpu = {.is_gpu = 1, .compute_units = 132};
	struct device cpu = {.is_gpu = 0, .compute_units = 16};
	double resident = 2048.0 * 132, min[3];

	/* Beside a CPU, a GPU's smallest piece is TILES_GPU_LAUNCHES launches'
	 * worth, or its share of a small image; a CPU's, one work-group per
	 * compute unit. */
	min_pieces((struct device[]){gpu, cpu}, 2, 4000, 4000, min);
	cr_assert_float_eq(min[0], TILES_GPU_LAUNCHES * resident, 1e-6);
	cr_assert_float_eq(min[1], 16.0 * 64, 1e-6);
	min_pieces((struct device[]){gpu, cpu}, 2, 2000, 2000, min);
	cr_assert_float_eq(min[0], 4e6 * resident / (resident + 1024), 1e-3);
	/* Equal GPUs: a third of the image each at most, so all three work. */
	min_pieces((struct device[]){gpu, gpu, gpu}, 3, 2000, 2000, min);
	for (int k = 0; k < 3; k++)
		cr_assert_float_eq(min[k], 4e6 / 3, 1e-3);
}

Test(multidev, bands_cover_every_row_once_with_all_samples)
{
	struct render_settings s = band_settings(33, 50, 16);
	int rows = 7, covered[50] = {0};

	for (int b = 0; b < 8; b++) {
		struct rt_piece p = tiles_band(&s, rows, b, 0, 16);
		cr_assert_eq(p.x0, 0);
		cr_assert_eq(p.width, 33);
		cr_assert_eq(p.samples, 16);
		cr_assert_eq(p.sample_end, 16);
		cr_assert(p.height >= 1 && p.height <= rows);
		for (int y = p.y0; y < p.y0 + p.height; y++)
			covered[y]++;
	}
	cr_assert_eq(tiles_band(&s, rows, 7, 0, 16).height, 1); /* 50 = 7 * 7 + 1 */
	for (int y = 0; y < 50; y++)
		cr_assert_eq(covered[y], 1, "row %d", y);
}

/* A row map (docs/GUIDE.md, "How the rows are ordered") maps split rows
 * onto image rows one to one, whole bands stay whole, the rows after the last
 * whole band stay where they are, and a map that moves nothing leaves every
 * row in place. */
static void check_permutation(const struct rt_piece *map, int height, int band, int moved)
{
	static int seen[2100];
	int bands = band ? height / band : 0;
	const struct rt_piece p = *map;

	cr_assert_eq(p.row_band, moved ? band : 0, "height %d band %d", height, band);
	memset(seen, 0, sizeof(seen));
	for (int v = 0; v < height; v++) {
		int y = rt_piece_row(&p, v);
		cr_assert(y >= 0 && y < height, "height %d band %d: row %d -> %d", height, band, v,
			  y);
		seen[y]++;
		if (!moved || v >= bands * band)
			cr_assert_eq(y, v, "height %d band %d: row %d moved", height, band, v);
		else /* a band's rows stay together, in order */
			cr_assert_eq(y % band, v % band);
	}
	for (int y = 0; y < height; y++)
		cr_assert_eq(seen[y], 1, "height %d band %d: row %d taken %d times", height, band, y,
			     seen[y]);
}

/* --row-order interleave:S: the same, and class c's bands (c, c + S, ..) come
 * in order, the classes one after the other, the first F mod S one band
 * longer. */
Test(multidev, interleaved_rows_are_the_classes_in_order)
{
	for (int height = 1; height <= 700; height += height < 80 ? 1 : 31) {
		for (int band = 1; band <= 9; band++) {
			for (int classes = 1; classes <= 7; classes++) {
				struct rt_piece p = {0};
				int bands = height / band, v = 0;
				renderer_interleave_rows(&p, height, band, classes);
				int moved = classes >= 2 && bands >= classes;
				check_permutation(&p, height, band, moved);
				for (int c = 0; moved && c < classes; c++)
					for (int b = c; b < bands; b += classes, v += band)
						cr_assert_eq(rt_piece_row(&p, v), b * band,
							     "height %d band %d classes %d: split "
							     "row %d",
							     height, band, classes, v);
			}
		}
	}
}

/* The point of interleaving: S devices that each take an equal run of the
 * split rows each get every S-th band, so their pieces cost the same however
 * the cost is laid out over the image. With a cost growing from 1 to 2 down
 * the image (the default scene's bottom half costs about 1.7x its top), each
 * of S equal runs costs within 1.5 % (S = 2), 2.5 % (3) or 3.5 % (4) of its
 * share, for every image height from 240 to 2200 rows in bands of 8 (the
 * remainder: a class one band longer than another); in scan order two
 * halves differ by a third. */
Test(multidev, interleaved_runs_cost_their_share_of_the_image)
{
	static const double bound[] = {0, 0, 0.015, 0.025, 0.035};

	for (int height = 240; height <= 2200; height += height % 8 ? 7 : 1) {
		double total = 0;
		for (int y = 0; y < height; y++)
			total += 1 + (double)y / height;
		for (int classes = 2; classes <= 4; classes++) {
			struct rt_piece p = {0};
			renderer_interleave_rows(&p, height, 8, classes);
			for (int k = 0; k < classes; k++) {
				int a = height * k / classes, b = height * (k + 1) / classes;
				double cost = 0, share = total * (b - a) / height;
				for (int v = a; v < b; v++)
					cost += 1 + (double)rt_piece_row(&p, v) / height;
				cr_assert(fabs(cost / share - 1) <= bound[classes],
					  "height %d, run %d of %d costs %.4f of its share", height,
					  k, classes, cost / share);
			}
		}
	}
}

Test(multidev, band_passes_keep_a_launch_near_the_pass_budget)
{
	struct render_settings s = band_settings(1024, 1024, 65536);
	struct rt_piece band = tiles_band(&s, 64, 0, 0, 65536);

	/* 64 Ki pixels: 2^22 / 2^16 = 64 samples per launch. */
	cr_assert_eq(renderer_pass_samples(&s, (long long)band.width * band.height, 0), 64);
	cr_assert_eq(tiles_piece_launches(&s, &band, 0), 1024);
	/* On a GPU at least RENDER_GPU_PASS_SAMPLES: 64 stays, the 2^22 / 2^20
	 * = 4 of a 1024x1024 image too, 2000x2000's 1 becomes 4. */
	cr_assert_eq(RENDER_GPU_PASS_SAMPLES, 4);
	cr_assert_eq(renderer_pass_samples(&s, (long long)band.width * band.height, 1), 64);
	cr_assert_eq(renderer_pass_samples(&s, 1024 * 1024, 1), 4);
	cr_assert_eq(renderer_pass_samples(&s, 2000 * 2000, 0), 1);
	cr_assert_eq(renderer_pass_samples(&s, 2000 * 2000, 1), 4);
	struct rt_piece whole = tiles_band(&s, 1024, 0, 0, 65536);
	cr_assert_eq(tiles_piece_launches(&s, &whole, 0), 16384);
	cr_assert_eq(tiles_piece_launches(&s, &whole, 1), 16384);
	s.samples_per_pass = 5;
	cr_assert_eq(renderer_pass_samples(&s, 2000 * 2000, 1), 5, "as given, on a GPU too");
	cr_assert_eq(renderer_pass_samples(&s, (long long)band.width * band.height, 0), 5);
	s = band_settings(8, 8, 3);
	band = tiles_band(&s, 8, 0, 0, 3);
	/* never more than there are */
	cr_assert_eq(renderer_pass_samples(&s, (long long)band.width * band.height, 0), 3);
	cr_assert_eq(renderer_pass_samples(&s, 2000 * 2000, 1), 3);
}

Test(multidev, write_count_check_names_the_first_pixel_off)
{
	uint32_t counts[12] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
	char err[256];

	cr_assert_eq(tiles_check_counts(counts, 4, 3, 1, err, sizeof(err)), 0);
	counts[6] = 2;
	counts[9] = 0;
	cr_assert_eq(tiles_check_counts(counts, 4, 3, 1, err, sizeof(err)), -1);
	cr_assert_str_eq(err, "internal error: pixel (2, 1) of a band was written 2 times, not 1");
	cr_assert_eq(tiles_check_counts(counts, 4, 3, 0, err, sizeof(err)), -1);
	cr_assert(strstr(err, "pixel (0, 0)"), "%s", err);
}

/* ---- the adaptive policy (adapt.h) --------------------------------------- */

static struct adapt_view view(double remaining, double rate, double others_rate)
{
	struct adapt_view v = {.remaining = remaining,
			       .total = 1e9,
			       .unit = 1000,
			       .rate = rate,
			       .others_rate = others_rate,
			       .devices = 2,
			       .others_fastest = others_rate};
	return v;
}

Test(multidev, adaptive_probe_comes_first_and_is_small)
{
	struct adapt_view v = view(1e9, 0, 0);

	/* No rate yet: a probe of ADAPT_PROBE_PIXEL_SAMPLES, not a share. */
	cr_assert_eq(adapt_piece_cells(&v), ADAPT_PROBE_PIXEL_SAMPLES / 1000);
	v.total = v.remaining = 64000; /* a small image: 1/32 of it */
	cr_assert_eq(adapt_piece_cells(&v), 2);
	v.total = v.remaining = 100; /* less than a cell: one cell, never none */
	cr_assert_eq(adapt_piece_cells(&v), 1);
}

Test(multidev, adaptive_pieces_keep_a_device_busy_unless_the_tail_rule_stops_them)
{
	struct adapt_view probe = view(1e9, 0, 0), slow = view(1e9, 1e4, 1e6);

	/* A GPU's probe and pieces hold at least one launch's worth of pixels. */
	probe.min_size = 5e7;
	cr_assert_eq(adapt_piece_cells(&probe), (long long)(5e7 / 1000));
	probe.remaining = 2e4; /* never past the remaining work */
	cr_assert_eq(adapt_piece_cells(&probe), 20);
	/* The tail rule still shrinks a slow device's piece below it. */
	slow.min_size = 5e7;
	slow.remaining = 1e6;
	cr_assert_lt(adapt_piece_cells(&slow) * 1000, 5e7);
}

Test(multidev, adaptive_pieces_follow_the_rate_and_shrink_towards_the_end)
{
	struct adapt_view fast = view(1e9, 1e6, 1e4), slow = view(1e9, 1e4, 1e6);
	long long last = 1LL << 62;

	/* Half the device's share of what is left: rate / (sum of rates). */
	cr_assert_eq(adapt_piece_cells(&fast), (long long)(1e9 * 1e6 / 1.01e6 / 2 / 1000));
	cr_assert_eq(adapt_piece_cells(&slow), (long long)(1e9 * 1e4 / 1.01e6 / 2 / 1000));
	for (double left = 1e9; left >= 1000; left /= 3) {
		fast.remaining = left;
		long long cells = adapt_piece_cells(&fast);
		cr_assert(cells <= last && cells >= 1);
		cr_assert(cells * 1000 <= left + 999, "never past the remaining work");
		last = cells;
	}
	fast.remaining = 1e6; /* floor: ADAPT_FLOOR_MS of its own time */
	cr_assert_eq(adapt_piece_cells(&fast), (long long)(1e6 / 1000));
	fast.remaining = 2.5e9;
	fast.unknown = 1; /* a device still probing counts as fast as this one */
	cr_assert_eq(adapt_piece_cells(&fast), (long long)(2.5e9 / 2.01 / 2 / 1000));
}

Test(multidev, adaptive_slow_device_never_holds_the_tail)
{
	struct adapt_view slow = view(2e6, 1e3, 1e6);

	/* The others finish 2e6 in 2 ms, the slow device plans to be done by
	 * ADAPT_TAIL_MARGIN of that, 1 ms; one cell takes it 1 ms: it fits
	 * exactly, its floor of ADAPT_FLOOR_MS (4 cells) does not. */
	cr_assert_eq(ADAPT_TAIL_MARGIN, 0.5);
	cr_assert_eq(adapt_piece_cells(&slow), 1);
	slow.remaining = 1e6; /* planned end 0.5 ms: no cell fits */
	cr_assert_eq(adapt_piece_cells(&slow), 0);
	slow.others_fastest = 1e3; /* the fastest never retires: ADAPT_FLOOR_MS of its time */
	cr_assert_eq(adapt_piece_cells(&slow), (long long)(1e3 * ADAPT_FLOOR_MS / 1000));
	slow.others_fastest = 1.9e3; /* nor one under ADAPT_TAIL_SLOWER times slower */
	cr_assert_eq(adapt_piece_cells(&slow), (long long)(1e3 * ADAPT_FLOOR_MS / 1000));
	slow.others_fastest = 1e6;
	slow.others_backlog = 1e6; /* the others still busy 1 ms: one cell fits */
	cr_assert_eq(adapt_piece_cells(&slow), 1);
}

/* Simulated time: devices of the given rates (pixel-samples per ms) plus a
 * fixed cost per piece (and first_ms more for device 0's first piece: a GPU's
 * first launch) take pieces of a width x height x spp image as soon as they
 * are idle. Returns when the last piece is done; counts each pixel's pieces
 * in covered (when given) and each device's pieces. */
static double simulate_first(int width, int height, int spp, const double *rate, int n,
			     double first_ms, unsigned char *covered, int *pieces)
{
	struct adapt a;
	double free_at[DEVICES_MAX], end = 0;
	int active[DEVICES_MAX], left = n;
	struct rt_piece p;

	adapt_init(&a, width, height, spp, 8, 8, n);
	adapt_new_frame(&a);
	for (int k = 0; k < n; k++) {
		free_at[k] = 0;
		active[k] = 1;
		pieces[k] = 0;
	}
	while (left > 0) {
		int k = -1;
		for (int j = 0; j < n; j++)
			if (active[j] && (k < 0 || free_at[j] < free_at[k]))
				k = j;
		if (!adapt_take(&a, k, free_at[k], &p)) {
			active[k] = 0;
			left--;
			continue;
		}
		free_at[k] += 0.05 + (double)p.width * p.height * spp / rate[k];
		free_at[k] += k == 0 && pieces[k] == 0 ? first_ms : 0;
		pieces[k]++;
		end = free_at[k] > end ? free_at[k] : end;
		for (int y = p.y0; covered && y < p.y0 + p.height; y++)
			for (int x = p.x0; x < p.x0 + p.width; x++)
				covered[(size_t)y * width + x]++;
	}
	return end;
}

static double simulate(int width, int height, int spp, const double *rate, int n,
		       unsigned char *covered, int *pieces)
{
	return simulate_first(width, height, spp, rate, n, 0, covered, pieces);
}

Test(multidev, adaptive_gpu_and_cpu_finish_no_later_than_the_gpu_alone)
{
	/* The H200 run (docs/results/h200-batch1): GPU 2000x2000 x 1024 spp
	 * in 1517 ms, the CPU 220 times slower; and a CPU 50 times slower. */
	double gpu = 2000.0 * 2000 * 1024 / 1517;
	double rates[][2] = {{gpu, gpu / 220}, {gpu, gpu / 50}, {gpu / 220, gpu}};
	static unsigned char covered[2000 * 2000];
	int pieces[2], alone_pieces[2];
	double alone = simulate(2000, 2000, 1024, &gpu, 1, NULL, alone_pieces);

	/* Few launches alone: pieces grow to whole cell rows (21 here). */
	cr_assert(alone_pieces[0] <= 40, "%d pieces", alone_pieces[0]);

	for (int r = 0; r < 3; r++) {
		memset(covered, 0, sizeof(covered));
		double both = simulate(2000, 2000, 1024, rates[r], 2, covered, pieces);
		int slow = rates[r][0] < rates[r][1] ? 0 : 1;
		cr_assert(both <= alone, "case %d: %.1f ms with both, %.1f alone", r, both, alone);
		cr_assert(pieces[slow] >= 1 && pieces[slow] < pieces[1 - slow], "case %d", r);
		for (size_t i = 0; i < sizeof(covered); i++)
			cr_assert_eq(covered[i], 1, "case %d: pixel %zu", r, i);
	}
}

Test(multidev, adaptive_gpu_pieces_are_whole_rows_from_the_start_cpu_pieces_from_the_end)
{
	/* A GPU keeps 132 x 2048 pixels in flight, a CPU 16 x 64; the CPU's
	 * small pieces come from the image's end, so the GPU's stay whole cell
	 * rows (thin rest-of-a-row pieces left the H200 3x slower), and the two
	 * cursors meet without a gap or an overlap on an image of odd size. */
	int width = 2003, height = 1001, spp = 64, pieces[2] = {0, 0}, thin_gpu = 0;
	double rate[2] = {2.7e6, 2.7e6 / 220}, free_at[2] = {0, 0};
	static unsigned char covered[2003 * 1001];
	int active[2] = {1, 1}, left = 2;
	struct adapt a;
	struct rt_piece p;

	memset(covered, 0, sizeof(covered));
	adapt_init(&a, width, height, spp, 8, 8, 2);
	adapt_new_frame(&a);
	adapt_set_min_pixels(&a, 0, 132.0 * 2048);
	adapt_set_min_pixels(&a, 1, 16.0 * 64);
	while (left > 0) {
		int k = active[0] && (!active[1] || free_at[0] <= free_at[1]) ? 0 : 1;
		if (!adapt_take(&a, k, free_at[k], &p)) {
			active[k] = 0;
			left--;
			continue;
		}
		free_at[k] += 0.05 + (double)p.width * p.height * spp / rate[k];
		pieces[k]++;
		thin_gpu += k == 0 && p.width != width;
		cr_assert(k == 0 || p.y0 + p.height > height / 2, "CPU piece at row %d", p.y0);
		for (int y = p.y0; y < p.y0 + p.height; y++)
			for (int x = p.x0; x < p.x0 + p.width; x++)
				covered[(size_t)y * width + x]++;
	}
	cr_assert(pieces[1] >= 1, "the CPU took no piece");
	cr_assert_leq(thin_gpu, 1, "%d GPU pieces narrower than the image", thin_gpu);
	for (size_t i = 0; i < sizeof(covered); i++)
		cr_assert_eq(covered[i], 1, "pixel %zu", i);
}

Test(multidev, adaptive_cpu_waits_for_no_gpu_whose_rate_is_unknown)
{
	/* The GPU's first piece is most of the image and says nothing of its
	 * rate until done: the CPU, its probe done, takes no second piece (on
	 * an H100 such pieces held the end 90-300 ms past the GPU). */
	struct adapt a;
	struct rt_piece gpu, cpu;

	adapt_init(&a, 2000, 2000, 1024, 8, 8, 2);
	adapt_new_frame(&a);
	adapt_set_min_pixels(&a, 0, 2e6); /* as beside another GPU (tiles.c) */
	adapt_set_min_pixels(&a, 1, 16.0 * 64);
	/* The CPU waits for the GPU's first request; the GPU waits for none. */
	cr_assert_not(adapt_fronts_asked(&a, 1));
	cr_assert(adapt_fronts_asked(&a, 0));
	cr_assert(adapt_take(&a, 0, 0, &gpu));
	cr_assert(adapt_fronts_asked(&a, 1));
	cr_assert(adapt_take(&a, 1, 0, &cpu));
	cr_assert_eq(gpu.width * gpu.height, 2000000);
	cr_assert_eq(adapt_take(&a, 1, 150, &cpu), 0, "a second CPU piece");
	adapt_new_frame(&a); /* each frame the GPU asks first again */
	cr_assert_not(adapt_fronts_asked(&a, 1));
	/* The view alone: the same device with every rate known may go on. */
	struct adapt_view v = {.remaining = 1e9,
			       .total = 4e9,
			       .unit = 64 * 1024.0,
			       .rate = 7e3,
			       .others_rate = 4e6,
			       .devices = 2,
			       .others_backlog = 1e9,
			       .front_unknown = 1};
	cr_assert_eq(adapt_piece_cells(&v), 0);
	v.front_unknown = 0;
	cr_assert_gt(adapt_piece_cells(&v), 0);
}

Test(multidev, adaptive_piece_leaves_no_rest_smaller_than_its_smallest)
{
	/* A GPU whose smallest piece is 1e9 pixel-samples, 1.05e9 left: a rest
	 * of 0.05e9 would cost it a latency-bound piece, so it takes all. */
	struct adapt_view v = {.remaining = 1.05e9,
			       .total = 1.05e9,
			       .unit = 1000,
			       .devices = 2,
			       .min_size = 1e9};

	cr_assert_eq(adapt_piece_cells(&v), 1050000);
	v.remaining = 2.5e9; /* a rest of at least its smallest piece stays */
	cr_assert_eq(adapt_piece_cells(&v), 1000000);
}

Test(multidev, adaptive_a_slow_first_launch_does_not_hand_the_cpu_a_huge_piece)
{
	/* The GPU's first launch takes 200 ms more (set-up on first use): its
	 * probe makes it look slower than the CPU. Pieces grow at most
	 * ADAPT_GROWTH-fold, so the CPU's stay small until the rates are
	 * right (a wide image: a piece can take a whole cell row, 2.5 s of
	 * the CPU without the cap). */
	double gpu = 2000.0 * 2000 * 1024 / 1517, rates[2] = {gpu, gpu / 220};
	int pieces[2];
	double alone = simulate_first(4000, 1000, 1024, &gpu, 1, 200, NULL, pieces);
	double both = simulate_first(4000, 1000, 1024, rates, 2, 200, NULL, pieces);

	cr_assert(both <= alone, "%.1f ms with both, %.1f alone", both, alone);
}

Test(multidev, adaptive_pieces_grow_at_most_twice_the_largest_so_far)
{
	struct adapt_view v = view(1e9, 1e6, 1e4);

	v.largest = 3000;
	cr_assert_eq(adapt_piece_cells(&v), ADAPT_GROWTH * 3);
}

/* Two GPUs whose measured rates differ by 8 % or by 1.8 % (batches 60 and
 * 63, two H200s: the rates come from other pixels and frames, and the
 * default scene's odd bands cost 1.8 % more), each with its smallest piece
 * its share of the image and 16 launches' worth of an H200 filling it
 * (tiles.c's set_min_pieces): frame after frame each takes one piece, no
 * rest is left for a latency-bound sliver, and the faster takes more, so
 * that the two end within 0.5 % of the ideal. */
static void check_gpus_of_about_one_speed(double slower)
{
	double rates[2] = {2000.0 * 2000 * 2048 / 1733, slower * 2000.0 * 2000 * 2048 / 1733};
	double ideal = 2000.0 * 2000 * 2048 / (rates[0] + rates[1]);
	struct adapt a;
	struct rt_piece p;

	adapt_init(&a, 2000, 2000, 2048, 8, 8, 2);
	for (int k = 0; k < 2; k++) {
		adapt_set_min_pixels(&a, k, 2000.0 * 2000 / 2);
		adapt_set_fill_pixels(&a, k, 16 * 132 * 2048.0);
	}
	for (int frame = 0; frame < 3; frame++) {
		double free_at[2] = {0, 0};
		int pieces[2] = {0, 0}, active[2] = {1, 1};
		adapt_new_frame(&a);
		while (active[0] || active[1]) {
			int k = !active[0] || (active[1] && free_at[1] < free_at[0]);
			if (!adapt_take(&a, k, free_at[k], &p)) {
				active[k] = 0;
				continue;
			}
			free_at[k] += (double)p.width * p.height * 2048 / rates[k];
			pieces[k]++;
		}
		if (frame == 0) /* the first frame probes */
			continue;
		for (int k = 0; k < 2; k++)
			cr_assert_eq(pieces[k], 1, "frame %d: GPU %d took %d pieces", frame, k,
				     pieces[k]);
		double end = free_at[0] > free_at[1] ? free_at[0] : free_at[1];
		cr_assert_lt(end, 1.005 * ideal, "frame %d: %.1f ms, ideal %.1f", frame, end, ideal);
	}
}

Test(multidev, adaptive_gpus_of_about_one_speed_take_one_piece_each)
{
	check_gpus_of_about_one_speed(0.92);
	check_gpus_of_about_one_speed(1 / 1.018);
}

Test(multidev, adaptive_equal_devices_share_the_image)
{
	double rates[2] = {1e5, 1e5};
	int pieces[2];
	double one = simulate(640, 480, 64, rates, 1, NULL, pieces);
	double two = simulate(640, 480, 64, rates, 2, NULL, pieces);

	cr_assert(two < 0.55 * one, "%.1f ms on two, %.1f on one", two, one);
}

/* --split samples (tiles_split_samples): the ranges follow one another from
 * sample 0 to N, each at least one sample, in whole passes of the unit but
 * the last, shared by the rates; pieces are the whole image with sum_begin
 * their first sample; more pieces than passes take single samples. */
Test(multidev, sample_ranges_cover_the_samples_once_by_rate)
{
	static const struct {
		int samples, total, unit;
		double rate[3];
	} cases[] = {
		{2048, 2, 4, {1, 1, 0}},     {2048, 2, 4, {3, 1, 0}}, {1000, 3, 4, {1, 2, 1}},
		{7, 3, 4, {1, 1, 1}},	      {3, 3, 4, {1, 1, 1}},    {130, 2, 4, {1, 1000, 0}},
	};
	struct render_settings base = band_settings(40, 30, 1);

	for (size_t c = 0; c < sizeof(cases) / sizeof(cases[0]); c++) {
		struct render_settings s = base;
		struct tiles_job t;
		struct rt_piece map = {0};
		struct device devs[3] = {{0}};
		char err[256];
		s.samples = cases[c].samples;
		cr_assert_eq(tiles_job_init(&t, NULL, &s, 30, 0, &map, devs, 2, err, sizeof(err)),
			     0, "%s", err);
		cr_assert_eq(tiles_split_samples(&t, cases[c].total, cases[c].unit, cases[c].rate),
			     0);
		cr_assert_eq(t.piece_count, cases[c].total);
		int next = 0, unit = (s.samples + cases[c].unit - 1) / cases[c].unit < cases[c].total
					     ? 1
					     : cases[c].unit;
		double rate_sum = 0;
		for (int k = 0; k < cases[c].total; k++)
			rate_sum += cases[c].rate[k];
		for (int k = 0; k < cases[c].total; k++) {
			const struct rt_piece *p = &t.pieces[k];
			int size = p->sample_end - p->sample_begin;
			cr_assert_eq(p->sample_begin, next, "case %zu piece %d", c, k);
			cr_assert_eq(p->sum_begin, p->sample_begin);
			cr_assert_gt(size, 0, "case %zu piece %d is empty", c, k);
			cr_assert(p->x0 == 0 && p->y0 == 0 && p->width == 40 && p->height == 30);
			cr_assert(k == cases[c].total - 1 || size % unit == 0,
				  "case %zu piece %d: %d samples, not whole passes of %d", c, k, size,
				  unit);
			/* Its share within a pass of the rate's, at least one pass. */
			double share = s.samples * cases[c].rate[k] / rate_sum;
			cr_assert(size <= (share > unit ? share : unit) + unit + 0.5 &&
					  size >= share - unit - 0.5,
				  "case %zu piece %d: %d samples for a share of %.1f", c, k, size,
				  share);
			next = p->sample_end;
		}
		cr_assert_eq(next, s.samples, "case %zu ends at %d", c, next);
		tiles_job_free(&t);
	}
}

/* The default split by measurement (issue 43): the samples when the
 * slowest device's read-back of its sums costs no more than
 * TILES_SHARE_PENALTY of the image's time over all devices, the pixels
 * otherwise; the image's time from the probes' rates, a slower device
 * counting less. */
Test(multidev, the_default_split_weighs_the_sums_against_a_share_of_the_pixels)
{
	double pass_ms[4] = {10, 10, 10, 20}, sums_ms[4] = {1, 4, 2, 3};
	double kernel_ms[4] = {0}; /* not profiled: nothing beyond the kernels */
	struct split_choice c;

	/* 4 samples a pass: 0.4 + 0.4 + 0.4 + 0.2 = 1.4 samples a ms. */
	cr_assert(tiles_prefer_samples(pass_ms, kernel_ms, sums_ms, 4, 4, 256, 2, 0, &c));
	cr_assert(c.measured && c.pass_samples == 4);
	cr_assert_float_eq(c.render_ms, 256 / 1.4, 1e-9);
	cr_assert_float_eq(c.pass_ms, 20, 1e-12);
	cr_assert_float_eq(c.sums_ms, 4, 1e-12);
	cr_assert_float_eq(c.add_ms, 2, 1e-12);
	cr_assert_float_eq(c.overhead_ms, 0, 1e-12);
	cr_assert_float_eq(c.move_ms, 0, 1e-12);
	cr_assert_float_eq(c.penalty_ms, TILES_SHARE_PENALTY * 256 / 1.4, 1e-9);
	/* 16 samples: 11.4 ms of work, 0.55 ms of penalty, less than the
	 * slowest read-back (4 ms). */
	cr_assert_not(tiles_prefer_samples(pass_ms, kernel_ms, sums_ms, 4, 4, 16, 0, 0, &c));
	cr_assert_float_eq(c.render_ms, 16 / 1.4, 1e-9);
	/* The boundary: a read-back and an add that make up the penalty take
	 * the samples; the add counts as much as the read-back. */
	double one[2] = {TILES_SHARE_PENALTY * 50, TILES_SHARE_PENALTY * 50}, pass[2] = {2, 2};
	double none[2] = {0, 0};
	double add = TILES_SHARE_PENALTY * 50;
	cr_assert(tiles_prefer_samples(pass, none, one, 2, 1, 100, add, 0, &c)); /* 100 ms */
	cr_assert_not(tiles_prefer_samples(pass, none, one, 2, 1, 100, add * 1.001, 0, &c));
	one[1] *= 1.001;
	cr_assert_not(tiles_prefer_samples(pass, none, one, 2, 1, 100, add, 0, &c));
}

/* What the pixel split costs beyond a share of the image's time (issue 43,
 * batch 99): a pass's host time beyond its kernels (a wavefront's round
 * trips per bounce), which each device of a pixel split pays for every pass
 * and of the sample split only its share; and under --mpi the pixels' way to
 * rank 0. Four H100s, the path-traced box by -k wavefront at 64 spp: one
 * pass of 4 samples 19.4 ms, 16.8 of kernels; the pixels took 110-121 ms a
 * device (75 of kernels) where the samples would take about 80. */
Test(multidev, the_pixel_split_pays_its_passes_host_time_and_the_way_to_rank_0)
{
	double pass_ms[4] = {19.4, 19.0, 19.2, 19.4}, kernel_ms[4] = {16.8, 16.8, 16.8, 16.9};
	double sums_ms[4] = {2.5, 2.5, 2.5, 2.5};
	struct split_choice c;

	/* 2.6 ms beyond the kernels a pass (the slowest), 16 passes, 3/4 of
	 * them paid beyond the sample split's: 31.2 ms. */
	cr_assert(tiles_prefer_samples(pass_ms, kernel_ms, sums_ms, 4, 4, 64, 5.5, 0, &c));
	cr_assert_float_eq(c.overhead_ms, 2.6 * 16 * 0.75, 1e-9);
	cr_assert_float_eq(c.penalty_ms, TILES_SHARE_PENALTY * c.render_ms + c.overhead_ms, 1e-9);
	/* Without it (kernels not profiled) the 4.8 % alone chose the pixels. */
	double none[4] = {0};
	cr_assert_not(tiles_prefer_samples(pass_ms, none, sums_ms, 4, 4, 64, 5.5, 0, &c));
	/* Kernels longer than the pass (several queues at once) count as no
	 * host time, not a negative one. */
	double longer[4] = {25, 25, 25, 25};
	cr_assert_not(tiles_prefer_samples(pass_ms, longer, sums_ms, 4, 4, 64, 5.5, 0, &c));
	cr_assert_float_eq(c.overhead_ms, 0, 1e-12);
	/* One device's pass at the same rate: nothing beyond the sample split. */
	cr_assert_float_eq(
		(tiles_prefer_samples(pass_ms, kernel_ms, sums_ms, 1, 4, 64, 0, 0, &c), c.overhead_ms),
		0, 1e-12);
	/* --mpi: the others' pixels to rank 0 (35 ms) count against the pixels
	 * too, so a box of -k dynamic (no host time) takes the samples. */
	double box[4] = {27.4, 27.4, 27.4, 27.4};
	cr_assert_not(tiles_prefer_samples(box, none, sums_ms, 4, 4, 64, 6.5, 0, &c));
	cr_assert(tiles_prefer_samples(box, none, sums_ms, 4, 4, 64, 6.5, 35, &c));
	cr_assert_float_eq(c.move_ms, 35, 1e-12);
	cr_assert_float_eq(c.penalty_ms, TILES_SHARE_PENALTY * c.render_ms + 35, 1e-9);
}
