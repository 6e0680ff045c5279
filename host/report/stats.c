#include "report/stats.h"

#include <jansson.h>
#include <stdio.h>
#include <string.h>

#include "base/version.h"
#include "base/files.h"
#include "base/quote.h"
#include "base/timing.h"

void flop_summary_compute(struct flop_summary *s, const uint64_t *item_flops, size_t items,
			  uint64_t rays)
{
	uint64_t max = 0, min = items ? UINT64_MAX : 0, total = 0;

	for (size_t i = 0; i < items; i++) {
		total += item_flops[i];
		max = item_flops[i] > max ? item_flops[i] : max;
		min = item_flops[i] < min ? item_flops[i] : min;
	}
	s->total = total;
	s->mean = items ? (double)total / items : 0;
	s->max = (double)max;
	s->min = (double)min;
	s->parallel_efficiency = max ? s->mean / s->max : 1.0;
	s->rays = rays;
}

static int fill_json(FILE *file, const void *document)
{
	if (json_dumpf(document, file, JSON_INDENT(2) | JSON_REAL_PRECISION(9)) != 0)
		return -1;
	return fputc('\n', file) == EOF ? -1 : 0;
}

int stats_stage_document(struct staged_file *staged, const char *path, json_t *doc, char *err,
			 size_t err_size)
{
	int failed = !doc || files_stage_with(staged, path, fill_json, doc, err, err_size);

	if (!doc)
		snprintf(err, err_size, "%s: cannot build the JSON document", quote_text(path));
	json_decref(doc);
	return failed ? -1 : 0;
}

struct npy_array {
	const uint64_t *counts;
	size_t rows, cols;
};

/* NPY format 1.0: magic, version, header length, a Python dict literal padded
 * with spaces to a multiple of 64 bytes and ended by a newline, then the data
 * (little-endian, as on every platform rtcl runs on). */
static int fill_npy(FILE *file, const void *context)
{
	const struct npy_array *a = context;
	char header[256];
	int length = snprintf(header, sizeof(header),
			      "{'descr': '<u8', 'fortran_order': False, 'shape': (%zu, %zu), }",
			      a->rows, a->cols);
	int padded = (10 + length + 1 + 63) / 64 * 64 - 10;

	memset(header + length, ' ', (size_t)(padded - length - 1));
	header[padded - 1] = '\n';
	unsigned char preamble[10] = {0x93,
				      'N',
				      'U',
				      'M',
				      'P',
				      'Y',
				      1,
				      0,
				      (unsigned char)(padded & 0xff),
				      (unsigned char)(padded >> 8)};
	if (fwrite(preamble, 1, sizeof(preamble), file) != sizeof(preamble) ||
	    fwrite(header, 1, (size_t)padded, file) != (size_t)padded)
		return -1;
	size_t n = a->rows * a->cols;
	return fwrite(a->counts, sizeof(uint64_t), n, file) == n ? 0 : -1;
}

int stats_stage_pixel_counts(struct staged_file *staged, const char *path, const struct run *run,
			     char *err, size_t err_size)
{
	struct npy_array array = {run->counted.pixel_flops, (size_t)run->settings.height,
				  (size_t)run->settings.width};

	return files_stage_with(staged, path, fill_npy, &array, err, err_size);
}

int stats_stage_flops(struct staged_file *staged, const char *path, const struct run *run,
		      char *err, size_t err_size)
{
	const struct render_result *c = &run->counted;
	/* One row per NDRange row; the wavefront's launches in one row. */
	int one_row = run->settings.kernel->multi_pass;
	size_t rows = one_row ? 1 : c->global_size[1];
	size_t cols = one_row ? c->item_count : c->global_size[0];

	struct npy_array array = {c->item_flops, rows, cols};

	return files_stage_with(staged, path, fill_npy, &array, err, err_size);
}

/* The figures of the counting run, for --stats and the --flops sidecar. */
static void add_flop_figures(json_t *doc, const struct run *run)
{
	const struct flop_summary *f = &run->flops;
	double ms = run->result.kernel_ms_median;

	json_object_set_new(doc, "gflop", json_real(f->total * 1e-9));
	json_object_set_new(doc, "total_flops", json_integer((json_int_t)f->total));
	json_object_set_new(
		doc, "flops_per_item",
		json_pack("{s:f, s:f, s:f}", "mean", f->mean, "max", f->max, "min", f->min));
	json_object_set_new(doc, "parallel_efficiency", json_real(f->parallel_efficiency));
	json_object_set_new(doc, "gflops", json_real(f->total * 1e-6 / ms));
	json_object_set_new(doc, "rays", json_integer((json_int_t)f->rays));
	json_object_set_new(doc, "mrays_per_s", json_real(f->rays * 1e-3 / ms));
	json_object_set_new(doc, "node_visits", json_integer((json_int_t)f->node_visits));
	json_object_set_new(doc, "node_visits_per_ray",
			    json_real(f->rays ? (double)f->node_visits / f->rays : 0.0));
}

