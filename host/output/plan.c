#include "output/plan.h"

#include <errno.h>
#include <jansson.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/interrupt.h"
#include "base/quote.h"
#include "base/test_hooks.h"
#include "base/timing.h"
#include "base/version.h"
#include "output/image.h"
#include "output/npy.h"
#include "output/schedmap.h"
#include "rtcl_shared.h"
#include "output/workmap.h"
#include "render/program.h"
#include "report/document.h"

/* Room for a path and the ".json" of the --flops sidecar. */
#define SIDECAR_PATH_SIZE (PATH_MAX + 8)
/* A resolved directory, a slash and a file name. */
#define CANONICAL_SIZE (2 * PATH_MAX)
/* Besides the images: the work map and its bar, the schedule map, the flops
 * and their sidecar, the stats, RTCL_DUMP_BINARY. */
#define MAX_OTHER_OUTPUTS (7 + OUTPUT_AOV_KINDS)

/* One output file of the run besides the images, and the option that named
 * it. */
struct output {
	const char *option;
	const char *path;
};

int output_frame_name(const char *path, int frame, char *name)
{
	const char *ext = files_extension(path);
	int stem = (int)(ext - path);
	int n = snprintf(name, PATH_MAX, "%.*s_%04d%s", stem, path, frame, ext);

	return n < 0 || n >= PATH_MAX ? -1 : 0;
}

const char *output_aov_kind_name(int kind)
{
	static const char *const names[OUTPUT_AOV_KINDS] = {"albedo", "normal", "depth"};

	return names[kind];
}

int output_aov_name(const char *path, int kind, char *name)
{
	const char *ext = files_extension(path);
	int n = snprintf(name, PATH_MAX, "%.*s.%s.pfm", (int)(ext - path), path,
			 output_aov_kind_name(kind));

	return n < 0 || n >= PATH_MAX ? -1 : 0;
}

void output_plan_close(struct output_plan *plan)
{
	for (int i = 0; plan->staged && i < plan->frames + MAX_OTHER_OUTPUTS; i++)
		files_discard(&plan->staged[i]);
	for (int i = 0; plan->held && i < plan->frames; i++)
		free(plan->held[i]);
	free(plan->names);
	free(plan->staged);
	free(plan->held);
	plan->names = NULL;
	plan->staged = NULL;
	plan->held = NULL;
}

int output_plan_open(struct output_plan *plan, const struct output_request *request,
		     const struct job *job, char *err, size_t err_size)
{
	int n = job_frame_count(job);

	memset(plan, 0, sizeof(*plan));
	plan->request = request;
	plan->job = job;
	plan->frames = n;
	plan->names = calloc((size_t)n, PATH_MAX);
	plan->staged = calloc((size_t)n + MAX_OTHER_OUTPUTS, sizeof(struct staged_file));
	plan->held = calloc((size_t)n, sizeof(float *));
	if (!plan->names || !plan->staged || !plan->held) {
		output_plan_close(plan);
		snprintf(err, err_size, "out of host memory for %d frames", n);
		return -1;
	}
	for (int k = 0; k < OUTPUT_AOV_KINDS; k++)
		if ((request->aov & (1 << k)) &&
		    output_aov_name(request->image, k, plan->aov_names[k]))
			plan->aov_names_too_long = 1;
	if (!job->animation) {
		snprintf(plan->names[0], PATH_MAX, "%s", request->image);
		return 0;
	}
	/* A name too long is output_plan_check's to report: under --mpi only
	 * rank 0 checks, and tells the other ranks. */
	for (int i = 0; i < n; i++)
		if (output_frame_name(request->image, job->first_frame + i, plan->names[i]))
			plan->names_too_long = 1;
	return 0;
}

/* Lists the outputs the plan's request asks for besides the images, the
 * sidecar written into sidecar. */
