#include "run/job_digest.h"

#include <stdio.h>
#include <string.h>

#include "base/quote.h"
#include "render/render.h"
#include "scene/scene.h"

void job_digest_fill(const struct job *job, struct job_digest *d)
{
	const struct render_settings *s = &job->settings;
	long long *v = d->setting;

	memset(d, 0, sizeof(*d));
	d->scene_digest = scene_digest(job->scene);
	snprintf(d->source, sizeof(d->source), "%s", job->scene->source);
	v[JOB_WIDTH] = s->width;
	v[JOB_HEIGHT] = s->height;
	v[JOB_SAMPLES] = s->samples;
	v[JOB_DEPTH] = s->max_depth;
	v[JOB_FRAMES_GIVEN] = job->animation;
	v[JOB_FRAME_FIRST] = job->animation ? job->first_frame : 0;
	v[JOB_FRAME_LAST] = job->animation ? job->last_frame : 0;
	v[JOB_PIECE_ROWS] = job->piece_rows;
	/* The split and whether it was given: the default chooses. */
	v[JOB_SPLIT_STATIC] = (int)job->split + 3 * (job->split_given != 0);
	v[JOB_ROW_ORDER] = job->row_order;
	v[JOB_ROW_CLASSES] = job->row_classes;
	v[JOB_KERNEL] = s->kernel ? s->kernel - render_kernels : -1;
	v[JOB_WORKGROUP_X] = s->workgroup[0];
	v[JOB_WORKGROUP_Y] = s->workgroup[1];
	v[JOB_GROUPS_X] = s->groups[0];
	v[JOB_GROUPS_Y] = s->groups[1];
	v[JOB_BATCH] = s->batch;
	v[JOB_ACCEL] = s->accel;
	v[JOB_FETCH] = s->fetch;
	v[JOB_REGENERATE] = s->regenerate;
	v[JOB_WAVEFRONT_STAGES] = s->wavefront_stages;
	v[JOB_PATHS_IN_FLIGHT] = s->paths_in_flight;
}

/* The settings as the options name them, in the order a mismatch is
 * looked for: each covers count numbers from first. */
static const struct {
	enum job_setting first;
	int count;
} job_options[] = {
	{JOB_WIDTH, 2},	     {JOB_SAMPLES, 1},	    {JOB_DEPTH, 1},  {JOB_FRAMES_GIVEN, 3},
	{JOB_PIECE_ROWS, 1}, {JOB_SPLIT_STATIC, 1}, {JOB_ROW_ORDER, 2}, {JOB_KERNEL, 1}, {JOB_WORKGROUP_X, 2},
	{JOB_GROUPS_X, 2},   {JOB_BATCH, 1},	    {JOB_ACCEL, 1},
	{JOB_FETCH, 1},	     {JOB_REGENERATE, 1},   {JOB_WAVEFRONT_STAGES, 1},
	{JOB_PATHS_IN_FLIGHT, 1},
};

