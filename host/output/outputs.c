#include "output/outputs.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "base/test_hooks.h"
#include "base/files.h"
#include "run/frames.h"
#include "output/image.h"
#include "base/interrupt.h"
#include "render/program.h"
#include "base/quote.h"
#include "output/workmap.h"

/* Room for a path and the ".json" of the --flops sidecar. */
#define SIDECAR_PATH_SIZE (PATH_MAX + 8)
/* A resolved directory, a slash and a file name. */
#define CANONICAL_SIZE (2 * PATH_MAX)
/* The image, the work map and its bar, the flops and their sidecar, the
 * stats, RTCL_DUMP_BINARY. */
#define MAX_OUTPUTS 7

/* One output file of the run, and the option that named it. */
struct output {
	const char *option;
	const char *path;
};

static enum workmap_scale work_map_scale(const struct options *opt)
{
	return opt->work_map_log ? WORKMAP_LOG : WORKMAP_LINEAR;
}

static int stage_work_map(struct staged_file *staged, const struct run *run, char *err,
			  size_t err_size)
{
	const char *path = run->opt->work_map_path;
	const uint64_t *counts = run->counted.pixel_flops;
	int w = run->settings.width, h = run->settings.height;

	switch (workmap_kind(path)) {
	case WORKMAP_NPY:
		return stats_stage_pixel_counts(staged, path, run, err, err_size);
	case WORKMAP_FLOATS:
		return workmap_stage_counts(staged, path, counts, w, h, err, err_size);
	default:
		return workmap_stage(staged, path, counts, w, h, work_map_scale(run->opt), err,
				     err_size);
	}
}

/* Lists the outputs the options ask for besides an animation's frames
 * (frames_output_name names those), the sidecar written into sidecar. */
static int list_outputs(const struct options *opt, char *sidecar, struct output *out)
{
	int n = 0;

	if (!opt->frames_given)
		out[n++] = (struct output){"-o/--output", opt->output};
	if (opt->work_map_path)
		out[n++] = (struct output){"--work-map", opt->work_map_path};
	if (opt->work_map_bar_path)
		out[n++] = (struct output){"--work-map-bar", opt->work_map_bar_path};
	if (opt->flops_path) {
		snprintf(sidecar, SIDECAR_PATH_SIZE, "%s.json", opt->flops_path);
		out[n++] = (struct output){"--flops", opt->flops_path};
		out[n++] = (struct output){"--flops (its sidecar)", sidecar};
	}
	if (opt->stats_path)
		out[n++] = (struct output){"--stats", opt->stats_path};
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

int outputs_same_file(const char *a, const char *b)
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
		return OUTPUTS_CLASH;
	}
	return 0;
}

/* Two outputs that name one file; and outputs that name an input. */
static int check_clashes(const struct options *opt, const struct scene *scene,
			 const struct output *out, int n, char *err, size_t err_size)
{
	struct stat *inputs =
		calloc(scene->input_count > 0 ? (size_t)scene->input_count : 1, sizeof(*inputs));
	char name[PATH_MAX], a[PATH_MAX + 64], b[PATH_MAX + 64];
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
			if (!outputs_same_file(out[i].path, out[j].path))
				continue;
			describe(&out[j], 0, NULL, a, sizeof(a));
			describe(&out[i], 0, NULL, b, sizeof(b));
			snprintf(err, err_size,
				 "%s and %s name the same file: give each output a file of its own",
				 a, b);
			ret = OUTPUTS_CLASH;
		}
		if (!ret)
			ret = check_not_input(scene, inputs, &out[i], 0, out[i].path, err,
					      err_size);
	}
	/* The frames' names differ from one another by construction. */
	for (int f = opt->frames[0]; opt->frames_given && f <= opt->frames[1] && !ret; f++) {
		if (frames_output_name(opt->output, f, name)) {
			snprintf(err, err_size, "-o/--output: %s: the frame names are too long",
				 quote_text(opt->output));
			ret = -1;
			break;
		}
		for (int i = 0; i < n && !ret; i++) {
			if (!outputs_same_file(out[i].path, name))
				continue;
			describe(&out[i], 0, NULL, a, sizeof(a));
			describe(NULL, f, name, b, sizeof(b));
			snprintf(err, err_size,
				 "%s and %s name the same file: give each output a file of its own",
				 a, b);
			ret = OUTPUTS_CLASH;
		}
		if (!ret)
			ret = check_not_input(scene, inputs, NULL, f, name, err, err_size);
	}
	free(inputs);
	return ret;
}