/* --accel and, with a BVH, its size and build. */
static void add_accel_figures(json_t *doc, const struct run *run)
{
	const struct render_result *r = &run->result;

	json_object_set_new(doc, "accel",
			    json_string(run->settings.accel == ACCEL_BVH ? "bvh" : "none"));
	/* The device's scene block (none for the CPU reference), and per
	 * triangle, the figure issue 11 budgets. */
	if (r->scene_bytes)
		json_object_set_new(doc, "scene_bytes", json_integer((json_int_t)r->scene_bytes));
	if (r->scene_bytes && run->scene->triangle_count) {
		json_object_set_new(doc, "bytes_per_triangle",
				    json_real((double)r->scene_bytes / run->scene->triangle_count));
		json_object_set_new(doc, "vertices", json_integer(r->vertex_count));
	}
	if (r->bvh_nodes == 0)
		return;
	json_object_set_new(doc, "bvh",
			    json_pack("{s:i, s:i, s:f, s:f, s:I}", "nodes", r->bvh_nodes, "depth",
				      r->bvh_depth, "sah_cost", r->bvh_sah_cost, "build_ms",
				      r->bvh_build_ms, "bytes", (json_int_t)r->bvh_bytes));
}

/* The --stats document, without the figures added below. */
static json_t *run_document(const struct run *run)
{
	const struct render_settings *s = &run->settings;
	const struct render_result *r = &run->result;
	char workgroup[32], groups[32];
	json_t *times = json_array();

	snprintf(workgroup, sizeof(workgroup), "%dx%d", s->workgroup[0], s->workgroup[1]);
	snprintf(groups, sizeof(groups), "%dx%d", r->groups[0], r->groups[1]);
	for (int i = 0; i < r->repeat; i++)
		json_array_append_new(times, json_real(r->kernel_ms[i]));
	return json_pack("{s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:[I,I], s:i, s:i, s:i, s:s, s:b,"
			 " s:f, s:f, s:f, s:i, s:o, s:s, s:i, s:i, s:i}",
			 "rtcl_version", RTCL_VERSION, "device", run->device_name, "device_version",
			 run->device_version, "driver", run->driver, "kernel",
			 s->kernel ? s->kernel->name : "reference", "workgroup", workgroup,
			 "groups", groups, "global_size", (json_int_t)r->global_size[0],
			 (json_int_t)r->global_size[1], "width", s->width, "height", s->height,
			 "max_depth", s->max_depth, "scene", run->scene->source,
			 "scene_in_local_memory", r->scene_in_local, "kernel_ms",
			 r->kernel_ms_median, "kernel_ms_min", r->kernel_ms_min, "kernel_ms_max",
			 r->kernel_ms_max, "repeat", r->repeat, "kernel_ms_all", times,
			 "build_options", r->build_options, "batch", s->batch, "samples",
			 settings_samples(s), "passes", r->passes > 0 ? r->passes : 1);
}

/* The device's size and clock, for peak-throughput estimates (not for the
 * CPU reference, which opens no device). */
static void add_device_figures(json_t *doc, const struct run *run)
{
	if (!run->on_device)
		return;
	json_object_set_new(doc, "compute_units", json_integer(run->compute_units));
	json_object_set_new(doc, "max_clock_mhz", json_integer(run->max_clock_mhz));
}

/* The --flops sidecar: how the counts were launched. */
static json_t *flops_sidecar(const struct run *run)
{
	const struct render_settings *s = &run->settings;
	const struct render_result *c = &run->counted;
	json_t *doc = json_pack(
		"{s:s, s:i, s:s, s:[i,i], s:[i,i], s:[I,I], s:i, s:i, s:i, s:s, s:s, s:s}",
		"format", "rtcl-flops", "version", 1, "kernel", s->kernel->name, "workgroup",
		(int)c->local_size[0], (int)c->local_size[1], "groups", c->groups[0], c->groups[1],
		"global_size", (json_int_t)c->global_size[0], (json_int_t)c->global_size[1],
		"width", s->width, "height", s->height, "max_depth", s->max_depth, "device",
		run->device_name, "scene", run->scene->source, "layout",
		s->kernel->multi_pass
			? "counts[0][i]: every launch's work-items one after the other (per "
			  "sample: the primary-ray launch, one launch per bounce, the "
			  "accumulate launch)"
			: "counts[y][x] for the work-item at global id (x, y), summed over the "
			  "passes; 0 for those given no pixel");

	if (doc)
		add_flop_figures(doc, run);
	return doc;
}

