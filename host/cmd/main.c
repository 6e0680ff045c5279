/* rtcl: ray-trace a scene with OpenCL and study how the work is balanced.
 *
 * main() reads the options and the scene, checks the outputs can be written,
 * renders on the device (or with the CPU reference), then writes the image,
 * the summary and the --stats document. Every failure ends here with one
 * message on stderr and no output file written; an interrupt ends the
 * process from interrupt.c's thread, leaving the previous outputs or the
 * complete new ones.
 */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/test_hooks.h"
#include "cmd/cli.h"
#include "device/device.h"
#include "device/devices.h"
#include "report/devstats.h"
#include "run/frames.h"
#include "base/embedded.h"
#include "base/files.h"
#include "base/interrupt.h"
#include "scene/mesh.h"
#include "run/mpi_render.h"
#include "output/outputs.h"
#include "base/progress.h"
#include "render/render.h"
#include "scene/scene.h"
#include "report/stats.h"
#include "schedule/tiles.h"
#include "base/timing.h"

#define DEFAULT_SCENE "paper60.json"
#define ERR_SIZE 65536 /* room for a kernel build log */

static int load_scene(const struct options *opt, struct scene *scene, char *err, size_t err_size)
{
	if (opt->scene_path)
		return scene_load_file(scene, opt->scene_path, err, err_size);
	return scene_load_string(scene, embedded_file(DEFAULT_SCENE), DEFAULT_SCENE " (built-in)",
				 err, err_size);
}

/* -v: the world-space box of the scene's finite objects; planes are
 * infinite and only counted. */
static void print_scene_bounds(const struct scene *scene)
{
	double lo[3], hi[3];
	char planes[64] = "";

	if (scene->plane_count)
		snprintf(planes, sizeof(planes), "; %d plane%s, infinite, not in the box",
			 scene->plane_count, scene->plane_count == 1 ? "" : "s");
	if (!scene_bounds(scene, lo, hi)) {
		fprintf(stderr, "rtcl: scene bounds: no sphere or triangle%s\n", planes);
		return;
	}
	fprintf(stderr,
		"rtcl: scene bounds of %d sphere%s and %d triangle%s: (%g, %g, %g) to (%g, %g, "
		"%g)%s\n",
		scene->sphere_count, scene->sphere_count == 1 ? "" : "s", scene->triangle_count,
		scene->triangle_count == 1 ? "" : "s", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2],
		planes);
}

/* Whether the progress line is shown: on a terminal, unless -q. Under
 * mpirun a rank's stderr is a pipe even when mpirun's is a terminal, which
 * the rank's stdout (a pseudo-terminal then) tells; other ranks than 0 turn
 * it off (mpi_render.c). */
static int shows_progress(const struct options *opt)
{
	return !opt->quiet && (isatty(STDERR_FILENO) || (opt->mpi && isatty(STDOUT_FILENO)));
}

/* The render settings: the options, else the scene's own values. */
static void choose_settings(struct run *run, const struct options *opt, const struct scene *scene)
{
	struct render_settings *s = &run->settings;

	memset(run, 0, sizeof(*run));
	run->opt = opt;
	run->scene = scene;
	s->kernel = render_find_kernel(opt->kernel); /* NULL: the reference */
	memcpy(s->workgroup, opt->workgroup, sizeof(s->workgroup));
	memcpy(s->groups, opt->groups, sizeof(s->groups));
	s->width = opt->size[0] ? opt->size[0] : scene->width;
	s->height = opt->size[1] ? opt->size[1] : scene->height;
	s->max_depth = opt->depth >= 0 ? opt->depth : scene->max_depth;
	s->samples = opt->spp ? opt->spp : scene->samples;
	s->repeat = opt->repeat ? opt->repeat : 1;
	s->warm_up = opt->repeat > 0;
	s->batch = opt->batch;
	s->source_dir = getenv("RTCL_CL_DIR");
	s->progress = 1; /* one image on one device: render() runs the line */
	s->verbose = opt->verbose;
	s->accel = opt->accel;
	run->counting = opt->flops_path || opt->work_map_path;
}

