/* Animations (--frames A:B): one image per frame, the camera on an orbit,
 * whole frames handed out to the devices as pieces (multidev.h). */
#ifndef RTCL_FRAMES_H
#define RTCL_FRAMES_H

#include <stddef.h>

#include "base/files.h"
#include "schedule/multidev.h"
#include "report/stats.h"

/* The most frames one run writes (each stays staged until all are done). */
#define FRAMES_MAX 1000

/* The camera of frame f of first..last: the scene's camera with its eye
 * turned about the axis through look_at along up, by 360° (f − first) /
 * (last − first + 1), right-handed (counter-clockwise seen from above when up
 * points up); look_at, up and fov stay. Frame `first` is the scene's camera,
 * and the orbit closes one step after `last`. */
void frames_orbit(const struct scene_camera *camera, int frame, int first, int last,
		  struct scene_camera *out);

/* The image name of frame f: "_NNNN" (the frame number, at least four
 * digits) before path's extension: out.png -> out_0007.png, out -> out_0007.
 * Returns 0, or -1 when it does not fit in name[PATH_MAX]. */
int frames_output_name(const char *path, int frame, char *name);

/* Checks before any work that every frame's image and the --stats document
 * can be written (outputs_check checks first that no two outputs, and no
 * output and input, name one file). Returns 0, or -1 with one message in
 * err. */
int frames_check_outputs(const struct options *opt, char *err, size_t err_size);

/* The frames' image names, their staged files (one per frame, then the
 * --stats document and RTCL_DUMP_BINARY's program), and under --mpi the
 * frames held in memory. */
#define FRAMES_EXTRA_FILES 2
struct frames_output {
	char (*names)[PATH_MAX];
	struct staged_file *staged;
	float **held; /* frame first + i's pixels, or NULL before it arrived */
	int count;    /* frames */
};

int frames_output_open(struct frames_output *o, const struct options *opt, char *err,
		       size_t err_size);

/* Discards the staged files still held, frees the held frames, and frees. */
void frames_output_close(struct frames_output *o);

/* What a frame rendered by frames_render_frame took, as a multidev piece. */
struct piece_work frames_piece_work(const struct render_settings *s,
				    const struct render_result *result);

/* Renders frame first + piece on dev (settings as for one image). */
int frames_render_frame(const struct run *run, struct device *dev, int piece,
			struct render_result *result, char *err, size_t err_size);

/* Stages frame first + piece's image for frames_commit. */
int frames_stage_image(const struct run *run, struct frames_output *o, int piece, const float *rgb,
		       char *err, size_t err_size);

/* Who did what, for the summary and --stats. */
struct frames_report {
	const struct device *devs;
	const int *ranks; /* each device's MPI rank, or NULL */
	const struct device_work *work;
	int count;
	double wall_ms;
};

/* Stages the --stats document, commits every staged file together and prints
 * the summary. Returns 0, or -1 with one message in err. */
int frames_commit(const struct run *run, struct frames_output *o, const struct frames_report *r,
		  char *err, size_t err_size);

/* Under --mpi, rank 0 keeps every frame in host memory and creates nothing
 * in the output folder until all have arrived, because a rank that dies makes
 * mpirun kill the others (SIGTERM, then SIGKILL) and a killed rank 0 cannot
 * remove what it has staged (mpi_render.c). Checks up front that the frames
 * fit: at most half of this host's memory. Returns 0, or -1 with one message
 * in err giving the numbers. */
int frames_check_memory(const struct options *opt, const struct render_settings *s, char *err,
			size_t err_size);

/* Keeps frame first + piece's pixels (malloc'd; o takes them, also on a
 * failure). Returns 0, or -1 with one message in err when the frame had
 * arrived already. Not thread-safe: the caller serialises. */
int frames_hold(struct frames_output *o, int piece, float *rgb, char *err, size_t err_size);

/* Every frame arrived. Returns 0, or -1 with one message in err naming the
 * first missing. */
int frames_check_held(const struct frames_output *o, char *err, size_t err_size);

/* Stages every held frame's image, then frames_commit: the one short step
 * in which an output file exists before the end. Returns 0, or -1 with one
 * message in err (a frame missing, or a write) and nothing written. */
int frames_write_held(const struct run *run, struct frames_output *o, const struct frames_report *r,
		      char *err, size_t err_size);

/* Renders frames first..last of run on devs[count], writes every frame's
 * image (all or none) and the --stats document, and prints the summary.
 * Returns 0, or -1 with one message in err and nothing written. */
int frames_render(struct run *run, struct device *devs, int count, char *err, size_t err_size);

#endif