static int list_outputs(const struct output_plan *plan, char *sidecar, struct output *out)
{
	const struct output_request *r = plan->request;
	int n = 0;

	for (int k = 0; k < OUTPUT_AOV_KINDS; k++)
		if (r->aov & (1 << k))
			out[n++] = (struct output){"--aov", plan->aov_names[k]};
	if (r->work_map)
		out[n++] = (struct output){"--work-map", r->work_map};
	if (r->work_map_bar)
		out[n++] = (struct output){"--work-map-bar", r->work_map_bar};
	if (r->schedule_map)
		out[n++] = (struct output){"--schedule-map", r->schedule_map};
	if (r->flops) {
		snprintf(sidecar, SIDECAR_PATH_SIZE, "%s.json", r->flops);
		out[n++] = (struct output){"--flops", r->flops};
		out[n++] = (struct output){"--flops (its sidecar)", sidecar};
	}
	if (r->stats)
		out[n++] = (struct output){"--stats", r->stats};
	if (program_dump_path())
		out[n++] = (struct output){"RTCL_DUMP_BINARY", program_dump_path()};
	return n;
}

/* The file path names, as an absolute path through its directory's real
 * location (so "./x.png", "x.png" and a path through a symbolic link to the
 * directory compare equal); path itself when the directory cannot be resolved. */
static void canonical(const char *path, char *out)
{
	const char *base = files_base_name(path);
	char dir[PATH_MAX], resolved[PATH_MAX];
	size_t dir_length = (size_t)(base - path);

	snprintf(dir, sizeof(dir), "%.*s", (int)(dir_length ? dir_length : 1),
		 dir_length ? path : ".");
	if (realpath(dir, resolved))
		snprintf(out, CANONICAL_SIZE, "%s/%s", strcmp(resolved, "/") ? resolved : "", base);
	else
		snprintf(out, CANONICAL_SIZE, "%s", path);
}

int output_same_file(const char *a, const char *b)
{
	char ca[CANONICAL_SIZE], cb[CANONICAL_SIZE];
	struct stat sa, sb;

	canonical(a, ca);
	canonical(b, cb);
	if (strcmp(ca, cb) == 0)
		return 1;
	/* Two names of one existing file: a symbolic or a hard link. */
	return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev &&
	       sa.st_ino == sb.st_ino;
}

/* Which output, for a message: "--stats x.json", "frame 3's image f_0003.png". */
static void describe(const struct output *out, int frame, const char *name, char *text, size_t size)
{
	if (out)
		snprintf(text, size, "%s %s", out->option, quote_text(out->path));
	else
		snprintf(text, size, "frame %d's image %s", frame, quote_text(name));
}

/* Refuses an output that is one of the files the scene was read from (by
 * identity: a hard link, a symbolic link or "./" count). */
static int check_not_input(const struct scene *scene, const struct stat *inputs,
			   const struct output *out, int frame, const char *name, char *err,
			   size_t err_size)
{
	struct stat st;
	char what[PATH_MAX + 64];

	if (stat(name, &st) != 0)
		return 0; /* not there yet: not an input */
	for (int i = 0; i < scene->input_count; i++) {
		if (inputs[i].st_nlink == 0 || inputs[i].st_dev != st.st_dev ||
		    inputs[i].st_ino != st.st_ino)
			continue;
		describe(out, frame, name, what, sizeof(what));
		snprintf(err, err_size,
			 "%s names the %s %s: rtcl does not replace a file the run reads; give "
			 "the output another name",
			 what, scene->inputs[i].kind, quote_text(scene->inputs[i].path));
		return OUTPUT_CLASH;
	}
	return 0;
}

