#include "report/document.h"

#include <stdio.h>
#include <string.h>

#include "base/timing.h"
#include "base/version.h"
#include "report/devstats.h"
#include "report/simd.h"
#include "render/stages.h"

int report_fill_json(FILE *file, const void *document)
{
	if (json_dumpf(document, file, JSON_INDENT(2) | JSON_REAL_PRECISION(9)) != 0)
		return -1;
	return fputc('\n', file) == EOF ? -1 : 0;
}

/* The figures of the counting run, for --stats and the --flops sidecar. */
static void add_flop_figures(json_t *doc, const struct record *record)
{
	const struct flop_summary *f = &record->flops;
	double ms = record->result.kernel_ms_median;

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
	json_object_set_new(doc, "leaf_visits", json_integer((json_int_t)f->leaf_visits));
	json_object_set_new(doc, "leaf_visits_per_ray",
			    json_real(f->rays ? (double)f->leaf_visits / f->rays : 0.0));
	json_object_set_new(doc, "primitive_tests", json_integer((json_int_t)f->prim_tests));
	json_object_set_new(doc, "primitive_tests_per_ray",
			    json_real(f->rays ? (double)f->prim_tests / f->rays : 0.0));
}

/* The counting run's paths (RENDERING.md, "Paths per bounce"): how many,
 * their lengths in segments, and the paths live at each bounce. */
static json_t *paths_document(const struct path_counts *p)
{
	uint64_t live[RT_PATH_LENGTH_BINS], count = 0;
	int bounces = p->max < RT_PATH_LENGTH_BINS ? (int)p->max : RT_PATH_LENGTH_BINS;
	json_t *histogram = json_array(), *per_bounce = json_array();

	for (int b = RT_PATH_LENGTH_BINS - 1; b >= 0; b--) {
		count += p->lengths[b];
		live[b] = count;
	}
	for (int b = 0; b < RT_PATH_LENGTH_BINS; b++)
		json_array_append_new(histogram, json_integer((json_int_t)p->lengths[b]));
	for (int b = 0; b < bounces; b++)
		json_array_append_new(per_bounce, json_integer((json_int_t)live[b]));
	return json_pack("{s:I, s:I, s:f, s:I, s:o, s:i, s:o}", "count", (json_int_t)count,
			 "segments", (json_int_t)p->segments, "mean_length",
			 count ? (double)p->segments / (double)count : 0.0, "max_length",
			 (json_int_t)p->max, "length_histogram", histogram, "length_bins",
			 RT_PATH_LENGTH_BINS, "live_per_bounce", per_bounce);
}

/* The textures that go to the device and the memory each takes there
 * (SCENE.md, "Textures"); nothing in a scene without. */
static void add_textures(json_t *doc, const struct scene *scene)
{
	static const char *const wraps[] = {"repeat", "clamp", "mirror"};
	json_t *list;

	if (scene->texture_count == 0)
		return;
	list = json_array();
	for (int i = 0; i < scene->texture_count; i++) {
		const struct scene_texture *t = &scene->textures[i];
		json_array_append_new(
			list, json_pack("{s:i, s:s, s:i, s:i, s:s, s:s, s:s, s:I}", "mesh", t->mesh,
					"name", t->name, "width", t->width, "height", t->height,
					"format", t->is_float ? "float linear" : "8-bit sRGB",
					"wrap_s", wraps[t->wrap_s], "wrap_t", wraps[t->wrap_t],
					"bytes", (json_int_t)t->bytes));
	}
	json_object_set_new(doc, "textures", list);
	json_object_set_new(doc, "texture_bytes", json_integer((json_int_t)scene_texture_bytes(scene)));
}

/* --accel and, with a BVH, its size and build. */
static void add_accel_figures(json_t *doc, const struct job *job, const struct record *record)
{
	const struct render_result *r = &record->result;

	json_object_set_new(doc, "accel", json_string(accel_name(job->settings.accel)));
	/* The device's scene block (none for the CPU reference), and per
	 * triangle, the figure issue 11 budgets. */
	if (r->scene_bytes)
		json_object_set_new(doc, "scene_bytes", json_integer((json_int_t)r->scene_bytes));
	if (r->scene_bytes && job->scene->triangle_count) {
		json_object_set_new(doc, "bytes_per_triangle",
				    json_real((double)r->scene_bytes / job->scene->triangle_count));
		json_object_set_new(doc, "vertices", json_integer(r->vertex_count));
	}
	add_textures(doc, job->scene);
	if (r->bvh_nodes == 0)
		return;
	json_object_set_new(doc, "bvh",
			    json_pack("{s:i, s:i, s:f, s:f, s:I, s:i, s:i}", "nodes", r->bvh_nodes,
				      "depth", r->bvh_depth, "sah_cost", r->bvh_sah_cost, "build_ms",
				      r->bvh_build_ms, "bytes", (json_int_t)r->bvh_bytes, "width",
				      r->bvh_width, "device_nodes", r->bvh_device_nodes));
}

