#include "run/frames.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/envchoice.h"
#include "base/interrupt.h"
#include "base/progress.h"
#include "base/test_hooks.h"
#include "base/timing.h"
#include "base/vec3.h"
#include "base/version.h"
#include "device/clerror.h"
#include "render/repeats.h"
#include "render/render.h"
#include "report/summary.h"
#include "run/mode.h"
#include "schedule/tiles.h"

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
	float *rgb; /* the frame's image, freed once staged (unless pinned) */
	int pinned; /* rgb is one of the device's pinned images (frame_memory) */
	int samples; /* its samples per pixel */
	/* READ_ASIDE: the frame's image in `from` on the device once `copied`
	 * (rgb NULL), read back here into the device's reads memory. */
	int device;
	cl_mem from;
	cl_event copied;
	int failed;
	char err[1024];
};

/* How a device's whole frames come back to the host (RTCL_FRAMES_READ).
 * READ_INLINE (before): read by the device's thread after the frame's
 * passes into one of two pinned images a device, pinned at its first two
 * frames. On four H100s a device of four paid 155-182 ms beyond its
 * kernels over its 4 frames, one GPU about 60 over 16, and the last frames
 * cost their kernels alone (docs/results/h100x4, batch 100): the excess is
 * in the first frames, and fits pinning that takes the process about 2 GB/s
 * whatever the devices (2 x 48 MB a device, 384 MB for four; an image
 * split's set-up, its 128 MB of sums pinned a device, took 138-140 ms a
 * device on two GPUs and 277-300 on four, batch 99). READ_ASIDE: the
 * device copies the frame's image into a buffer of its own (two a device,
 * alternating) and goes on with its next frame; its stager
 * thread reads the copy back on a queue of its own into one pinned image a
 * device (pinned there, at the device's first frame) and stages it from
 * there: half the pinned memory, and neither pinning nor reading in the
 * device's thread. READ_PAGEABLE (the default since batch 106): as
 * READ_ASIDE, read into memory of malloc (NVIDIA: 28-34 ms for 2000x2000,
 * beside the next frame's kernels), nothing pinned. Batch 106 (four H200s,
 * the default scene's 16 frames at 256 spp): one GPU 2371-2388 ms pageable,
 * 2357-2360 aside, 2382-2392 inline; four GPUs 695.5-696.9 pageable
 * (3.40-3.43x one GPU), 716.7-720.3 aside, 833.7-842.9 inline: pinning
 * even one image a device in the stager threads still cost the devices
 * 25-48 ms over their frames, reading into ordinary memory beside the next
 * frame 13-18. Every way gives the same bytes. */
enum frames_read { READ_ASIDE, READ_PAGEABLE, READ_INLINE, FRAMES_READS };

static const char *const frames_read_names[FRAMES_READS] = {"aside", "pageable", "inline"};

/* The way RTCL_FRAMES_READ names (READ_PAGEABLE when unset or empty), or
 * -1. */
static int frames_read_from_env(void)
{
	return env_choice("RTCL_FRAMES_READ", frames_read_names, FRAMES_READS, READ_PAGEABLE);
}

/* Host memory a device reads a frame back into: pinned (device.h), where
 * NVIDIA's OpenCL reads at the speed of the link. A 2000x2000 image read
 * into memory of malloc took one H100 27.6-33.8 ms (docs/results/h100x4,
 * batch 96; the sums of four, 128 MB each, 2.3-2.6 ms pinned). Two a
 * device (READ_INLINE): one frame renders into one while the other is
 * staged; one a device for READ_ASIDE (the stager's). */
struct frame_memory {
	cl_mem mem;
	void *host; /* mapped; malloc's with mem NULL */
	cl_command_queue queue; /* mapped on this queue of its own
				   (device_pinned_alloc_aside), or NULL */
};

/* A device's pinned memory for the sums of its shares of the last frames,
 * allocated in a thread of its own from the animation's start, beside the
 * device's whole frames (pin_share_sums). */