/* Two outputs that name one file; and outputs that name an input. */
static int check_clashes(const struct output_plan *plan, const struct output *out, int n,
			 char *err, size_t err_size)
{
	const struct scene *scene = plan->job->scene;
	struct stat *inputs =
		calloc(scene->input_count > 0 ? (size_t)scene->input_count : 1, sizeof(*inputs));
	char a[PATH_MAX + 64], b[PATH_MAX + 64];
	int ret = 0;

	if (!inputs) {
		snprintf(err, err_size, "out of host memory to check the outputs");
		return -1;
	}
	for (int i = 0; i < scene->input_count; i++)
		if (stat(scene->inputs[i].path, &inputs[i]) != 0)
			inputs[i].st_nlink = 0; /* gone: nothing to protect */
	for (int i = 0; i < n && !ret; i++) {
		for (int j = 0; j < i && !ret; j++) {
			if (!output_same_file(out[i].path, out[j].path))
				continue;
			describe(&out[j], 0, NULL, a, sizeof(a));
			describe(&out[i], 0, NULL, b, sizeof(b));
			snprintf(err, err_size,
				 "%s and %s name the same file: give each output a file of its own",
				 a, b);
			ret = OUTPUT_CLASH;
		}
		if (!ret)
			ret = check_not_input(scene, inputs, &out[i], 0, out[i].path, err,
					      err_size);
	}
	/* The frames' names differ from one another by construction. */
	for (int f = 0; plan->job->animation && f < plan->frames && !ret; f++) {
		const char *name = plan->names[f];
		int frame = plan->job->first_frame + f;
		for (int i = 0; i < n && !ret; i++) {
			if (!output_same_file(out[i].path, name))
				continue;
			describe(&out[i], 0, NULL, a, sizeof(a));
			describe(NULL, frame, name, b, sizeof(b));
			snprintf(err, err_size,
				 "%s and %s name the same file: give each output a file of its own",
				 a, b);
			ret = OUTPUT_CLASH;
		}
		if (!ret)
			ret = check_not_input(scene, inputs, NULL, frame, name, err, err_size);
	}
	free(inputs);
	return ret;
}

int output_plan_check(const struct output_plan *plan, char *err, size_t err_size)
{
	const struct output_request *r = plan->request;
	struct output out[MAX_OTHER_OUTPUTS + 1];
	char sidecar[SIDECAR_PATH_SIZE];
	int n = 0;

	/* One image is an output like the others; an animation's frames are
	 * checked by name below. */
	if (!plan->job->animation)
		out[n++] = (struct output){"-o/--output", r->image};
	int others = n;
	n += list_outputs(plan, sidecar, out + n);
	if (plan->aov_names_too_long) {
		snprintf(err, err_size, "--aov: %s: the auxiliary images' names are too long",
			 quote_text(r->image));
		return -1;
	}
	if (plan->names_too_long) {
		snprintf(err, err_size, "-o/--output: %s: the frame names are too long",
			 quote_text(r->image));
		return -1;
	}
	int clash = check_clashes(plan, out, n, err, err_size);
	if (clash)
		return clash;
	for (int f = 0; f < plan->frames; f++)
		if (image_check_writable(plan->names[f], err, err_size))
			return -1;
	for (int i = others; i < n; i++) {
		const char *path = out[i].path;
		int image = ((path == r->work_map || path == r->schedule_map) &&
			     workmap_kind(path) != WORKMAP_NPY) ||
			    path == r->work_map_bar || strcmp(out[i].option, "--aov") == 0;
		if (image ? image_check_writable(path, err, err_size)
			  : files_check_writable(path, err, err_size))
			return -1;
	}
	return 0;
}

/* Stages image i, which holds `samples` samples per pixel, into staged. */
static int stage_image(const struct output_plan *plan, struct staged_file *staged, int i,
		       const float *rgb, int samples, const char *why, char *err, size_t err_size)
{
	const struct job *job = plan->job;
	const struct render_settings *s = &job->settings;
	int planned = settings_samples(s);
	char description[1024];
	struct image_meta meta = {"rtcl " RTCL_VERSION, description,
				  plan->request->linear_encoding ? IMAGE_LINEAR : IMAGE_SRGB,
				  samples};
	size_t n = (size_t)snprintf(description, sizeof(description),
				    "scene %s, kernel %s, %dx%d, max depth %d", job->scene->source,
				    s->kernel ? s->kernel->name : "reference", s->width, s->height,
				    s->max_depth);
	if (job->animation && n < sizeof(description))
		n += (size_t)snprintf(description + n, sizeof(description) - n,
				      ", frame %d of %d..%d", job->first_frame + i,
				      job->first_frame, job->last_frame);
	if (samples < planned && n < sizeof(description))
		snprintf(description + n, sizeof(description) - n,
			 ", %d of %d samples per pixel (%s)", samples, planned, why);
	else if (n < sizeof(description))
		snprintf(description + n, sizeof(description) - n, ", %d sample%s per pixel",
			 samples, samples == 1 ? "" : "s");
	return image_stage(staged, plan->names[i], rgb, s->width, s->height, &meta, err, err_size);
}