/* The --stats document, without the figures added below. */
static json_t *image_document(const struct job *job, const struct record *record)
{
	const struct render_settings *s = &job->settings;
	const struct render_result *r = &record->result;
	char workgroup[32], groups[32];
	json_t *times = json_array();

	snprintf(workgroup, sizeof(workgroup), "%dx%d", s->workgroup[0], s->workgroup[1]);
	snprintf(groups, sizeof(groups), "%dx%d", r->groups[0], r->groups[1]);
	for (int i = 0; i < r->repeat; i++)
		json_array_append_new(times, json_real(r->kernel_ms[i]));
	return json_pack("{s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:[I,I], s:i, s:i, s:i, s:s, s:b,"
			 " s:f, s:f, s:f, s:i, s:o, s:s, s:i, s:i, s:i}",
			 "rtcl_version", RTCL_VERSION, "device", record->device.name, "device_version",
			 record->device.version, "driver", record->device.driver, "kernel",
			 s->kernel ? s->kernel->name : "reference", "workgroup", workgroup,
			 "groups", groups, "global_size", (json_int_t)r->global_size[0],
			 (json_int_t)r->global_size[1], "width", s->width, "height", s->height,
			 "max_depth", s->max_depth, "scene", job->scene->source,
			 "scene_in_local_memory", r->scene_in_local, "kernel_ms",
			 r->kernel_ms_median, "kernel_ms_min", r->kernel_ms_min, "kernel_ms_max",
			 r->kernel_ms_max, "repeat", r->repeat, "kernel_ms_all", times,
			 "build_options", r->build_options, "batch", s->batch, "samples",
			 settings_samples(s), "passes", r->passes > 0 ? r->passes : 1);
}

/* The device's size and clock, for peak-throughput estimates (not for the
 * CPU reference, which opens no device). */
static void add_device_figures(json_t *doc, const struct record *record)
{
	if (!record->device.on_device)
		return;
	json_object_set_new(doc, "compute_units", json_integer(record->device.compute_units));
	json_object_set_new(doc, "max_clock_mhz", json_integer(record->device.max_clock_mhz));
}

/* The --flops sidecar: how the counts were launched. */
static json_t *flops_sidecar(const struct job *job, const struct record *record)
{
	const struct render_settings *s = &job->settings;
	const struct render_result *c = &record->counted;
	json_t *doc = json_pack(
		"{s:s, s:i, s:s, s:[i,i], s:[i,i], s:[I,I], s:i, s:i, s:i, s:s, s:s, s:s}",
		"format", "rtcl-flops", "version", 1, "kernel", s->kernel->name, "workgroup",
		(int)c->local_size[0], (int)c->local_size[1], "groups", c->groups[0], c->groups[1],
		"global_size", (json_int_t)c->global_size[0], (json_int_t)c->global_size[1],
		"width", s->width, "height", s->height, "max_depth", s->max_depth, "device",
		record->device.name, "scene", job->scene->source, "layout",
		s->kernel->multi_pass
			? "counts[0][i]: every launch's work-items one after the other (per "
			  "sample: the primary-ray launch, one launch per bounce, the "
			  "accumulate launch)"
			: "counts[y][x] for the work-item at global id (x, y), summed over the "
			  "passes; 0 for those given no pixel");

	if (doc)
		add_flop_figures(doc, record);
	return doc;
}

/* The time breakdown of the whole process, up to now. */
static json_t *times_document(const struct record *record)
{
	const struct render_times *t = &record->result.times;
	double now = timing_now();

	json_t *doc = json_pack(
		"{s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:i}", "device_setup", record->device_ms,
		"scene_and_upload", t->scene, "build", t->build, "kernels", t->kernels, "read_back",
		t->read_back, "counting_run", record->counting_ms, "encode_and_write",
		(now - record->write_start) * 1e3, "total", (now - record->start) * 1e3, "launches",
		record->result.launches);

	/* Only where --aov or --denoise asked for them. */
	if (doc && record->result.aov)
		json_object_set_new(doc, "auxiliary_images", json_real(t->aov));
	if (doc && record->denoise_ms > 0)
		json_object_set_new(doc, "denoise", json_real(record->denoise_ms));
	return doc;
}

