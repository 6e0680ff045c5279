/* Animations (--frames A:B): one image per frame, the camera on an orbit,
 * whole frames handed out to the devices as pieces (schedule/multidev.h).
 * The mode itself is frames_mode (run/mode.h). */
#ifndef RTCL_FRAMES_H
#define RTCL_FRAMES_H

#include <stddef.h>

#include "job/job.h"
#include "schedule/multidev.h"

/* The camera of frame f of first..last: the scene's camera with its eye
 * turned about the axis through look_at along up, by 360° (f − first) /
 * (last − first + 1), right-handed (counter-clockwise seen from above when up
 * points up); look_at, up and fov stay. Frame `first` is the scene's camera,
 * and the orbit closes one step after `last`. */
void frames_orbit(const struct scene_camera *camera, int frame, int first, int last,
		  struct scene_camera *out);

/* Renders frame first + piece of job on dev. */
int frames_render_frame(const struct job *job, const struct render_settings *s,
			struct device *dev, int piece, struct render_result *result, char *err,
			size_t err_size);

/* What a frame rendered by frames_render_frame took, as a multidev piece. */
struct piece_work frames_piece_work(const struct render_settings *s,
				    const struct render_result *result);

#endif