int output_plan_stage_image(struct output_plan *plan, int i, const float *rgb, int samples,
			    char *err, size_t err_size)
{
	return stage_image(plan, &plan->staged[i], i, rgb, samples, "interrupted", err, err_size);
}

int output_plan_write_checkpoint(struct output_plan *plan, const float *rgb, int samples, char *err,
				 size_t err_size)
{
	struct staged_file staged;

	memset(&staged, 0, sizeof(staged));
	if (stage_image(plan, &staged, 0, rgb, samples, "a checkpoint", err, err_size))
		return -1;
	/* One step for an interrupt: the rename and what the message says. */
	interrupt_hold();
	if (files_commit(&staged, 1, err, err_size)) {
		interrupt_release();
		return -1;
	}
	interrupt_set_outcome("the image's last checkpoint was written, no other output");
	interrupt_release();
	plan->checkpoints++;
	plan->checkpoint_samples = samples;
	return 0;
}

int output_plan_check_memory(const struct output_plan *plan, char *err, size_t err_size)
{
	const struct render_settings *s = &plan->job->settings;
	const double gib = 1024.0 * 1024 * 1024;
	double need = (double)plan->frames * (double)image_float_bytes(s->width, s->height);
	long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGESIZE);
	double limit = pages > 0 && page_size > 0 ? (double)pages * (double)page_size / 2 : 0;

	if (limit <= 0 || need <= limit)
		return 0; /* an unknown host size: malloc says when it is too much */
	snprintf(err, err_size,
		 "--frames: under --mpi, rank 0 keeps every frame in host memory until all "
		 "have arrived: %d frames of %dx%d need %.1f GiB (%zu bytes a pixel), more than "
		 "the limit of %.1f GiB (half of this host's memory): render fewer frames per run "
		 "or a smaller --size",
		 plan->frames, s->width, s->height, need / gib, image_float_bytes(1, 1),
		 limit / gib);
	return -1;
}

int output_plan_hold(struct output_plan *plan, int i, float *rgb, char *err, size_t err_size)
{
	if (plan->held[i]) {
		free(rgb);
		snprintf(err, err_size, "frame %s arrived twice", quote_text(plan->names[i]));
		return -1;
	}
	plan->held[i] = rgb;
	return 0;
}

int output_plan_check_held(const struct output_plan *plan, char *err, size_t err_size)
{
	for (int i = 0; i < plan->frames; i++) {
		if (!plan->held[i]) {
			snprintf(err, err_size, "frame %s never arrived",
				 quote_text(plan->names[i]));
			return -1;
		}
	}
	return 0;
}

static int any_held(const struct output_plan *plan)
{
	for (int i = 0; i < plan->frames; i++)
		if (plan->held[i])
			return 1;
	return 0;
}

/* Stages the held images, each freed once staged: the encoders' memory
 * comes on top. */
static int stage_held(struct output_plan *plan, char *err, size_t err_size)
{
	if (output_plan_check_held(plan, err, err_size))
		return -1;
	for (int i = 0; i < plan->frames; i++) {
		if (output_plan_stage_image(plan, i, plan->held[i],
					    settings_samples(&plan->job->settings), err, err_size))
			return -1;
		free(plan->held[i]);
		plan->held[i] = NULL;
	}
	return 0;
}