int outputs_check(const struct options *opt, const struct scene *scene, char *err, size_t err_size)
{
	struct output out[MAX_OUTPUTS];
	char sidecar[SIDECAR_PATH_SIZE];
	int n = list_outputs(opt, sidecar, out);
	int clash = check_clashes(opt, scene, out, n, err, err_size);

	if (clash)
		return clash;
	if (opt->frames_given)
		return frames_check_outputs(opt, err, err_size) ||
				       (program_dump_path() &&
					files_check_writable(program_dump_path(), err, err_size))
			       ? -1
			       : 0;
	if (image_check_writable(opt->output, err, err_size))
		return -1;
	if (opt->work_map_path &&
	    (workmap_kind(opt->work_map_path) == WORKMAP_NPY
		     ? files_check_writable(opt->work_map_path, err, err_size)
		     : image_check_writable(opt->work_map_path, err, err_size)))
		return -1;
	if (opt->work_map_bar_path && image_check_writable(opt->work_map_bar_path, err, err_size))
		return -1;
	for (int i = 0; i < n; i++)
		if (strncmp(out[i].option, "-o", 2) && strncmp(out[i].option, "--work-map", 10) &&
		    files_check_writable(out[i].path, err, err_size))
			return -1;
	return 0;
}

/* Stages every output (the sidecar's name in sidecar); on a failure
 * discards what it staged. Returns how many were staged, or -1. */
static int stage_all(const struct run *run, char *sidecar, struct staged_file *staged, char *err,
		     size_t err_size)
{
	const struct options *opt = run->opt;
	const struct render_settings *s = &run->settings;
	char description[1024];
	struct image_meta meta = {"rtcl " RTCL_VERSION, description,
				  opt->linear_encoding ? IMAGE_LINEAR : IMAGE_SRGB};
	int n = 0;

	snprintf(description, sizeof(description), "scene %s, kernel %s, %dx%d, max depth %d",
		 run->scene->source, opt->kernel, s->width, s->height, s->max_depth);
	if (image_stage(&staged[n++], opt->output, run->result.rgb, s->width, s->height, &meta, err,
			err_size))
		goto out_discard;
	if (opt->work_map_path && stage_work_map(&staged[n++], run, err, err_size))
		goto out_discard;
	if (opt->work_map_bar_path &&
	    workmap_stage_bar(&staged[n++], opt->work_map_bar_path, run->counted.pixel_flops,
			      s->width, s->height, work_map_scale(opt), err, err_size))
		goto out_discard;
	if (opt->flops_path) {
		snprintf(sidecar, SIDECAR_PATH_SIZE, "%s.json", opt->flops_path);
		if (stats_stage_flops(&staged[n++], opt->flops_path, run, err, err_size) ||
		    stats_stage_flops_sidecar(&staged[n++], sidecar, run, err, err_size))
			goto out_discard;
	}
	if (opt->stats_path && stats_stage_run(&staged[n++], opt->stats_path, run, err, err_size))
		goto out_discard;
	int dumped = program_stage_dump(&staged[n], err, err_size);
	if (dumped < 0)
		goto out_discard;
	return n + dumped;

out_discard:
	while (n > 0)
		files_discard(&staged[--n]);
	return -1;
}

int outputs_write(const struct run *run, char *err, size_t err_size)
{
	struct staged_file staged[MAX_OUTPUTS];
	char sidecar[SIDECAR_PATH_SIZE];
	int n;

	memset(staged, 0, sizeof(staged));
	n = stage_all(run, sidecar, staged, err, err_size);
	if (n < 0)
		return -1;
	/* One step for an interrupt: the renames and what the message says. */
	interrupt_hold();
	int ret = files_commit(staged, n, err, err_size);
	if (ret == 0) {
		interrupt_set_outcome("the outputs were written");
		hook_commit_delay();
	}
	interrupt_release();
	return ret;
}