/* The CPU reference, timed by the host clock like a single launch. */
static int render_on_cpu(struct run *run, char *err, size_t err_size)
{
	snprintf(run->device_name, sizeof(run->device_name),
		 "CPU reference (C++, GLM, double precision, one core)");
	return render_reference(run->scene, &run->settings, &run->result, err, err_size);
}

static void record_device(struct run *run, const struct device *dev)
{
	snprintf(run->device_name, sizeof(run->device_name), "%s (%s)", dev->name,
		 dev->platform_name);
	snprintf(run->device_version, sizeof(run->device_version), "%s", dev->version);
	snprintf(run->driver, sizeof(run->driver), "%s", dev->driver);
	run->on_device = 1;
	run->compute_units = dev->compute_units;
	run->max_clock_mhz = dev->max_clock_mhz;
}

/* Opens the device -p/-d name, or those of --devices. */
static int open_devices(const struct options *opt, struct device *devs, int *count, char *err,
			size_t err_size)
{
	if (opt->devices_given)
		return devices_open(&opt->devices, opt->device_kind, devs, count, err, err_size);
	*count = 1;
	return device_open_kind(&devs[0], opt->platform, opt->device, opt->device_kind, err,
				err_size);
}

/* With --flops or --work-map, a separate counting run first; then the timed
 * run. */
static int render_on_device(struct run *run, struct device *dev, char *err, size_t err_size)
{
	const struct options *opt = run->opt;
	int failed = 0;
	double lap = timing_now();

	record_device(run, dev);
	if (opt->verbose)
		fprintf(stderr, "rtcl: platform %d, device %d: %s\n", dev->platform_index,
			dev->device_index, run->device_name);
	if (run->counting) {
		struct render_settings counting = run->settings;
		counting.count_flops = 1;
		failed = render(dev, run->scene, &counting, &run->counted, err, err_size);
		run->counting_ms = timing_lap_ms(&lap);
		if (!failed) {
			flop_summary_compute(&run->flops, run->counted.item_flops,
					     run->counted.item_count, run->counted.total_rays);
			run->flops.node_visits = run->counted.total_node_visits;
		}
	}
	if (!failed)
		failed = render(dev, run->scene, &run->settings, &run->result, err, err_size);
	if (!failed && opt->verbose)
		fprintf(stderr, "rtcl: build options: %s\n", run->result.build_options);
	return failed ? -1 : 0;
}

/* The devices of one image: each device's share, for the summary. */
struct image_devices {
	struct device devs[DEVICES_MAX];
	struct device_work work[DEVICES_MAX];
	int count;
};

/* Whether the image is cut into pieces (tiles.h): over several devices, or
 * into --piece-rows bands on one (which measures what pieces cost a device). */
static int in_pieces(const struct options *opt, int device_count)
{
	return device_count > 1 || opt->piece_rows > 0;
}

/* One image on the device(s) the options name; several share it in bands
 * (tiles.h). The devices stay open for the summary (d->count of them). */
static int render_on_devices(struct run *run, struct image_devices *d, char *err, size_t err_size)
{
	double lap = timing_now();

	if (open_devices(run->opt, d->devs, &d->count, err, err_size)) {
		d->count = 0; /* nothing left open */
		return -1;
	}
	run->device_ms = timing_lap_ms(&lap);
	if (!in_pieces(run->opt, d->count))
		return render_on_device(run, &d->devs[0], err, err_size);
	record_device(run, &d->devs[0]);
	int n = snprintf(run->device_name, sizeof(run->device_name), "%d devices:", d->count);
	for (int k = 0; k < d->count && n > 0 && (size_t)n < sizeof(run->device_name); k++)
		n += snprintf(run->device_name + n, sizeof(run->device_name) - (size_t)n, "%s %s",
			      k ? "," : "", d->devs[k].name);
	return tiles_render(run, d->devs, d->count, d->work, err, err_size);
}

/* --frames: every frame's image and the summary, or nothing. Returns the exit
 * status. */
static int render_frames(struct run *run, char *err, size_t err_size)
{
	struct device devs[DEVICES_MAX];
	int count = 0, failed;

	if (open_devices(run->opt, devs, &count, err, err_size)) {
		fprintf(stderr, "rtcl: %s\n", err);
		return EXIT_FAILED;
	}
	failed = frames_render(run, devs, count, err, err_size);
	devices_close(devs, count);
	if (failed)
		fprintf(stderr, "rtcl: %s\n", err);
	return failed ? EXIT_FAILED : 0;
}

