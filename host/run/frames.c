#include "run/frames.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/test_hooks.h"
#include "report/devstats.h"
#include "output/image.h"
#include "base/interrupt.h"
#include "render/launch.h"
#include "render/program.h"
#include "base/progress.h"
#include "base/quote.h"
#include "render/render.h"
#include "base/timing.h"
#include "base/vec3.h"

#define PI 3.14159265358979323846

/* Rodrigues' rotation of v about the unit axis k by angle a. */
static void rotate(const double v[3], const double k[3], double a, double out[3])
{
	double c = cos(a), s = sin(a);
	double dot = vec3_dot(k, v);
	double cross[3];

	vec3_cross(k, v, cross);
	for (int i = 0; i < 3; i++)
		out[i] = v[i] * c + cross[i] * s + k[i] * dot * (1 - c);
}

void frames_orbit(const struct scene_camera *camera, int frame, int first, int last,
		  struct scene_camera *out)
{
	double angle = 2 * PI * (frame - first) / (last - first + 1);
	double length = sqrt(camera->up[0] * camera->up[0] + camera->up[1] * camera->up[1] +
			     camera->up[2] * camera->up[2]);
	double axis[3], offset[3], turned[3];

	*out = *camera;
	if (frame == first)
		return; /* exactly the scene's camera */
	for (int i = 0; i < 3; i++) {
		axis[i] = camera->up[i] / length;
		offset[i] = camera->eye[i] - camera->look_at[i];
	}
	rotate(offset, axis, angle, turned);
	for (int i = 0; i < 3; i++)
		out->eye[i] = camera->look_at[i] + turned[i];
}

int frames_output_name(const char *path, int frame, char *name)
{
	const char *ext = files_extension(path);
	int stem = (int)(ext - path);
	int n = snprintf(name, PATH_MAX, "%.*s_%04d%s", stem, path, frame, ext);

	return n < 0 || n >= PATH_MAX ? -1 : 0;
}

static int frame_count(const struct options *opt)
{
	return opt->frames[1] - opt->frames[0] + 1;
}

int frames_check_outputs(const struct options *opt, char *err, size_t err_size)
{
	char name[PATH_MAX];

	for (int f = opt->frames[0]; f <= opt->frames[1]; f++) {
		if (frames_output_name(opt->output, f, name)) {
			snprintf(err, err_size, "-o/--output: %s: the frame names are too long",
				 quote_text(opt->output));
			return -1;
		}
		if (image_check_writable(name, err, err_size))
			return -1;
	}
	if (opt->stats_path && files_check_writable(opt->stats_path, err, err_size))
		return -1;
	return 0;
}

int frames_output_open(struct frames_output *o, const struct options *opt, char *err,
		       size_t err_size)
{
	int n = frame_count(opt);

	o->names = calloc((size_t)n, PATH_MAX);
	o->staged = calloc((size_t)n + FRAMES_EXTRA_FILES, sizeof(struct staged_file));
	o->held = calloc((size_t)n, sizeof(float *));
	o->count = n;
	if (!o->names || !o->staged || !o->held) {
		frames_output_close(o);
		snprintf(err, err_size, "out of host memory for %d frames", n);
		return -1;
	}
	for (int i = 0; i < n; i++)
		frames_output_name(opt->output, opt->frames[0] + i, o->names[i]);
	return 0;
}

void frames_output_close(struct frames_output *o)
{
	for (int i = 0; o->staged && i < o->count + FRAMES_EXTRA_FILES; i++)
		files_discard(&o->staged[i]);
	for (int i = 0; o->held && i < o->count; i++)
		free(o->held[i]);
	free(o->names);
	free(o->staged);
	free(o->held);
	o->names = NULL;
	o->staged = NULL;
	o->held = NULL;
}

int frames_render_frame(const struct run *run, struct device *dev, int piece,
			struct render_result *result, char *err, size_t err_size)
{
	const struct options *opt = run->opt;
	struct scene scene = *run->scene;

	frames_orbit(&run->scene->camera, opt->frames[0] + piece, opt->frames[0], opt->frames[1],
		     &scene.camera);
	return render(dev, &scene, &run->settings, result, err, err_size);
}

struct piece_work frames_piece_work(const struct render_settings *s,
				    const struct render_result *result)
{
	return (struct piece_work){(long long)s->width * s->height,
				   result->kernel_ms_median * result->repeat,
				   result->passes * result->repeat};
}

