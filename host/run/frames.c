#include "run/frames.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/interrupt.h"
#include "base/progress.h"
#include "base/timing.h"
#include "base/vec3.h"
#include "base/version.h"
#include "render/repeats.h"
#include "render/render.h"
#include "report/summary.h"
#include "run/mode.h"

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
	double length = vec3_length(camera->up);
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

int frames_render_frame(const struct job *job, const struct render_settings *s,
			struct device *dev, int piece, struct render_result *result, char *err,
			size_t err_size)
{
	struct scene scene = *job->scene;

	frames_orbit(&job->scene->camera, job->first_frame + piece, job->first_frame,
		     job->last_frame, &scene.camera);
	return render(dev, &scene, s, result, err, err_size);
}

struct piece_work frames_piece_work(const struct render_settings *s,
				    const struct render_result *result)
{
	return (struct piece_work){(long long)s->width * s->height,
				   result->kernel_ms_median * result->repeat,
				   result->passes * result->repeat};
}

/* A device's last frame, staged (converted and written to its temporary
 * file) in a thread of its own while the device renders its next frame: on
 * four H100s (docs/results/h100x4, batch 95) a 2000x2000 frame took its
 * device's thread 758 ms, 142 of them kernels, and a single render's
 * encoding and writing of such an image 460-660 ms. */
struct stager {
	struct frames_state *f;
	pthread_t thread;
	int running; /* thread started and not yet joined */
	int piece;
	float *rgb; /* the frame's image, freed once staged */
	int samples; /* its samples per pixel */
	int failed;
	char err[1024];
};

/* The devices of an animation, and what the devices' threads share. */
struct frames_state {
	const struct job *job;
	struct render_settings settings; /* the job's, the progress line ours */
	struct output_plan *plan;
	struct device devs[DEVICES_MAX];
	struct device_work work[DEVICES_MAX];
	int count;
	int done; /* frames rendered, for the progress line */
	struct stager stagers[DEVICES_MAX]; /* each device's frame being staged */
	int keeps; /* an interrupt keeps the frames finished (not --no-partial) */
	int kept;  /* frames staged */
};

/* Names the frame under way on the progress line: with one device "frame k
 * of N" with the frame's own share; with several, whose frames run side by
 * side, how many are done. */
static void show_frame(struct frames_state *f, int piece, int finished)
{
	char step[48];
	int n = job_frame_count(f->job);

	if (f->count == 1 && !finished) {
		snprintf(step, sizeof(step), "frame %d of %d", piece + 1, n);
		progress_step(step, repeats_image_work(&f->settings));
	} else if (f->count > 1 && finished) {
		snprintf(step, sizeof(step), "%d of %d frames done",
			 __atomic_add_fetch(&f->done, 1, __ATOMIC_RELAXED), n);
		progress_step(step, 0);
	}
}

static void *stage_frame(void *arg)
{
	struct stager *st = arg;

	st->failed = output_plan_stage_image(st->f->plan, st->piece, st->rgb, st->samples,
					     st->err, sizeof(st->err)) != 0;
	if (!st->failed)
		__atomic_add_fetch(&st->f->kept, 1, __ATOMIC_RELAXED);
	free(st->rgb);
	st->rgb = NULL;
	return NULL;
}

/* Waits for the device's frame being staged; returns 0, or -1 with its
 * message in err when staging it failed (reported once). */
static int finish_staging(struct stager *st, char *err, size_t err_size)
{
	if (st->running) {
		pthread_join(st->thread, NULL);
		st->running = 0;
	}
	if (!st->failed)
		return 0;
	st->failed = 0;
	snprintf(err, err_size, "%s", st->err);
	return -1;
}

/* A multidev render_piece: frame first + piece, rendered whole; staged in
 * the device's stager thread once its previous frame is staged (at most one
 * frame a device waits to be staged), or here when no thread starts. */