/* --help, --version and --list-devices: answers that need no scene. Returns
 * the exit status, or -1 when the run is a render. */
static int answer_query(const struct options *opt, char *err, size_t err_size)
{
	if (opt->help) {
		cli_print_help(stdout);
		return 0;
	}
	if (opt->version) {
		printf("rtcl %s\n", RTCL_VERSION);
		return 0;
	}
	if (!opt->list_devices)
		return -1;
	if (device_list(stdout, err, err_size)) {
		fprintf(stderr, "rtcl: %s\n", err);
		return EXIT_FAILED;
	}
	return 0;
}

/* --mpi: under mpirun, rank 0 hands out the pieces (mpi_render.h). Returns
 * the exit status. */
static int render_mpi(struct run *run)
{
	if (!mpi_render_available()) {
		fprintf(stderr, "rtcl: %s\n", MPI_MISSING_MESSAGE);
		return EXIT_FAILED;
	}
	return run->opt->frames_given ? mpi_render_frames(run) : mpi_render_image(run);
}

/* Renders and writes the outputs; returns the exit status. */
static int render_and_write(struct run *run, char *err, size_t err_size)
{
	int checked;

	if (run->opt->mpi)
		return render_mpi(run); /* rank 0 checks the outputs */
	checked = outputs_check(run->opt, run->scene, err, err_size);
	if (checked) {
		fprintf(stderr, "rtcl: %s\n", err);
		return checked == OUTPUTS_CLASH ? EXIT_USAGE : EXIT_FAILED;
	}
	if (run->opt->frames_given)
		return render_frames(run, err, err_size);
	static struct image_devices d;
	int failed = run->settings.kernel ? render_on_devices(run, &d, err, err_size)
					  : render_on_cpu(run, err, err_size);
	if (!failed) {
		run->write_start = timing_now();
		failed = outputs_write(run, err, err_size);
	}
	if (failed) {
		fprintf(stderr, "rtcl: %s\n", err);
	} else {
		if (run->opt->verbose)
			stats_print_times(run);
		if (!run->opt->quiet)
			stats_print_summary(run);
		if (!run->opt->quiet && d.count > 0 && in_pieces(run->opt, d.count))
			devstats_print(stdout, d.devs, NULL, d.work, d.count,
				       run->opt->split_static || run->opt->piece_rows > 0
					       ? "band"
					       : "piece");
	}
	devices_close(d.devs, d.count);
	return failed ? EXIT_FAILED : 0;
}

int main(int argc, char **argv)
{
	static char err[ERR_SIZE];
	double start = timing_now();
	struct options opt;
	struct scene scene;
	struct run run;
	int status;

	if (cli_parse(argc, argv, &opt, err, sizeof(err))) {
		fprintf(stderr, "rtcl: %s\n", err);
		return EXIT_USAGE;
	}
	struct mesh_limits limits = mesh_get_limits();
	if (opt.mesh_time_limit != ULONG_MAX)
		limits.seconds = opt.mesh_time_limit;
	if (opt.mesh_memory_limit != ULONG_MAX)
		limits.memory_mib = opt.mesh_memory_limit;
	mesh_set_limits(&limits);
	progress_init(shows_progress(&opt));
	files_inject_rename_failure(hook_rename_fault());
	/* Before the OpenCL runtime starts threads of its own. */
	if (interrupt_setup(progress_enabled(), opt.mpi, err, sizeof(err))) {
		fprintf(stderr, "rtcl: %s\n", err);
		return EXIT_FAILED;
	}
	status = answer_query(&opt, err, sizeof(err));
	if (status >= 0)
		return status;
	if (load_scene(&opt, &scene, err, sizeof(err))) {
		fprintf(stderr, "%s\n", err);
		return EXIT_FAILED;
	}
	if (opt.verbose)
		print_scene_bounds(&scene);
	choose_settings(&run, &opt, &scene);
	run.start = start;
	status = render_and_write(&run, err, sizeof(err));
	render_result_free(&run.result);
	render_result_free(&run.counted);
	json_decref(run.multidevice);
	scene_free(&scene);
	if (status == 0)
		interrupt_settle();
	return status;
}
