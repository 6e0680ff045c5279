/* rtcl: ray-trace a scene with OpenCL and study how the work is balanced.
 *
 * main() reads the options and the scene, checks the outputs can be written,
 * renders on the device (or with the CPU reference), then writes the image,
 * the summary and the --stats document. Every failure ends here with one
 * message on stderr and no output file written.
 */
#include <jansson.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "device.h"
#include "embedded.h"
#include "image.h"
#include "reference.h"
#include "render.h"
#include "scene.h"
#include "outfile.h"
#include "stats.h"
#include "workmap.h"

#define DEFAULT_SCENE "paper60.json"
#define ERR_SIZE 65536 /* room for a kernel build log */

/* What one run produced, for the summary and --stats. */
struct run {
	const struct options *opt;
	const struct scene *scene;
	struct render_settings settings;
	struct render_result result;  /* the timed, uncounted run */
	struct render_result counted; /* the counting run, with --flops/--work-map */
	int counting;
	struct flop_summary flops;
	char device_name[640];
	char device_version[256];
	char driver[256];
	int on_device;		/* an OpenCL device (not the CPU reference) */
	unsigned compute_units; /* CL_DEVICE_MAX_COMPUTE_UNITS */
	unsigned max_clock_mhz; /* CL_DEVICE_MAX_CLOCK_FREQUENCY */
};

/* Ctrl-C (or SIGTERM) before the outputs are written: nothing has been written
 * yet and nothing needs undoing, so leave at once with the conventional
 * status. While they are written the signals are held back (see main). */
static volatile sig_atomic_t progress_on_terminal; /* a progress line may be open */

static void on_interrupt(int signal_number)
{
	static const char message[] = "\nrtcl: interrupted; no output written\n";
	int skip_newline = !progress_on_terminal;
	ssize_t ignored =
		write(STDERR_FILENO, message + skip_newline, sizeof(message) - 1 - skip_newline);

	(void)ignored;
	_exit(128 + signal_number);
}

static void catch_interrupts(void)
{
	struct sigaction action;

	memset(&action, 0, sizeof(action));
	action.sa_handler = on_interrupt;
	sigemptyset(&action.sa_mask);
	sigaction(SIGINT, &action, NULL);
	sigaction(SIGTERM, &action, NULL);
}

/* Blocks (block = 1) or unblocks SIGINT and SIGTERM. */
static void hold_interrupts(int block, sigset_t *pending)
{
	sigset_t set;

	sigemptyset(&set);
	sigaddset(&set, SIGINT);
	sigaddset(&set, SIGTERM);
	sigprocmask(block ? SIG_BLOCK : SIG_UNBLOCK, &set, NULL);
	if (pending)
		sigpending(pending);
}

static int load_scene(const struct options *opt, struct scene *scene, char *err, size_t err_size)
{
	if (opt->scene_path)
		return scene_load_file(scene, opt->scene_path, err, err_size);
	return scene_load_string(scene, embedded_file(DEFAULT_SCENE), DEFAULT_SCENE " (built-in)",
				 err, err_size);
}

static double seconds_now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* The CPU reference, timed by the host clock like a single launch. */
static int render_reference(struct run *run, char *err, size_t err_size)
{
	const struct render_settings *s = &run->settings;
	struct render_result *res = &run->result;
	size_t values = (size_t)s->width * s->height * 3;

	memset(res, 0, sizeof(*res));
	res->rgb = malloc(values * sizeof(float));
	res->kernel_ms = calloc((size_t)s->repeat, sizeof(double));
	if (!res->rgb || !res->kernel_ms) {
		render_result_free(res);
		snprintf(err, err_size, "out of host memory for a %dx%d image", s->width,
			 s->height);
		return -1;
	}
	for (int i = 0; i < s->repeat; i++) {
		double start = seconds_now();
		if (reference_render(run->scene, s->width, s->height, s->max_depth, res->rgb)) {
			render_result_free(res);
			snprintf(err, err_size,
				 "the CPU reference renderer failed (out of memory)");
			return -1;
		}
		res->kernel_ms[i] = (seconds_now() - start) * 1e3;
	}
	res->repeat = s->repeat;
	if (render_summarize_times(res, err, err_size)) {
		render_result_free(res);
		return -1;
	}
	res->groups[0] = res->groups[1] = 1;
	snprintf(run->device_name, sizeof(run->device_name),
		 "CPU reference (C++, GLM, double precision, one core)");
	return 0;
}