int frames_stage_image(const struct run *run, struct frames_output *o, int piece, const float *rgb,
		       char *err, size_t err_size)
{
	const struct render_settings *s = &run->settings;
	const struct options *opt = run->opt;
	char description[1024];
	struct image_meta meta = {"rtcl " RTCL_VERSION, description,
				  opt->linear_encoding ? IMAGE_LINEAR : IMAGE_SRGB};

	snprintf(description, sizeof(description),
		 "scene %s, kernel %s, %dx%d, max depth %d, frame %d of %d..%d", run->scene->source,
		 opt->kernel, s->width, s->height, s->max_depth, opt->frames[0] + piece,
		 opt->frames[0], opt->frames[1]);
	return image_stage(&o->staged[piece], o->names[piece], rgb, s->width, s->height, &meta, err,
			   err_size);
}

/* The --stats document of an animation. */
static json_t *frames_document(const struct run *run, const struct frames_report *r)
{
	const struct render_settings *s = &run->settings;

	return json_pack("{s:s, s:s, s:i, s:i, s:i, s:s, s:[i,i], s:s, s:f, s:o}", "rtcl_version",
			 RTCL_VERSION, "kernel", s->kernel->name, "width", s->width, "height",
			 s->height, "max_depth", s->max_depth, "scene", run->scene->source,
			 "frames", run->opt->frames[0], run->opt->frames[1], "camera_path", "orbit",
			 "wall_ms", r->wall_ms, "multidevice",
			 devstats_json(r->devs, r->ranks, r->work, r->count, run->opt->split_static,
				       "frame"));
}

static void print_summary(const struct run *run, const struct frames_report *r)
{
	const struct render_settings *s = &run->settings;
	const struct options *opt = run->opt;
	int n = frame_count(opt);
	char first[PATH_MAX], last[PATH_MAX];

	printf("frames:  %d..%d (%d), camera orbit, %dx%d, max depth %d, scene %s, kernel %s\n",
	       opt->frames[0], opt->frames[1], n, s->width, s->height, s->max_depth,
	       quote_text(run->scene->source), s->kernel->name);
	devstats_print(stdout, r->devs, r->ranks, r->work, r->count, "frame");
	printf("time:    %.1f ms for %d frame%s (%.1f ms each), %s split\n", r->wall_ms, n,
	       n == 1 ? "" : "s", r->wall_ms / n, opt->split_static ? "static" : "dynamic");
	frames_output_name(opt->output, opt->frames[0], first);
	frames_output_name(opt->output, opt->frames[1], last);
	printf("output:  %s%s%s\n", quote_text(first), n > 1 ? " .. " : "",
	       n > 1 ? quote_text(last) : "");
}

int frames_commit(const struct run *run, struct frames_output *o, const struct frames_report *r,
		  char *err, size_t err_size)
{
	const struct options *opt = run->opt;
	int n = frame_count(opt);

	if (opt->stats_path) {
		if (stats_stage_document(&o->staged[n], opt->stats_path, frames_document(run, r),
					 err, err_size))
			return -1;
		n++;
	}
	int dumped = program_stage_dump(&o->staged[n], err, err_size);
	if (dumped < 0)
		return -1;
	n += dumped;
	interrupt_hold();
	int ret = files_commit(o->staged, n, err, err_size);
	if (ret == 0) {
		interrupt_set_outcome("the outputs were written");
		hook_commit_delay();
	}
	interrupt_release();
	if (ret == 0 && !opt->quiet)
		print_summary(run, r);
	return ret;
}

int frames_check_memory(const struct options *opt, const struct render_settings *s, char *err,
			size_t err_size)
{
	const double gib = 1024.0 * 1024 * 1024;
	double need = (double)frame_count(opt) * (double)image_float_bytes(s->width, s->height);
	long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGESIZE);
	double limit = pages > 0 && page_size > 0 ? (double)pages * (double)page_size / 2 : 0;

	if (limit <= 0 || need <= limit)
		return 0; /* an unknown host size: malloc says when it is too much */
	snprintf(err, err_size,
		 "--frames: under --mpi, rank 0 keeps every frame in host memory until all "
		 "have arrived: %d frames of %dx%d need %.1f GiB (%zu bytes a pixel), more than "
		 "the limit of %.1f GiB (half of this host's memory): render fewer frames per run "
		 "or a smaller --size",
		 frame_count(opt), s->width, s->height, need / gib, image_float_bytes(1, 1),
		 limit / gib);
	return -1;
}

