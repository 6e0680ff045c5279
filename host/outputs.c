#include "outputs.h"

#include <stdio.h>

#include "files.h"
#include "image.h"
#include "workmap.h"

/* Room for a path and the ".json" of the --flops sidecar. */
#define SIDECAR_PATH_SIZE 4200

static void sidecar_path(const char *flops_path, char *path)
{
	snprintf(path, SIDECAR_PATH_SIZE, "%s.json", flops_path);
}

int outputs_check(const struct options *opt, char *err, size_t err_size)
{
	char sidecar[SIDECAR_PATH_SIZE];

	if (image_check_writable(opt->output, err, err_size))
		return -1;
	if (opt->work_map_path && image_check_writable(opt->work_map_path, err, err_size))
		return -1;
	if (opt->stats_path && files_check_writable(opt->stats_path, err, err_size))
		return -1;
	if (opt->flops_path) {
		sidecar_path(opt->flops_path, sidecar);
		if (files_check_writable(opt->flops_path, err, err_size) ||
		    files_check_writable(sidecar, err, err_size))
			return -1;
	}
	return 0;
}

int outputs_write(const struct run *run, char *err, size_t err_size)
{
	const struct options *opt = run->opt;
	const struct render_settings *s = &run->settings;
	char description[1024], sidecar[SIDECAR_PATH_SIZE];
	struct image_meta meta = {"rtcl " RTCL_VERSION, description};
	const char *written[4];
	int count = 0;

	snprintf(description, sizeof(description), "scene %s, kernel %s, %dx%d, max depth %d",
		 run->scene->source, opt->kernel, s->width, s->height, s->max_depth);
	if (image_write(opt->output, run->result.rgb, s->width, s->height, &meta, err, err_size))
		return -1;
	written[count++] = opt->output;
	if (opt->work_map_path) {
		if (workmap_write(opt->work_map_path, run->counted.pixel_flops, s->width, s->height,
				  err, err_size))
			goto out_remove;
		written[count++] = opt->work_map_path;
	}
	if (opt->flops_path) {
		if (stats_write_flops(opt->flops_path, run, err, err_size))
			goto out_remove;
		written[count++] = opt->flops_path;
		sidecar_path(opt->flops_path, sidecar);
		if (stats_write_flops_sidecar(sidecar, run, err, err_size))
			goto out_remove;
		written[count++] = sidecar;
	}
	if (opt->stats_path && stats_write_run(opt->stats_path, run, err, err_size))
		goto out_remove;
	return 0;

out_remove:
	while (count > 0)
		files_remove(written[--count]);
	return -1;
}

void outputs_remove(const struct options *opt)
{
	char sidecar[SIDECAR_PATH_SIZE];

	files_remove(opt->output);
	if (opt->work_map_path)
		files_remove(opt->work_map_path);
	if (opt->stats_path)
		files_remove(opt->stats_path);
	if (opt->flops_path) {
		sidecar_path(opt->flops_path, sidecar);
		files_remove(opt->flops_path);
		files_remove(sidecar);
	}
}