struct sums_pinning {
	struct frames_state *f;
	int device;
	pthread_t thread;
	int running; /* started and not yet joined */
	double ms;   /* the allocation's time */
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
	struct render_keeper keepers[DEVICES_MAX]; /* each device's renderer, kept
						      open from frame to frame */
	struct frame_memory pinned[DEVICES_MAX][2]; /* each device's images */
	struct frame_memory sums[DEVICES_MAX]; /* each device's sums of a shared
						  frame (share_samples) */
	struct sums_pinning pinning[DEVICES_MAX];
	int next[DEVICES_MAX]; /* the one its next frame reads back into */
	enum frames_read read; /* RTCL_FRAMES_READ */
	cl_mem copies[DEVICES_MAX][2]; /* READ_ASIDE: each device's frames'
					  images on it, alternating */
	int next_copy[DEVICES_MAX];
	struct frame_memory reads[DEVICES_MAX]; /* READ_ASIDE: the stager's image
						   and queue */
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

/* The stager's memory and queue for reading device's frames back (at its
 * first frame): pinned on a queue of its own, else (READ_PAGEABLE, or
 * where pinning fails) memory of malloc and a queue of its own. Returns the
 * memory, or NULL with err set. */
static float *read_memory(struct frames_state *f, int device, char *err, size_t err_size)
{
	struct frame_memory *m = &f->reads[device];
	struct device *dev = &f->devs[device];
	size_t bytes = image_float_bytes(f->settings.width, f->settings.height);
	cl_int status;

	if (m->host)
		return m->host;
	if (f->read == READ_ASIDE)
		m->host = device_pinned_alloc_aside(dev, bytes, &m->mem, &m->queue);
	if (!m->host) {
		m->queue = clCreateCommandQueue(dev->context, dev->id, 0, &status);
		if (status != CL_SUCCESS) {
			m->queue = NULL;
			snprintf(err, err_size, "making a queue to read frames back from %s failed: %s",
				 dev->name, cl_error_name(status));
			return NULL;
		}
		m->host = malloc(bytes);
		if (!m->host) {
			clReleaseCommandQueue(m->queue);
			m->queue = NULL;
			snprintf(err, err_size, "out of host memory for a %dx%d frame",
				 f->settings.width, f->settings.height);
			return NULL;
		}
	}
	memset(m->host, 0, bytes); /* mapped, or touched, now */
	return m->host;
}

/* READ_ASIDE: the stager's frame read back from its device's copy, once
 * the copy is done. Returns 0, or -1 with st->err set. */
static int read_aside(struct stager *st)
{
	struct frames_state *f = st->f;
	float *rgb = read_memory(f, st->device, st->err, sizeof(st->err));
	cl_int status;

	if (!rgb)
		return -1;
	status = clEnqueueReadBuffer(f->reads[st->device].queue, st->from, CL_TRUE, 0,
				     image_float_bytes(f->settings.width, f->settings.height), rgb,
				     1, &st->copied, NULL);
	if (status != CL_SUCCESS) {
		snprintf(st->err, sizeof(st->err), "reading a frame back from %s failed: %s",
			 f->devs[st->device].name, cl_error_name(status));
		return -1;
	}
	st->rgb = rgb;
	st->pinned = 1; /* the device's: not freed */
	return 0;
}

static void *stage_frame(void *arg)
{
	struct stager *st = arg;

	if (st->copied) {
		st->failed = read_aside(st) != 0;
		clReleaseEvent(st->copied);
		st->copied = NULL;
		if (st->failed)
			return NULL;
	}
	st->failed = output_plan_stage_image(st->f->plan, st->piece, st->rgb, st->samples,
					     st->err, sizeof(st->err)) != 0;
	if (!st->failed)
		__atomic_add_fetch(&st->f->kept, 1, __ATOMIC_RELAXED);
	if (!st->pinned)
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

/* Frame first + piece, whole, on the renderer kept open on device: the
 * frames differ only in their camera (frames_orbit). Without `to` its image
 * is read back into rgb when not NULL (then result->rgb == rgb), else into
 * memory of its own; with `to` it stays on the device, copied into `to`
 * (render_kept_on_device: *copied the copy's event). */
static int render_kept_frame(struct frames_state *f, int device, int piece, float *rgb,
			     cl_mem to, cl_event *copied, struct render_result *result, char *err,
			     size_t err_size)
{
	const struct job *job = f->job;
	struct scene scene = *job->scene;

	frames_orbit(&job->scene->camera, job->first_frame + piece, job->first_frame,
		     job->last_frame, &scene.camera);
	if (to)
		return render_kept_on_device(&f->keepers[device], &f->devs[device], &scene,
					     &f->settings, to, copied, result, err, err_size);
	return render_kept(&f->keepers[device], &f->devs[device], &scene, &f->settings, rgb,
			   result, err, err_size);
}

/* The device's pinned image for its next frame (allocated at its first
 * use), or NULL where none can be had (the frame's own memory then). */
static float *next_image(struct frames_state *f, int device)
{
	struct frame_memory *m = &f->pinned[device][f->next[device]];
	size_t bytes = image_float_bytes(f->settings.width, f->settings.height);

	if (!m->host) {
		m->host = device_pinned_alloc(&f->devs[device], bytes, &m->mem);
		if (m->host)
			memset(m->host, 0, bytes); /* mapped now */
	}
	return m->host;
}

/* Frees a frame's result, but not its image when that is the device's
 * pinned one (rgb). */
static void free_frame(struct render_result *result, const float *rgb)
{
	if (rgb && result->rgb == rgb)
		result->rgb = NULL;
	render_result_free(result);
}

/* READ_ASIDE: the device's buffer for its next frame's image on it (made
 * at its first use), or NULL where none can be made or the two would take
 * more than an eighth of the device's memory (the frame is read inline
 * then). */
static cl_mem next_copy(struct frames_state *f, int device)
{
	cl_mem *m = &f->copies[device][f->next_copy[device]];
	const struct device *dev = &f->devs[device];
	size_t bytes = image_float_bytes(f->settings.width, f->settings.height);
	cl_int status;

	if (bytes > dev->max_alloc_size || 2.0 * bytes > dev->global_mem_size / 8.0)
		return NULL;
	if (!*m) {
		*m = clCreateBuffer(dev->context, CL_MEM_READ_WRITE, bytes, NULL, &status);
		if (status != CL_SUCCESS)
			*m = NULL;
	}
	return *m;
}

/* A multidev render_piece: frame first + piece, rendered whole; staged in
 * the device's stager thread once its previous frame is staged (at most one
 * frame a device waits to be staged), or here when no thread starts. With
 * READ_ASIDE the frame's image is copied on the device and the stager reads
 * it back too. */
static int render_frame_piece(void *context, int device, int piece, struct piece_work *done,
			      char *err, size_t err_size)
{
	struct frames_state *f = context;
	struct stager *st = &f->stagers[device];
	struct render_result result;
	float *rgb = NULL;
	cl_mem to = NULL;
	cl_event copied = NULL;

	/* Interrupted: no frame starts; one under way stops after its pass and
	 * is not written (an animation's frames hold all their samples). */
	*done = (struct piece_work){0, 0, 0};
	if (f->keeps && interrupt_stop_signal())
		return 0;
	show_frame(f, piece, 0);
	if (f->read != READ_INLINE)
		to = next_copy(f, device);
	if (!to)
		rgb = next_image(f, device);
	if (render_kept_frame(f, device, piece, rgb, to, &copied, &result, err, err_size))
		return -1;
	show_frame(f, piece, 1);
	/* A frame stopped by an interrupt is not written (an animation's
	 * frames hold all their samples). */
	if (result.samples_done < settings_samples(&f->settings)) {
		free_frame(&result, rgb);
		return 0;
	}
	/* A frame is done: an interrupt from now on keeps the finished ones
	 * (this one staged first: frames_render waits for every stager). */
	if (f->keeps)
		interrupt_allow_stop(1);
	*done = frames_piece_work(&f->settings, &result);
	if (finish_staging(st, err, err_size)) {
		if (copied)
			clReleaseEvent(copied);
		free_frame(&result, rgb);
		return -1;
	}
	int pinned = rgb && result.rgb == rgb;
	*st = (struct stager){.f = f,
			      .piece = piece,
			      .rgb = result.rgb,
			      .pinned = pinned,
			      .samples = result.samples_done,
			      .device = device,
			      .from = to,
			      .copied = copied};
	result.rgb = NULL; /* the stager's now */
	if (pinned) /* the other for the next frame, while this one is staged */
		f->next[device] ^= 1;
	if (to) /* the other for the next frame, while the stager reads this */
		f->next_copy[device] ^= 1;
	render_result_free(&result);
	if (pthread_create(&st->thread, NULL, stage_frame, st) == 0) {
		st->running = 1;
		return 0;
	}
	stage_frame(st);
	return finish_staging(st, err, err_size);
}

/* render_frames_whole's frames: piece i is frame first + i. */
struct frames_tail {
	struct frames_state *f;
	int first;
};

static int render_tail_piece(void *context, int device, int piece, struct piece_work *done,
			     char *err, size_t err_size)
{
	struct frames_tail *tail = context;

	return render_frame_piece(tail->f, device, tail->first + piece, done, err, err_size);
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

/* ---- the last frames, shared ----------------------------------------------
 *
 * Frames are dealt one at a time to whichever device is free, so with G
 * GPUs the last n mod G frames would leave the other GPUs idle (6 frames on
 * four H100s, docs/results/h100x4 batch 97: 64-85 % device-level
 * efficiency). With GPUs alone those last frames may be rendered side by
 * side, each as one image over a group of the GPUs (tiles_render, its split
 * chosen as for one image: the same image as one device's), once the others
 * are done. That pays only for long frames: one image over several devices
 * first opens a renderer on each, allocates its pinned sums and probes it,
 * which took 260-300 ms a device for a 2000x2000 frame on four H100s (batch
 * 98, 6 frames at 256 spp: 874-896 ms against about 450 for two rounds of
 * whole frames), against 95-100 ms of kernels saved. So a frame is shared
 * only when the frames so far took each device longer, per frame, than
 * FRAMES_SHARE_SETUP_NS a pixel beyond what a group's share of it would
 * take; with no frame rendered yet (fewer frames than GPUs) none is.
 *
 * With the devices' renderers kept open (render_keeps), a shared frame is
 * instead split by samples on them (share_samples): each device of the
 * group renders a range of every pixel's samples on its open renderer and
 * reads its sums back into pinned memory, and the host adds them, as
 * tiles_render's sample split does (the same image). That costs no
 * renderer's set-up: the sums' pinned memory (allocated at a device's first
 * share), their read-back (2.3-2.6 ms for 2000x2000 on an H100, batch 96)
 * and the add (5.4-6.2 ms for four devices' there): FRAMES_SHARE_SUMS_NS a
 * pixel, with a margin for the allocation (not measured on GPUs yet). */
#define FRAMES_SHARE_SETUP_NS 70.0 /* 280 ms / 4 M pixels, batch 98 */
#define FRAMES_SHARE_SUMS_NS 10.0  /* about 2 ns a pixel read back and added */

/* One of the last frames, over devices [first, first + count). */
struct shared_frame {
	struct frames_state *f;
	int piece, first, count;
	struct device_work work[DEVICES_MAX];
	int begin[DEVICES_MAX], end[DEVICES_MAX]; /* share_samples: device k's */
	struct scene *scene; /* share_samples: the frame's */
	int stopped;	     /* share_samples: an interrupt stopped a share */
	int opened;	     /* tiles_render opened a renderer on each device */
	double start;
	pthread_t thread;
	int running;
	int failed;
	char err[1024];
};

/* The frames at the end that groups of devices may render: n mod count when
 * every device is a GPU (RTCL_TEST_AS_GPUS: PoCL's count as GPUs) and some
 * frames come before them, else 0. */
static int shared_frame_count(const struct frames_state *f, int n)
{
	int gpus = 0;

	for (int k = 0; k < f->count; k++)
		gpus += f->devs[k].is_gpu != 0 || hook_devices_as_gpus();
	return f->count >= 2 && gpus == f->count && n > f->count ? n % f->count : 0;
}

/* Whether the last `shared` frames are worth sharing, from the others: a
 * frame's mean time on a device, less its share over the smallest group,
 * against a group's set-up (FRAMES_SHARE_SETUP_NS a pixel). */
static int sharing_pays(const struct frames_state *f, int shared)
{
	double busy = 0;
	int pieces = 0, group = f->count / shared;

	for (int k = 0; k < f->count; k++) {
		busy += f->work[k].busy_ms;
		pieces += f->work[k].pieces;
	}
	if (pieces == 0 || group < 2)
		return 0;
	double frame_ms = busy / pieces;
	double ns = render_keeps(&f->settings) ? FRAMES_SHARE_SUMS_NS : FRAMES_SHARE_SETUP_NS;
	double setup_ms = ns * 1e-6 * f->settings.width * f->settings.height;
	return frame_ms * (1 - 1.0 / group) > setup_ms;
}

/* Device p->device's pinned memory for its shares' sums, on a queue of its
 * own (its renderer's queue is rendering frames meanwhile), mapped and
 * touched. Where it cannot, share_sums allocates it at the first share. */
static void *pin_share_sums(void *arg)
{
	struct sums_pinning *p = arg;
	struct frames_state *f = p->f;
	struct frame_memory *m = &f->sums[p->device];
	size_t bytes = image_sum_bytes(f->settings.width, f->settings.height);
	double lap = timing_now();

	m->host = device_pinned_alloc_aside(&f->devs[p->device], bytes, &m->mem, &m->queue);
	if (m->host)
		memset(m->host, 0, bytes); /* mapped now */
	p->ms = timing_lap_ms(&lap);
	return NULL;
}

/* With `shared` frames to share on the kept renderers, from the animation's
 * start: every device's sums for its shares pinned in a thread beside its
 * whole frames. A frame's sums of 2000x2000 pixels are 128 MB; pinned at
 * the first share, four H100s' shared frames of batch 99 took 266-306 ms a
 * device for about 70 ms of kernels (6 frames 643 ms, one GPU 972). Where
 * sharing does not pay after all, the memory goes unused. */
static void start_pinning(struct frames_state *f, int shared)
{
	if (!shared || !render_keeps(&f->settings) || settings_samples(&f->settings) < 2)
		return;
	for (int k = 0; k < f->count; k++) {
		struct sums_pinning *p = &f->pinning[k];
		*p = (struct sums_pinning){.f = f, .device = k};
		p->running = pthread_create(&p->thread, NULL, pin_share_sums, p) == 0;
	}
}

/* Waits for device k's pinning thread, if any. */
static void end_pinning(struct frames_state *f, int k)
{
	struct sums_pinning *p = &f->pinning[k];

	if (p->running) {
		pthread_join(p->thread, NULL);
		p->running = 0;
	}
}

/* Device k of sf's group: its pinned memory for a frame's sums (pinned from
 * the animation's start, or allocated at its first share), or NULL with err
 * set. */
static cl_long *share_sums(struct frames_state *f, int k, char *err, size_t err_size)
{
	struct frame_memory *m = &f->sums[k];
	size_t bytes = image_sum_bytes(f->settings.width, f->settings.height);

	end_pinning(f, k);
	if (!m->host) {
		m->host = device_pinned_alloc(&f->devs[k], bytes, &m->mem);
		if (!m->host) {
			m->host = malloc(bytes); /* not pinned, but memory */
			m->mem = NULL;
		}
		if (!m->host) {
			snprintf(err, err_size, "out of host memory for a frame's sample sums");
			return NULL;
		}
		memset(m->host, 0, bytes); /* mapped now */
	}
	return m->host;
}

/* A multidev render_piece of share_samples: device k of the group renders
 * its range of the frame's samples on its kept renderer. */
static int render_sample_share(void *context, int k, int piece, struct piece_work *done,
			       char *err, size_t err_size)
{
	struct shared_frame *sf = context;
	struct frames_state *f = sf->f;
	int device = sf->first + k;
	struct piece_result out;
	cl_long *sums = share_sums(f, device, err, err_size);

	(void)piece; /* device k's is piece k (SPLIT_STATIC) */
	if (!sums || render_kept_samples(&f->keepers[device], &f->devs[device], sf->scene,
					 &f->settings, sf->begin[k], sf->end[k], sums, &out, err,
					 err_size))
		return -1;
	int n = settings_samples(&f->settings);
	*done = (struct piece_work){(long long)((double)f->settings.width * f->settings.height *
							(sf->end[k] - sf->begin[k]) / n +
						0.5),
				    out.kernel_ms, out.launches};
	/* Stopped by an interrupt: the frame is not written. */
	if (out.samples < sf->end[k] - sf->begin[k])
		__atomic_store_n(&sf->stopped, 1, __ATOMIC_RELAXED);
	return 0;
}

/* sf's frame split by samples over its group's kept renderers, added into
 * result (its image; samples_done less than all when stopped). Returns 0,
 * or -1 with one message in sf->err. */
static int share_samples(struct shared_frame *sf, struct scene *scene,
			 struct render_result *result)
{
	struct frames_state *f = sf->f;
	const struct render_settings *s = &f->settings;
	int n = settings_samples(s), unit = tiles_sample_unit(s, f->devs + sf->first, sf->count);
	struct multidev_job job = {.piece_count = sf->count,
				   .split = SPLIT_STATIC,
				   .render_piece = render_sample_share,
				   .context = sf};
	const cl_long *parts[DEVICES_MAX];

	/* In whole passes, as tiles_split_samples deals them. */
	if ((n + unit - 1) / unit < sf->count)
		unit = 1;
	int units = (n + unit - 1) / unit;
	for (int k = 0; k < sf->count; k++) {
		int first = units * k / sf->count, last = units * (k + 1) / sf->count;
		sf->begin[k] = first * unit;
		sf->end[k] = last * unit < n ? last * unit : n;
	}
	sf->scene = scene;
	sf->stopped = 0;
	if (multidev_run(&job, f->devs + sf->first, sf->count, sf->work, sf->err,
			 sizeof(sf->err)))
		return -1;
	result->samples_done = sf->stopped ? 0 : n;
	if (result->samples_done < n)
		return 0;
	result->rgb = malloc(image_float_bytes(s->width, s->height));
	if (!result->rgb) {
		snprintf(sf->err, sizeof(sf->err), "out of host memory for a %dx%d image",
			 s->width, s->height);
		return -1;
	}
	for (int k = 0; k < sf->count; k++)
		parts[k] = f->sums[sf->first + k].host;
	tiles_mean_of_parts(s, parts, sf->count, result->rgb);
	return 0;
}

static void *render_shared_frame(void *arg)
{
	struct shared_frame *sf = arg;
	struct frames_state *f = sf->f;
	const struct job *job = f->job;
	struct scene scene = *job->scene;
	struct render_result result;
	int failed;

	memset(&result, 0, sizeof(result));
	frames_orbit(&job->scene->camera, job->first_frame + sf->piece, job->first_frame,
		     job->last_frame, &scene.camera);
	if (sf->count == 1) {
		double lap = timing_now();
		failed = render_kept_frame(f, sf->first, sf->piece, NULL, NULL, NULL, &result,
					   sf->err, sizeof(sf->err));
		struct piece_work done = failed ? (struct piece_work){0}
						: frames_piece_work(&f->settings, &result);
		sf->work[0] = (struct device_work){.pixels = (long long)done.pixels,
						   .busy_ms = timing_lap_ms(&lap),
						   .kernel_ms = done.kernel_ms,
						   .launches = (int)done.launches};
	} else if (render_keeps(&f->settings) && settings_samples(&f->settings) >= sf->count) {
		failed = share_samples(sf, &scene, &result);
	} else {
		struct tiles_request r = {.scene = &scene,
					  .devs = f->devs + sf->first,
					  .count = sf->count,
					  .split = SPLIT_DYNAMIC};
		sf->opened = 1;
		failed = tiles_choose_split(&r, &f->settings, 0, &r.split, &r.measure, sf->err,
					    sizeof(sf->err)) ||
			 tiles_render(&r, &f->settings, sf->work, &result, sf->err, sizeof(sf->err));
	}
	/* A frame an interrupt stopped is not written (an animation's frames
	 * hold all their samples). */
	if (!failed && result.samples_done >= settings_samples(&f->settings)) {
		show_frame(f, sf->piece, 1);
		failed = output_plan_stage_image(f->plan, sf->piece, result.rgb,
						 result.samples_done, sf->err, sizeof(sf->err)) != 0;
		if (!failed)
			__atomic_add_fetch(&f->kept, 1, __ATOMIC_RELAXED);
	}
	render_result_free(&result);
	sf->failed = failed;
	return NULL;
}

/* Renders the last `shared` of n frames side by side, each over a group of
 * the devices, once the others are done; adds what each device did to its
 * work (each frame a piece of every device of its group). Returns 0, or -1
 * with the first failure's message in err. */
static int render_shared_frames(struct frames_state *f, int n, int shared, double start,
				char *err, size_t err_size)
{
	struct shared_frame frames[DEVICES_MAX];
	int failed = 0;

	for (int i = 0; i < shared; i++) {
		int first = f->count * i / shared, end = f->count * (i + 1) / shared;
		frames[i] = (struct shared_frame){.f = f, .piece = n - shared + i, .first = first,
						  .count = end - first};
		frames[i].running =
			pthread_create(&frames[i].thread, NULL, render_shared_frame, &frames[i]) == 0;
		if (!frames[i].running)
			render_shared_frame(&frames[i]);
	}
	for (int i = 0; i < shared; i++) {
		struct shared_frame *sf = &frames[i];
		if (sf->running)
			pthread_join(sf->thread, NULL);
		if (sf->failed && !failed) {
			snprintf(err, err_size, "frame %d over %d device%s: %s",
				 f->job->first_frame + sf->piece, sf->count, sf->count == 1 ? "" : "s",
				 sf->err);
			failed = 1;
		}
		double done_ms = (timing_now() - start) * 1e3;
		for (int k = 0; k < sf->count; k++) {
			struct device_work *to = &f->work[sf->first + k], *w = &sf->work[k];
			if (to->pieces++ == 0)
				to->first_piece_ms = w->busy_ms;
			to->pixels += w->pixels;
			to->busy_ms += w->busy_ms;
			to->kernel_ms += w->kernel_ms;
			to->launches += w->launches;
			to->setup_ms += w->setup_ms;
			to->last_piece_ms = w->busy_ms;
			to->finish_ms = done_ms;
			to->renderers_opened += sf->opened;
		}
	}
	return failed ? -1 : 0;
}

/* The last `shared` frames after all, each whole on a device, dealt as the
 * others were (each device's last frame staged meanwhile). */
static int render_frames_whole(struct frames_state *f, int n, int shared, char *err,
			       size_t err_size)
{
	struct frames_tail tail = {.f = f, .first = n - shared};
	struct device_work work[DEVICES_MAX];
	struct multidev_job pieces = {.piece_count = shared,
				      .split = f->job->split,
				      .render_piece = render_tail_piece,
				      .context = &tail};
	int failed = multidev_run(&pieces, f->devs, f->count, work, err, err_size);

	for (int k = 0; k < f->count; k++) {
		if (f->work[k].pieces == 0)
			f->work[k].first_piece_ms = work[k].first_piece_ms;
		f->work[k].pieces += work[k].pieces;
		f->work[k].pixels += work[k].pixels;
		f->work[k].busy_ms += work[k].busy_ms;
		f->work[k].kernel_ms += work[k].kernel_ms;
		f->work[k].launches += work[k].launches;
		if (work[k].pieces)
			f->work[k].last_piece_ms = work[k].last_piece_ms;
	}
	return failed;
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
	int read = frames_read_from_env();
	if (read < 0) {
		snprintf(err, err_size,
			 "RTCL_FRAMES_READ=%s: expected aside, pageable or inline (how --frames "
			 "reads each frame back), or leave it unset",
			 getenv("RTCL_FRAMES_READ"));
		return EXIT_USAGE;
	}
	/* An instrumented frame opens its renderer (render_kept): read inline. */
	f->read = render_keeps(&f->settings) ? (enum frames_read)read : READ_INLINE;
	if (job_open_devices(job, f->devs, &f->count, err, err_size)) {
		f->count = 0;
		return EXIT_FAILED;
	}
	int shared = shared_frame_count(f, n);
	start_pinning(f, shared);
	/* The last frames shared, after the others: each device's last frame
	 * of those staged meanwhile (joined below). */
	struct multidev_job pieces = {.piece_count = n - shared,
				      .split = job->split,
				      .render_piece = render_frame_piece,
				      .end = shared ? NULL : end_frames,
				      .context = f};
	/* One line for every frame: render() only adds to it. */
	f->settings.progress = 0;
	char devices[32];
	snprintf(devices, sizeof(devices), "%d devices", f->count);
	repeats_progress_begin(&f->settings, n, f->count > 1 ? devices : NULL);
	double start = timing_now();
	int failed = n - shared > 0
			     ? multidev_run(&pieces, f->devs, f->count, f->work, err, err_size)
			     : 0;
	if (!failed && shared)
		failed = sharing_pays(f, shared)
				 ? render_shared_frames(f, n, shared, start, err, err_size)
				 : render_frames_whole(f, n, shared, err, err_size);
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
	for (int k = 0; k < f->count; k++) {
		f->work[k].renderers_opened += f->keepers[k].opened;
		f->work[k].open_ms += f->keepers[k].open_ms;
		/* The shares' sums pinned beside the frames: the device's
		 * set-up (--stats setup_ms), not its frames' busy time. */
		end_pinning(f, k);
		f->work[k].setup_ms += f->pinning[k].ms;
	}
	run->record->shares = (struct device_shares){
		.devs = f->devs,
		.work = f->work,
		.count = f->count,
		.split = job->split,
		.piece = "frame",
		.frames_read = frames_read_names[f->read],
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

	for (int k = 0; f && k < f->count; k++) { /* before its device */
		end_pinning(f, k); /* the frames were dealt whole, or failed */
		render_keeper_close(&f->keepers[k]);
		for (int i = 0; i < 2; i++) {
			device_pinned_free(&f->devs[k], f->pinned[k][i].mem, f->pinned[k][i].host);
			if (f->copies[k][i])
				clReleaseMemObject(f->copies[k][i]);
		}
		struct frame_memory *r = &f->reads[k];
		if (r->mem) {
			device_pinned_free_aside(&f->devs[k], r->queue, r->mem, r->host);
		} else {
			free(r->host);
			if (r->queue)
				clReleaseCommandQueue(r->queue);
		}
		if (f->sums[k].mem)
			device_pinned_free_aside(&f->devs[k], f->sums[k].queue, f->sums[k].mem,
						 f->sums[k].host);
		else
			free(f->sums[k].host);
	}
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