static int stage_json(struct staged_file *staged, const char *path, json_t *doc, char *err,
		      size_t err_size)
{
	int failed = !doc || files_stage_with(staged, path, report_fill_json, doc, err, err_size);

	if (!doc)
		snprintf(err, err_size, "%s: cannot build the JSON document", quote_text(path));
	json_decref(doc);
	return failed ? -1 : 0;
}

static int stage_work_map(struct staged_file *staged, const struct output_plan *plan,
			  const struct record *record, char *err, size_t err_size)
{
	const struct output_request *r = plan->request;
	const uint64_t *counts = record->counted.pixel_flops;
	int w = plan->job->settings.width, h = plan->job->settings.height;
	enum workmap_scale scale = r->work_map_log ? WORKMAP_LOG : WORKMAP_LINEAR;

	switch (workmap_kind(r->work_map)) {
	case WORKMAP_NPY:
		return npy_stage(staged, r->work_map, counts, (size_t)h, (size_t)w, err, err_size);
	case WORKMAP_FLOATS:
		return workmap_stage_counts(staged, r->work_map, counts, w, h, err, err_size);
	default:
		return workmap_stage(staged, r->work_map, counts, w, h, scale, err, err_size);
	}
}

/* The counting run's per-work-item flops: shape (global y, global x), or (1,
 * every launch's work-items) for the wavefront. */
static int stage_flops(struct staged_file *staged, const struct output_plan *plan,
		       const struct record *record, char *err, size_t err_size)
{
	const struct render_result *c = &record->counted;
	int one_row = plan->job->settings.kernel->multi_pass;

	return npy_stage(staged, plan->request->flops, c->item_flops,
			 one_row ? 1 : c->global_size[1],
			 one_row ? c->item_count : c->global_size[0], err, err_size);
}

/* The schedule map: its three words per pixel as .npy, or a picture. */
static int stage_schedule_map(struct staged_file *staged, const struct output_plan *plan,
			      const struct record *record, char *err, size_t err_size)
{
	const char *path = plan->request->schedule_map;
	const uint32_t *schedule = record->counted.schedule;
	int w = plan->job->settings.width, h = plan->job->settings.height;

	if (workmap_kind(path) == WORKMAP_NPY)
		return npy_stage_u32(staged, path, schedule, (size_t)h, (size_t)w,
				     RT_SCHEDULE_WORDS, err, err_size);
	return schedmap_stage(staged, path, schedule, w, h, err, err_size);
}

/* Auxiliary image `kind` (render_result.aov) as linear RGB in a .pfm: the
 * depth in all three channels. */
static int stage_aov(struct staged_file *staged, const struct output_plan *plan,
		     const struct record *record, int kind, char *err, size_t err_size)
{
	int w = plan->job->settings.width, h = plan->job->settings.height;
	size_t pixels = (size_t)w * h;
	const float *aov = record->result.aov;
	float *grey = NULL;
	int ret;

	if (!aov) {
		snprintf(err, err_size, "internal error: no auxiliary images were rendered");
		return -1;
	}
	if (kind == 2) {
		grey = malloc(pixels * 3 * sizeof(float));
		if (!grey) {
			snprintf(err, err_size, "out of host memory for the depth image");
			return -1;
		}
		for (size_t i = 0; i < pixels; i++)
			grey[3 * i] = grey[3 * i + 1] = grey[3 * i + 2] = aov[6 * pixels + i];
	}
	ret = image_stage(staged, plan->aov_names[kind], grey ? grey : aov + 3 * pixels * kind, w,
			  h, NULL, err, err_size);
	free(grey);
	return ret;
}

/* Stages the outputs besides the images into staged[]; returns how many,
 * or -1. */
static int stage_others(const struct output_plan *plan, const struct record *record,
			struct staged_file *staged, char *err, size_t err_size)
{
	const struct output_request *r = plan->request;
	const struct render_settings *s = &plan->job->settings;
	char sidecar[SIDECAR_PATH_SIZE];
	int n = 0;