static void print_summary(const struct run *run)
{
	const struct render_settings *s = &run->settings;
	const struct render_result *r = &run->result;

	printf("device:  %s\n", run->device_name);
	if (!s->kernel)
		printf("kernel:  reference\n");
	else if (s->kernel->single_item)
		printf("kernel:  %s (one work-item)\n", s->kernel->name);
	else
		printf("kernel:  %s, work-group %dx%d, %dx%d groups (global %zux%zu)\n",
		       s->kernel->name, s->workgroup[0], s->workgroup[1], r->groups[0],
		       r->groups[1], r->global_size[0], r->global_size[1]);
	printf("image:   %dx%d, max depth %d, scene %s\n", s->width, s->height, s->max_depth,
	       run->scene->source);
	if (r->repeat > 1)
		printf("time:    %.3f ms median of %d launches (min %.3f, max %.3f)\n",
		       r->kernel_ms_median, r->repeat, r->kernel_ms_min, r->kernel_ms_max);
	else
		printf("time:    %.3f ms\n", r->kernel_ms_median);
	if (run->counting) {
		const struct flop_summary *f = &run->flops;
		printf("work:    %.3f GFLOP, %.1f GFLOP/s; per work-item mean %.0f, max %.0f, min "
		       "%.0f flops: parallel efficiency %.1f%%\n",
		       f->total * 1e-9, f->total * 1e-6 / r->kernel_ms_median, f->mean, f->max,
		       f->min, 100 * f->parallel_efficiency);
		printf("rays:    %llu (primary, secondary and shadow), %.1f Mrays/s\n",
		       (unsigned long long)f->rays, f->rays * 1e-3 / r->kernel_ms_median);
	}
	printf("output:  %s", run->opt->output);
	if (run->opt->work_map_path)
		printf(", work map %s", run->opt->work_map_path);
	if (run->opt->flops_path)
		printf(", flops %s", run->opt->flops_path);
	printf("\n");
}

/* The figures of the counting run, for --stats and the --flops sidecar. */
static void add_flop_figures(json_t *doc, const struct run *run)
{
	const struct flop_summary *f = &run->flops;
	double ms = run->result.kernel_ms_median;

	json_object_set_new(doc, "gflop", json_real(f->total * 1e-9));
	json_object_set_new(doc, "total_flops", json_integer((json_int_t)f->total));
	json_object_set_new(
		doc, "flops_per_item",
		json_pack("{s:f, s:f, s:f}", "mean", f->mean, "max", f->max, "min", f->min));
	json_object_set_new(doc, "parallel_efficiency", json_real(f->parallel_efficiency));
	json_object_set_new(doc, "gflops", json_real(f->total * 1e-6 / ms));
	json_object_set_new(doc, "rays", json_integer((json_int_t)f->rays));
	json_object_set_new(doc, "mrays_per_s", json_real(f->rays * 1e-3 / ms));
}

static json_t *stats_document(const struct run *run)
{
	const struct render_settings *s = &run->settings;
	const struct render_result *r = &run->result;
	char workgroup[32], groups[32];
	json_t *times = json_array();

	snprintf(workgroup, sizeof(workgroup), "%dx%d", s->workgroup[0], s->workgroup[1]);
	snprintf(groups, sizeof(groups), "%dx%d", r->groups[0], r->groups[1]);
	for (int i = 0; i < r->repeat; i++)
		json_array_append_new(times, json_real(r->kernel_ms[i]));
	return json_pack("{s:s, s:s, s:s, s:s, s:s, s:s, s:s, s:[I,I], s:i, s:i, s:i, s:s, s:b,"
			 " s:f, s:f, s:f, s:i, s:o, s:s, s:i}",
			 "rtcl_version", RTCL_VERSION, "device", run->device_name, "device_version",
			 run->device_version, "driver", run->driver, "kernel",
			 s->kernel ? s->kernel->name : "reference", "workgroup", workgroup,
			 "groups", groups, "global_size", (json_int_t)r->global_size[0],
			 (json_int_t)r->global_size[1], "width", s->width, "height", s->height,
			 "max_depth", s->max_depth, "scene", run->scene->source,
			 "scene_in_local_memory", r->scene_in_local, "kernel_ms",
			 r->kernel_ms_median, "kernel_ms_min", r->kernel_ms_min, "kernel_ms_max",
			 r->kernel_ms_max, "repeat", r->repeat, "kernel_ms_all", times,
			 "build_options", r->build_options, "batch", s->batch);
}

/* The device's size and clock, for peak-throughput estimates (not for the
 * CPU reference, which opens no device). */