/* Several devices: who did what (devstats.h), and the bands. */
static json_t *shares_document(const struct device_shares *d)
{
	json_t *doc = devstats_json(d->devs, d->ranks, d->work, d->count, d->split, d->piece);

	if (doc && d->bands) {
		json_object_set_new(doc, "band_rows", json_integer(d->band_rows));
		json_object_set_new(doc, "bands", json_integer(d->bands));
	}
	if (doc && d->choice.measured)
		json_object_set_new(
			doc, "split_choice",
			json_pack("{s:f, s:i, s:f, s:f, s:f, s:f, s:f, s:f}", "pass_ms",
				  d->choice.pass_ms, "pass_samples", d->choice.pass_samples,
				  "render_ms", d->choice.render_ms, "sums_ms", d->choice.sums_ms,
				  "add_ms", d->choice.add_ms, "overhead_ms", d->choice.overhead_ms,
				  "move_ms", d->choice.move_ms, "penalty_ms", d->choice.penalty_ms));
	if (doc && d->frames_read)
		json_object_set_new(doc, "frames_read", json_string(d->frames_read));
	if (doc && d->ranks_count)
		json_object_set_new(doc, "ranks", json_integer(d->ranks_count));
	if (doc && d->rank_sums) {
		json_t *sums =
			json_pack("{s:s, s:f}", "added_by", d->rank_sums, "ms", d->rank_sums_ms);
		if (sums && d->rank_sums_into_slot)
			json_object_set_new(sums, "into_slot", json_string(d->rank_sums_into_slot));
		json_object_set_new(doc, "rank_sums", sums);
	}
	if (doc && d->row_order_given) {
		json_object_set_new(doc, "row_order",
				    json_string(d->rows.row_band ? "interleave" : "scan"));
		json_object_set_new(doc, "row_band", json_integer(d->rows.row_band));
		json_object_set_new(doc, "row_bands", json_integer(d->rows.row_bands));
		json_object_set_new(doc, "row_classes", json_integer(d->rows.row_classes));
	}
	return doc;
}

/* The last frame's pieces of one image over several devices of this
 * process: where each went and when. */
static json_t *pieces_document(const struct render_result *r)
{
	json_t *list = json_array();

	for (int b = 0; b < r->piece_count && list; b++) {
		const struct piece_record *p = &r->pieces[b];
		json_array_append_new(
			list, json_pack("{s:i, s:i, s:i, s:i, s:i, s:[i,i], s:f, s:f, s:f}",
					"device", p->device, "x0", p->piece.x0, "y0",
					p->piece.y0, "width", p->piece.width, "height",
					p->piece.height, "samples", p->piece.sample_begin,
					p->piece.sample_end, "start_ms", p->start_ms, "end_ms",
					p->end_ms, "kernel_ms", p->kernel_ms));
	}
	return list;
}

static json_t *uint_list(const uint32_t *values, int count)
{
	json_t *list = json_array();

	for (int i = 0; i < count && list; i++)
		json_array_append_new(list, json_integer(values[i]));
	return list;
}

/* The wavefront's stages form (docs/wavefront.md, "The stages form"): per
 * kernel its launches, profiled time, work-items with work and the path
 * state they moved (at most), over every frame run (a warm-up included);
 * per iteration of the last frame the paths live, started, extended and
 * shadow rays traced. */
static json_t *stages_document(const struct stages_stats *st)
{
	json_t *kernels = json_object();
	uint64_t bytes = 0;

	for (int s = 0; s < STAGE_COUNT && kernels; s++) {
		json_object_set_new(kernels, stages_name((enum stage)s),
				    json_pack("{s:i, s:f, s:I, s:I, s:i}", "launches",
					      st->launches[s], "kernel_ms", st->ms[s], "items",
					      (json_int_t)st->items[s], "state_bytes",
					      (json_int_t)st->state_bytes[s], "bytes_per_item",
					      stages_item_bytes((enum stage)s)));
		bytes += st->state_bytes[s];
	}
	return json_pack("{s:i, s:i, s:o, s:I, s:i, s:o, s:o, s:o, s:o}", "paths_in_flight",
			 st->slots, "bytes_per_path", RT_STAGE_FIELDS * 16 + 4 * RT_STAGE_QUEUES,
			 "kernels", kernels, "state_bytes", (json_int_t)bytes, "iterations",
			 st->iterations, "live_paths", uint_list(st->live, st->iterations),
			 "new_paths", uint_list(st->started, st->iterations), "extension_rays",
			 uint_list(st->extended, st->iterations), "shadow_rays",
			 uint_list(st->shadowed, st->iterations));
}