int frames_hold(struct frames_output *o, int piece, float *rgb, char *err, size_t err_size)
{
	if (o->held[piece]) {
		free(rgb);
		snprintf(err, err_size, "frame %s arrived twice", quote_text(o->names[piece]));
		return -1;
	}
	o->held[piece] = rgb;
	return 0;
}

int frames_check_held(const struct frames_output *o, char *err, size_t err_size)
{
	for (int i = 0; i < o->count; i++) {
		if (!o->held[i]) {
			snprintf(err, err_size, "frame %s never arrived", quote_text(o->names[i]));
			return -1;
		}
	}
	return 0;
}

int frames_write_held(const struct run *run, struct frames_output *o, const struct frames_report *r,
		      char *err, size_t err_size)
{
	int n = frame_count(run->opt);

	if (frames_check_held(o, err, err_size))
		return -1;
	/* Each frame is freed once staged: the encoders' memory comes on top. */
	for (int i = 0; i < n; i++) {
		if (frames_stage_image(run, o, i, o->held[i], err, err_size))
			return -1;
		free(o->held[i]);
		o->held[i] = NULL;
	}
	return frames_commit(run, o, r, err, err_size);
}

/* What the devices' threads share. */
struct frames_context {
	const struct run *run;
	struct device *devs;
	int count;
	struct frames_output *output;
	int done; /* frames rendered, for the progress line */
};

/* Names the frame under way on the progress line: with one device "frame k
 * of N" with the frame's own share; with several, whose frames run side by
 * side, how many are done. */
static void show_frame(struct frames_context *c, int piece, int finished)
{
	char step[48];
	int n = frame_count(c->run->opt);

	if (c->count == 1 && !finished) {
		snprintf(step, sizeof(step), "frame %d of %d", piece + 1, n);
		progress_step(step, launch_image_work(&c->run->settings));
	} else if (c->count > 1 && finished) {
		snprintf(step, sizeof(step), "%d of %d frames done",
			 __atomic_add_fetch(&c->done, 1, __ATOMIC_RELAXED), n);
		progress_step(step, 0);
	}
}

/* A multidev render_frame_piece: frame first + piece, rendered whole and staged. */
static int render_frame_piece(void *context, int device, int piece, struct piece_work *done,
			      char *err, size_t err_size)
{
	struct frames_context *c = context;
	const struct render_settings *s = &c->run->settings;
	struct render_result result;

	show_frame(c, piece, 0);
	if (frames_render_frame(c->run, &c->devs[device], piece, &result, err, err_size))
		return -1;
	show_frame(c, piece, 1);
	int failed = frames_stage_image(c->run, c->output, piece, result.rgb, err, err_size);
	*done = frames_piece_work(s, &result);
	render_result_free(&result);
	return failed ? -1 : 0;
}

int frames_render(struct run *run, struct device *devs, int count, char *err, size_t err_size)
{
	int n = frame_count(run->opt);
	struct device_work work[DEVICES_MAX];
	struct frames_output output;
	struct frames_context c = {run, devs, count, &output, 0};
	struct multidev_job job = {.piece_count = n,
				   .split = run->opt->split_static ? SPLIT_STATIC : SPLIT_DYNAMIC,
				   .render_piece = render_frame_piece,
				   .context = &c};

	if (frames_output_open(&output, run->opt, err, err_size))
		return -1;
	/* One line for every frame: render() only adds to it. */
	run->settings.progress = 0;
	char devices[32];
	snprintf(devices, sizeof(devices), "%d devices", count);
	launch_progress_begin(&run->settings, n, count > 1 ? devices : NULL);
	double start = timing_now();
	int failed = multidev_run(&job, devs, count, work, err, err_size);
	progress_end();
	if (failed) {
		frames_output_close(&output);
		return -1;
	}
	struct frames_report report = {devs, NULL, work, count, (timing_now() - start) * 1e3};
	failed = frames_commit(run, &output, &report, err, err_size);
	frames_output_close(&output);
	return failed ? -1 : 0;
}