static void add_device_figures(json_t *doc, const struct run *run)
{
	if (!run->on_device)
		return;
	json_object_set_new(doc, "compute_units", json_integer(run->compute_units));
	json_object_set_new(doc, "max_clock_mhz", json_integer(run->max_clock_mhz));
}

/* The --flops sidecar: how the counts were launched. */
static json_t *flops_sidecar(const struct run *run)
{
	const struct render_settings *s = &run->settings;
	const struct render_result *c = &run->counted;
	json_t *doc = json_pack(
		"{s:s, s:i, s:s, s:[i,i], s:[i,i], s:[I,I], s:i, s:i, s:i, s:s, s:s, s:s}",
		"format", "rtcl-flops", "version", 1, "kernel", s->kernel->name, "workgroup",
		(int)c->local_size[0], (int)c->local_size[1], "groups", c->groups[0], c->groups[1],
		"global_size", (json_int_t)c->global_size[0], (json_int_t)c->global_size[1],
		"width", s->width, "height", s->height, "max_depth", s->max_depth, "device",
		run->device_name, "scene", run->scene->source, "layout",
		s->kernel->multi_pass
			? "counts[0][i]: every launch's work-items one after the other (the "
			  "primary-ray launch, then one launch per bounce)"
			: "counts[y][x] for the work-item at global id (x, y); 0 for those given "
			  "no "
			  "pixel");

	if (doc)
		add_flop_figures(doc, run);
	return doc;
}

/* Writes one JSON document; returns 0 or -1 with a message. */
static int write_json(const char *path, json_t *doc, char *err, size_t err_size)
{
	int failed = !doc || stats_write_json(path, doc, err, err_size);

	if (!doc)
		snprintf(err, err_size, "%s: cannot build the JSON document", path);
	json_decref(doc);
	return failed ? -1 : 0;
}

/* Writes the image and every other output asked for, or none of them: a
 * failure removes what this run already wrote. */
static int write_outputs(const struct run *run, char *err, size_t err_size)
{
	const struct options *opt = run->opt;
	const struct render_settings *s = &run->settings;
	char description[1024], sidecar[4200];
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
		const struct render_result *c = &run->counted;
		/* One row per NDRange row; the wavefront's launches in one row. */
		int one_row = s->kernel->multi_pass;
		size_t rows = one_row ? 1 : c->global_size[1];
		size_t cols = one_row ? c->item_count : c->global_size[0];
		if (stats_write_npy(opt->flops_path, c->item_flops, rows, cols, err, err_size))
			goto out_remove;
		written[count++] = opt->flops_path;
		snprintf(sidecar, sizeof(sidecar), "%s.json", opt->flops_path);
		if (write_json(sidecar, flops_sidecar(run), err, err_size))
			goto out_remove;
		written[count++] = sidecar;
	}
	if (opt->stats_path) {
		json_t *doc = stats_document(run);
		if (doc && run->counting)
			add_flop_figures(doc, run);
		if (doc)
			add_device_figures(doc, run);
		if (write_json(opt->stats_path, doc, err, err_size))
			goto out_remove;
	}
	return 0;

out_remove:
	while (count > 0)
		outfile_remove(written[--count]);
	return -1;
}

/* Removes every output of this run (after an interrupt while writing). */
static void remove_outputs(const struct options *opt)
{
	char sidecar[4200];

	outfile_remove(opt->output);
	if (opt->work_map_path)
		outfile_remove(opt->work_map_path);
	if (opt->stats_path)
		outfile_remove(opt->stats_path);
	if (opt->flops_path) {
		snprintf(sidecar, sizeof(sidecar), "%s.json", opt->flops_path);
		outfile_remove(opt->flops_path);
		outfile_remove(sidecar);
	}
}

/* Checks every output can be written before any work starts. */
static int check_outputs(const struct options *opt, char *err, size_t err_size)
{
	char sidecar[4200];

	if (image_check_writable(opt->output, err, err_size))
		return -1;
	if (opt->work_map_path && image_check_writable(opt->work_map_path, err, err_size))
		return -1;
	if (opt->stats_path && outfile_check_writable(opt->stats_path, err, err_size))
		return -1;
	if (opt->flops_path) {
		snprintf(sidecar, sizeof(sidecar), "%s.json", opt->flops_path);
		if (outfile_check_writable(opt->flops_path, err, err_size) ||
		    outfile_check_writable(sidecar, err, err_size))
			return -1;
	}
	return 0;
}