/* The time breakdown of the whole process, up to now. */
static json_t *times_document(const struct run *run)
{
	const struct render_times *t = &run->result.times;
	double now = timing_now();

	return json_pack("{s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:i}", "device_setup",
			 run->device_ms, "scene_and_upload", t->scene, "build", t->build, "kernels",
			 t->kernels, "read_back", t->read_back, "counting_run", run->counting_ms,
			 "encode_and_write", (now - run->write_start) * 1e3, "total",
			 (now - run->start) * 1e3, "launches", run->result.launches);
}

int stats_stage_run(struct staged_file *staged, const char *path, const struct run *run, char *err,
		    size_t err_size)
{
	json_t *doc = run_document(run);

	if (doc) {
		json_object_set_new(doc, "time_breakdown_ms", times_document(run));
		json_object_set_new(doc, "build_cached", json_boolean(run->result.build_cached));
	}

	if (doc && run->counting)
		add_flop_figures(doc, run);
	if (doc) {
		add_device_figures(doc, run);
		add_accel_figures(doc, run);
	}
	if (doc && run->multidevice)
		json_object_set(doc, "multidevice", run->multidevice);
	return stats_stage_document(staged, path, doc, err, err_size);
}

int stats_stage_flops_sidecar(struct staged_file *staged, const char *path, const struct run *run,
			      char *err, size_t err_size)
{
	return stats_stage_document(staged, path, flops_sidecar(run), err, err_size);
}

void stats_print_summary(const struct run *run)
{
	const struct render_settings *s = &run->settings;
	const struct render_result *r = &run->result;

	printf("device:  %s\n", run->device_name);
	if (!s->kernel)
		printf("kernel:  reference\n");
	else if (s->kernel->single_item)
		printf("kernel:  %s (one work-item)\n", s->kernel->name);
	else
		printf("kernel:  %s, work-group %dx%d, %dx%d groups (global %zux%zu)\n",
		       s->kernel->name, s->workgroup[0], s->workgroup[1], r->groups[0],
		       r->groups[1], r->global_size[0], r->global_size[1]);
	printf("image:   %dx%d, max depth %d, scene %s\n", s->width, s->height, s->max_depth,
	       quote_text(run->scene->source));
	if (s->samples > 1)
		printf("samples: %d per pixel in %d pass%s\n", s->samples, r->passes,
		       r->passes == 1 ? "" : "es");
	if (r->repeat > 1)
		printf("time:    %.3f ms median of %d launches (min %.3f, max %.3f)\n",
		       r->kernel_ms_median, r->repeat, r->kernel_ms_min, r->kernel_ms_max);
	else
		printf("time:    %.3f ms\n", r->kernel_ms_median);
	if (run->counting) {
		const struct flop_summary *f = &run->flops;
		printf("work:    %.3f GFLOP, %.1f GFLOP/s; per work-item mean %.0f, max %.0f, min "
		       "%.0f flops: parallel efficiency %.1f%%\n",
		       f->total * 1e-9, f->total * 1e-6 / r->kernel_ms_median, f->mean, f->max,
		       f->min, 100 * f->parallel_efficiency);
		printf("rays:    %llu (primary, secondary and shadow), %.1f Mrays/s\n",
		       (unsigned long long)f->rays, f->rays * 1e-3 / r->kernel_ms_median);
		if (s->accel == ACCEL_BVH)
			printf("nodes:   %llu BVH node visits, %.2f per ray\n",
			       (unsigned long long)f->node_visits,
			       f->rays ? (double)f->node_visits / f->rays : 0.0);
	}
	printf("output:  %s", quote_text(run->opt->output));
	if (run->opt->work_map_path)
		printf(", work map %s", quote_text(run->opt->work_map_path));
	if (run->opt->flops_path)
		printf(", flops %s", quote_text(run->opt->flops_path));
	printf("\n");
}

void stats_print_times(const struct run *run)
{
	const struct render_times *t = &run->result.times;
	double now = timing_now();

	fprintf(stderr,
		"rtcl: time: device set-up %.1f ms, scene and upload %.1f ms, build %.1f ms%s, "
		"kernels %.1f ms (%d launch%s), read-back %.1f ms, counting run %.1f ms, encoding "
		"and writing %.1f ms; total %.1f ms\n",
		run->device_ms, t->scene, t->build, run->result.build_cached ? " (cached)" : "",
		t->kernels, run->result.launches, run->result.launches == 1 ? "" : "es",
		t->read_back, run->counting_ms, (now - run->write_start) * 1e3,
		(now - run->start) * 1e3);
}