/* One setting of a digest as an option would give it ("--spp 4"). */
static void show_setting(const long long *v, enum job_setting first, char *out, size_t size)
{
	switch (first) {
	case JOB_WIDTH:
		snprintf(out, size, "--size %lldx%lld", v[JOB_WIDTH], v[JOB_HEIGHT]);
		break;
	case JOB_SAMPLES:
		snprintf(out, size, "--spp %lld", v[JOB_SAMPLES]);
		break;
	case JOB_DEPTH:
		snprintf(out, size, "--depth %lld", v[JOB_DEPTH]);
		break;
	case JOB_FRAMES_GIVEN:
		if (v[JOB_FRAMES_GIVEN])
			snprintf(out, size, "--frames %lld:%lld", v[JOB_FRAME_FIRST],
				 v[JOB_FRAME_LAST]);
		else
			snprintf(out, size, "one image (no --frames)");
		break;
	case JOB_PIECE_ROWS:
		if (v[JOB_PIECE_ROWS])
			snprintf(out, size, "--piece-rows %lld", v[JOB_PIECE_ROWS]);
		else
			snprintf(out, size, "no --piece-rows");
		break;
	case JOB_SPLIT_STATIC:
		snprintf(out, size, "--split %s%s", split_name((enum split)(v[JOB_SPLIT_STATIC] % 3)),
			 v[JOB_SPLIT_STATIC] >= 3 ? "" : " (the default)");
		break;
	case JOB_ROW_ORDER:
		if (v[JOB_ROW_ORDER] == ROWS_INTERLEAVE && v[JOB_ROW_CLASSES])
			snprintf(out, size, "--row-order interleave:%lld", v[JOB_ROW_CLASSES]);
		else
			snprintf(out, size, "--row-order %s",
				 v[JOB_ROW_ORDER] == ROWS_SCAN ? "scan" : "interleave");
		break;
	case JOB_KERNEL:
		snprintf(out, size, "-k %s",
			 v[JOB_KERNEL] >= 0 && v[JOB_KERNEL] < render_kernel_count
				 ? render_kernels[v[JOB_KERNEL]].name
				 : "?");
		break;
	case JOB_WORKGROUP_X:
		snprintf(out, size, "-w %lldx%lld", v[JOB_WORKGROUP_X], v[JOB_WORKGROUP_Y]);
		break;
	case JOB_GROUPS_X:
		snprintf(out, size, "--groups %lldx%lld", v[JOB_GROUPS_X], v[JOB_GROUPS_Y]);
		break;
	case JOB_BATCH:
		snprintf(out, size, "--batch %lld", v[JOB_BATCH]);
		break;
	case JOB_ACCEL:
		snprintf(out, size, "--accel %s", accel_name((int)v[JOB_ACCEL]));
		break;
	case JOB_FETCH:
		snprintf(out, size, "--fetch %s", fetch_name((int)v[JOB_FETCH]));
		break;
	case JOB_REGENERATE:
		snprintf(out, size, "%s", v[JOB_REGENERATE] ? "--regenerate" : "no --regenerate");
		break;
	case JOB_WAVEFRONT_STAGES:
		snprintf(out, size, "--wavefront-form %s",
			 v[JOB_WAVEFRONT_STAGES] ? "stages" : "bounce");
		break;
	case JOB_PATHS_IN_FLIGHT:
		if (v[JOB_PATHS_IN_FLIGHT])
			snprintf(out, size, "--paths-in-flight %lld", v[JOB_PATHS_IN_FLIGHT]);
		else
			snprintf(out, size, "no --paths-in-flight");
		break;
	default:
		snprintf(out, size, "setting %d", (int)first);
	}
}

int job_digest_differs(const struct job_digest *root, const struct job_digest *d, int rank,
		       char *message, size_t size)
{
	char mine[64], theirs[64], root_source[JOB_SOURCE_SIZE + 16];

	if (d->scene_digest != root->scene_digest) {
		snprintf(root_source, sizeof(root_source), "%s", quote_text(root->source));
		snprintf(message, size,
			 "rank %d renders another job: the scene differs (file %s on rank 0, %s on "
			 "rank %d%s)",
			 rank, root_source, quote_text(d->source), rank,
			 strcmp(root->source, d->source) ? "" : ", with other contents");
		return 1;
	}
	for (size_t k = 0; k < sizeof(job_options) / sizeof(job_options[0]); k++) {
		enum job_setting first = job_options[k].first;
		if (memcmp(&d->setting[first], &root->setting[first],
			   (size_t)job_options[k].count * sizeof(long long)) == 0)
			continue;
		show_setting(d->setting, first, mine, sizeof(mine));
		show_setting(root->setting, first, theirs, sizeof(theirs));
		snprintf(message, size, "rank %d renders another job: %s against rank 0's %s", rank,
			 mine, theirs);
		return 1;
	}
	return 0;
}