static int render_frame_piece(void *context, int device, int piece, struct piece_work *done,
			      char *err, size_t err_size)
{
	struct frames_state *f = context;
	struct stager *st = &f->stagers[device];
	struct render_result result;

	/* Interrupted: no frame starts; one under way stops after its pass and
	 * is not written (an animation's frames hold all their samples). */
	*done = (struct piece_work){0, 0, 0};
	if (f->keeps && interrupt_stop_signal())
		return 0;
	show_frame(f, piece, 0);
	if (frames_render_frame(f->job, &f->settings, &f->devs[device], piece, &result, err,
				err_size))
		return -1;
	show_frame(f, piece, 1);
	/* A frame stopped by an interrupt is not written (an animation's
	 * frames hold all their samples). */
	if (result.samples_done < settings_samples(&f->settings)) {
		render_result_free(&result);
		return 0;
	}
	/* A frame is done: an interrupt from now on keeps the finished ones
	 * (this one staged first: frames_render waits for every stager). */
	if (f->keeps)
		interrupt_allow_stop(1);
	*done = frames_piece_work(&f->settings, &result);
	if (finish_staging(st, err, err_size)) {
		render_result_free(&result);
		return -1;
	}
	*st = (struct stager){
		.f = f, .piece = piece, .rgb = result.rgb, .samples = result.samples_done};
	result.rgb = NULL; /* the stager's now */
	render_result_free(&result);
	if (pthread_create(&st->thread, NULL, stage_frame, st) == 0) {
		st->running = 1;
		return 0;
	}
	stage_frame(st);
	return finish_staging(st, err, err_size);
}

/* A multidev end: the device's last frame staged (a failure is reported
 * after the job, frames_render). */
static void end_frames(void *context, int device)
{
	struct frames_state *f = context;
	struct stager *st = &f->stagers[device];

	if (st->running) {
		pthread_join(st->thread, NULL);
		st->running = 0;
	}
}

static int frames_render(struct mode_run *run, int checked, char *err, size_t err_size)
{
	const struct job *job = run->job;
	struct frames_state *f = calloc(1, sizeof(*f));
	int n = job_frame_count(job);

	(void)checked; /* not called with a failed check */
	if (!f) {
		snprintf(err, err_size, "out of host memory");
		return EXIT_FAILED;
	}
	run->state = f;
	f->job = job;
	f->settings = job->settings;
	f->settings.stoppable = job_stoppable(job);
	f->keeps = !job->all_or_nothing;
	f->plan = run->plan;
	if (job_open_devices(job, f->devs, &f->count, err, err_size)) {
		f->count = 0;
		return EXIT_FAILED;
	}
	struct multidev_job pieces = {.piece_count = n,
				      .split = job->split,
				      .render_piece = render_frame_piece,
				      .end = end_frames,
				      .context = f};
	/* One line for every frame: render() only adds to it. */
	f->settings.progress = 0;
	char devices[32];
	snprintf(devices, sizeof(devices), "%d devices", f->count);
	repeats_progress_begin(&f->settings, n, f->count > 1 ? devices : NULL);
	double start = timing_now();
	int failed = multidev_run(&pieces, f->devs, f->count, f->work, err, err_size);
	/* A device's last frame may fail to stage after its job: that message,
	 * unless a piece failed first. */
	for (int k = 0; k < f->count; k++) {
		char late[sizeof(f->stagers[k].err)];
		if (finish_staging(&f->stagers[k], late, sizeof(late)) && !failed) {
			snprintf(err, err_size, "%s", late);
			failed = 1;
		}
	}
	interrupt_allow_stop(0);
	progress_end();
	run->record->shares = (struct device_shares){
		.devs = f->devs,
		.work = f->work,
		.count = f->count,
		.split = job->split,
		.piece = "frame",
		.wall_ms = (timing_now() - start) * 1e3,
	};
	if (!failed && f->kept == 0 && interrupt_stop_signal()) {
		snprintf(err, err_size,
			 "interrupted before a frame was finished; no output written");
		return 128 + interrupt_stop_signal();
	}
	return failed ? EXIT_FAILED : 0;
}

void mode_summary_frames(const struct mode_run *run, FILE *out)
{
	report_print_frames(out, run->job, run->record);
	output_plan_print(run->plan, out);
}

static void frames_release(struct mode_run *run)
{
	struct frames_state *f = run->state;

	if (f)
		devices_close(f->devs, f->count);
	free(f);
	run->state = NULL;
}

const struct mode frames_mode = {
	.name = "frames",
	.render = frames_render,
	.summary = mode_summary_frames,
	.release = frames_release,
};