	for (int k = 0; k < OUTPUT_AOV_KINDS; k++)
		if ((r->aov & (1 << k)) && stage_aov(&staged[n++], plan, record, k, err, err_size))
			return -1;
	if (r->work_map && stage_work_map(&staged[n++], plan, record, err, err_size))
		return -1;
	if (r->work_map_bar &&
	    workmap_stage_bar(&staged[n++], r->work_map_bar, record->counted.pixel_flops,
			      s->width, s->height, r->work_map_log ? WORKMAP_LOG : WORKMAP_LINEAR,
			      err, err_size))
		return -1;
	if (r->schedule_map && stage_schedule_map(&staged[n++], plan, record, err, err_size))
		return -1;
	if (r->flops) {
		snprintf(sidecar, sizeof(sidecar), "%s.json", r->flops);
		if (stage_flops(&staged[n++], plan, record, err, err_size) ||
		    stage_json(&staged[n++], sidecar, report_flops_sidecar(plan->job, record), err,
			       err_size))
			return -1;
	}
	if (r->stats &&
	    stage_json(&staged[n++], r->stats, report_document(plan->job, record), err, err_size))
		return -1;
	int dumped = program_stage_dump(&staged[n], err, err_size);
	return dumped < 0 ? -1 : n + dumped;
}

int output_plan_commit(struct output_plan *plan, struct record *record, char *err,
		       size_t err_size)
{
	record->write_start = timing_now();
	/* The images: held ones (--mpi), or one image's; an animation's frames
	 * were staged as they were rendered. */
	int failed = 0;
	if (any_held(plan))
		failed = stage_held(plan, err, err_size);
	else if (!plan->job->animation)
		failed = output_plan_stage_image(plan, 0, record->result.rgb,
						 record_samples_done(&plan->job->settings, record),
						 err, err_size);
	if (failed)
		return -1;
	plan->frames_written = 0;
	for (int i = 0; i < plan->frames; i++)
		plan->frames_written += plan->staged[i].temp[0] != '\0';
	int others = stage_others(plan, record, plan->staged + plan->frames, err, err_size);
	if (others < 0)
		return -1;
	/* One step for an interrupt: the renames and what the message says. */
	interrupt_hold();
	int ret = files_commit(plan->staged, plan->frames + others, err, err_size);
	if (ret == 0) {
		interrupt_set_outcome("the outputs were written");
		hook_commit_delay();
	}
	interrupt_release();
	return ret;
}

void output_plan_print(const struct output_plan *plan, FILE *out)
{
	const struct output_request *r = plan->request;

	if (plan->job->animation) {
		fprintf(out, "output:  %s", quote_text(plan->names[0]));
		if (plan->frames > 1)
			fprintf(out, " .. %s", quote_text(plan->names[plan->frames - 1]));
		if (plan->frames_written < plan->frames)
			fprintf(out,
				": the %d frame%s finished (interrupted; the frames not "
				"finished are not written)",
				plan->frames_written, plan->frames_written == 1 ? "" : "s");
		fprintf(out, "\n");
		return;
	}
	fprintf(out, "output:  %s", quote_text(r->image));
	if (plan->checkpoints)
		fprintf(out, " (%d checkpoint%s before it)", plan->checkpoints,
			plan->checkpoints == 1 ? "" : "s");
	for (int k = 0; k < OUTPUT_AOV_KINDS; k++)
		if (r->aov & (1 << k))
			fprintf(out, ", %s %s", output_aov_kind_name(k),
				quote_text(plan->aov_names[k]));
	if (r->work_map)
		fprintf(out, ", work map %s", quote_text(r->work_map));
	if (r->flops)
		fprintf(out, ", flops %s", quote_text(r->flops));
	if (r->schedule_map)
		fprintf(out, ", schedule map %s", quote_text(r->schedule_map));
	fprintf(out, "\n");
}
