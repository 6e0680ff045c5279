/* rtcl: ray-trace a scene with OpenCL and study how the work is balanced.
 *
 * main() reads the options and the scene, checks the outputs can be written,
 * renders on the device (or with the CPU reference), then writes the image,
 * the summary and the --stats document. Every failure ends here with one
 * message on stderr and no output file written.
 */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "device.h"
#include "embedded.h"
#include "render.h"
#include "scene.h"
#include "outputs.h"
#include "stats.h"

#define DEFAULT_SCENE "paper60.json"
#define ERR_SIZE 65536 /* room for a kernel build log */

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

/* The CPU reference, timed by the host clock like a single launch. */
static int render_on_cpu(struct run *run, char *err, size_t err_size)
{
	snprintf(run->device_name, sizeof(run->device_name),
		 "CPU reference (C++, GLM, double precision, one core)");
	return render_reference(run->scene, &run->settings, &run->result, err, err_size);
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
	if (outputs_check(&opt, err, sizeof(err))) {
		fprintf(stderr, "rtcl: %s\n", err);
		goto out_free_scene;
	}
	if (run.settings.kernel ? render_on_device(&run, err, sizeof(err))
				: render_on_cpu(&run, err, sizeof(err))) {
		fprintf(stderr, "rtcl: %s\n", err);
		goto out_free_scene;
	}
	/* An interrupt while the outputs are written must not leave some of
	 * them: hold it back, and if one came, remove what was written. */
	sigset_t pending;
	hold_interrupts(1, NULL);
	if (outputs_write(&run, err, sizeof(err))) {
		hold_interrupts(0, NULL);
		fprintf(stderr, "rtcl: %s\n", err);
		goto out_free_result;
	}
	sigpending(&pending);
	if (sigismember(&pending, SIGINT) || sigismember(&pending, SIGTERM))
		outputs_remove(&opt);
	hold_interrupts(0, NULL);
	if (!opt.quiet)
		stats_print_summary(&run);
	status = 0;

out_free_result:
	render_result_free(&run.result);
	render_result_free(&run.counted);
out_free_scene:
	scene_free(&scene);
	return status;
}