/* The --stats document of an animation. */
static json_t *frames_document(const struct job *job, const struct record *record)
{
	const struct render_settings *s = &job->settings;

	return json_pack("{s:s, s:s, s:i, s:i, s:i, s:s, s:[i,i], s:s, s:f, s:o}", "rtcl_version",
			 RTCL_VERSION, "kernel", s->kernel->name, "width", s->width, "height",
			 s->height, "max_depth", s->max_depth, "scene", job->scene->source,
			 "frames", job->first_frame, job->last_frame, "camera_path", "orbit",
			 "wall_ms", record->shares.wall_ms, "multidevice",
			 shares_document(&record->shares));
}

/* Each timed frame's wall time (frame_ms in settings.h), where it was kept. */
static void add_frame_times(json_t *doc, const struct render_result *r)
{
	json_t *times;

	if (!r->frame_ms || r->repeat < 1)
		return;
	times = json_array();
	for (int i = 0; i < r->repeat; i++)
		json_array_append_new(times, json_real(r->frame_ms[i]));
	json_object_set_new(doc, "frame_ms", json_real(r->frame_ms_median));
	json_object_set_new(doc, "frame_ms_all", times);
}

json_t *report_document(const struct job *job, const struct record *record)
{
	if (job->animation)
		return frames_document(job, record);
	json_t *doc = image_document(job, record);

	if (!doc)
		return NULL;
	json_object_set_new(doc, "time_breakdown_ms", times_document(record));
	if (job->settings.kernel && job->settings.kernel->pixel_counter) {
		/* How the persistent kernel's work-items took their work. */
		json_object_set_new(doc, "regenerate", json_boolean(job->settings.regenerate));
		json_object_set_new(doc, "fetch", json_string(fetch_name(job->settings.fetch)));
		json_object_set_new(doc, "fetch_lanes", json_integer(record->result.fetch_lanes));
	}
	json_object_set_new(doc, "build_cached", json_boolean(record->result.build_cached));
	if (record->device.on_device)
		json_object_set_new(doc, "queues", json_integer(record->result.queues));
	add_frame_times(doc, &record->result);
	if (job->counting)
		add_flop_figures(doc, record);
	if (job->counting) {
		const struct render_result *c = &record->counted;
		json_t *measured = c->simd_measured
					   ? json_pack("{s:f, s:f, s:f}", "intersect",
						       simd_measured(c, RT_SIMD_INTERSECT),
						       "traversal",
						       simd_measured(c, RT_SIMD_TRAVERSAL), "both",
						       simd_measured_all(c))
					   : json_string("not measurable on this device");
		if (c->simd_measured && job->scene->integrator == SCENE_INTEGRATOR_PATH) {
			json_object_set_new(measured, "shade",
					    json_real(simd_measured(c, RT_SIMD_SHADE)));
			json_object_set_new(measured, "all",
					    json_real(simd_measured_first(c, RT_SIMD_PHASES)));
		}
		json_object_set_new(doc, "simd_efficiency_measured", measured);
		if (job->scene->integrator == SCENE_INTEGRATOR_PATH)
			json_object_set_new(doc, "paths", paths_document(&c->paths));
	}
	if (record->simd.modelled) {
		json_object_set_new(doc, "simd_efficiency_model", json_real(record->simd.efficiency));
		if (record->counted.simd_measured)
			json_object_set_new(doc, "simd_model_error",
					    json_real(record->simd.efficiency -
						      simd_measured_all(&record->counted)));
		json_object_set_new(doc, "warp_width", json_integer(record->simd.warp_width));
		json_object_set_new(doc, "warp_steps",
				    json_integer((json_int_t)record->simd.warp_steps));
		json_object_set_new(doc, "work_items_used",
				    json_integer((json_int_t)record->simd.items_used));
	}
	add_device_figures(doc, record);
	add_accel_figures(doc, job, record);
	if (record->result.stages)
		json_object_set_new(doc, "wavefront_stages", stages_document(record->result.stages));
	/* Fewer than "samples" when an interrupt stopped the render. */
	json_object_set_new(doc, "samples_done",
			    json_integer(record_samples_done(&job->settings, record)));
	if (record->shares.count) {
		json_t *shares = shares_document(&record->shares);
		if (shares && record->result.pieces)
			json_object_set_new(shares, "pieces", pieces_document(&record->result));
		json_object_set_new(doc, "multidevice", shares);
	}
	return doc;
}

json_t *report_flops_sidecar(const struct job *job, const struct record *record)
{
	return flops_sidecar(job, record);
}
