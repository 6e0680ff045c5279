/* Animations (--frames A:B): one image per frame, the camera on an orbit,
 * whole frames handed out to the devices as pieces (multidev.h). */
#ifndef RTCL_FRAMES_H
#define RTCL_FRAMES_H

#include <stddef.h>

#include "files.h"
#include "multidev.h"
#include "stats.h"

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

/* Checks before any work that every frame's image can be written and that
 * --stats names none of them. Returns 0, or -1 with one message in err. */
int frames_check_outputs(const struct options *opt, char *err, size_t err_size);

/* Renders frames first..last of run on devs[count], writes every frame's
 * image (all or none) and the --stats document, and prints the summary.
 * Returns 0, or -1 with one message in err and nothing written. */
int frames_render(struct run *run, struct device *devs, int count, char *err, size_t err_size);

#endif