static int render_on_device(struct run *run, char *err, size_t err_size)
{
	const struct options *opt = run->opt;
	struct device dev;

	if (device_open(&dev, opt->platform, opt->device, err, err_size))
		return -1;
	snprintf(run->device_name, sizeof(run->device_name), "%s (%s)", dev.name,
		 dev.platform_name);
	snprintf(run->device_version, sizeof(run->device_version), "%s", dev.version);
	snprintf(run->driver, sizeof(run->driver), "%s", dev.driver);
	run->on_device = 1;
	run->compute_units = dev.compute_units;
	run->max_clock_mhz = dev.max_clock_mhz;
	if (opt->verbose)
		fprintf(stderr, "rtcl: platform %d, device %d: %s\n", dev.platform_index,
			dev.device_index, run->device_name);
	int failed = 0;
	if (run->counting) {
		struct render_settings counting = run->settings;
		counting.count_flops = 1;
		failed = render(&dev, run->scene, &counting, &run->counted, err, err_size);
		if (!failed)
			flop_summary_compute(&run->flops, run->counted.item_flops,
					     run->counted.item_count, run->counted.total_rays);
	}
	if (!failed)
		failed = render(&dev, run->scene, &run->settings, &run->result, err, err_size);
	if (!failed && opt->verbose)
		fprintf(stderr, "rtcl: build options: %s\n", run->result.build_options);
	device_close(&dev);
	return failed ? -1 : 0;
}

int main(int argc, char **argv)
{
	static char err[ERR_SIZE];
	struct options opt;
	struct scene scene;
	struct run run;
	int status = EXIT_FAILED;

	if (cli_parse(argc, argv, &opt, err, sizeof(err))) {
		fprintf(stderr, "rtcl: %s\n", err);
		return EXIT_USAGE;
	}
	if (opt.help) {
		cli_print_help(stdout);
		return 0;
	}
	if (opt.version) {
		printf("rtcl %s\n", RTCL_VERSION);
		return 0;
	}
	if (opt.list_devices) {
		if (device_list(stdout, err, sizeof(err))) {
			fprintf(stderr, "rtcl: %s\n", err);
			return EXIT_FAILED;
		}
		return 0;
	}

	catch_interrupts();
	if (load_scene(&opt, &scene, err, sizeof(err))) {
		fprintf(stderr, "%s\n", err);
		return EXIT_FAILED;
	}
	memset(&run, 0, sizeof(run));
	run.opt = &opt;
	run.scene = &scene;
	run.settings.kernel = render_find_kernel(opt.kernel); /* NULL: the reference */
	run.settings.workgroup[0] = opt.workgroup[0];
	run.settings.workgroup[1] = opt.workgroup[1];
	run.settings.groups[0] = opt.groups[0];
	run.settings.groups[1] = opt.groups[1];
	run.settings.width = opt.size[0] ? opt.size[0] : scene.width;
	run.settings.height = opt.size[1] ? opt.size[1] : scene.height;
	run.settings.max_depth = opt.depth >= 0 ? opt.depth : scene.max_depth;
	run.settings.repeat = opt.repeat;
	run.settings.batch = opt.batch;
	run.settings.source_dir = getenv("RTCL_CL_DIR");
	run.settings.progress = !opt.quiet && isatty(STDERR_FILENO);
	progress_on_terminal = run.settings.progress;
	run.settings.verbose = opt.verbose;

	run.counting = opt.flops_path || opt.work_map_path;
	if (check_outputs(&opt, err, sizeof(err))) {
		fprintf(stderr, "rtcl: %s\n", err);
		goto out_free_scene;
	}
	if (run.settings.kernel ? render_on_device(&run, err, sizeof(err))
				: render_reference(&run, err, sizeof(err))) {
		fprintf(stderr, "rtcl: %s\n", err);
		goto out_free_scene;
	}
	/* An interrupt while the outputs are written must not leave some of
	 * them: hold it back, and if one came, remove what was written. */
	sigset_t pending;
	hold_interrupts(1, NULL);
	if (write_outputs(&run, err, sizeof(err))) {
		hold_interrupts(0, NULL);
		fprintf(stderr, "rtcl: %s\n", err);
		goto out_free_result;
	}
	sigpending(&pending);
	if (sigismember(&pending, SIGINT) || sigismember(&pending, SIGTERM))
		remove_outputs(&opt);
	hold_interrupts(0, NULL);
	if (!opt.quiet)
		print_summary(&run);
	status = 0;

out_free_result:
	render_result_free(&run.result);
	render_result_free(&run.counted);
out_free_scene:
	scene_free(&scene);
	return status;
}
