/* rtcl: ray-trace a scene with OpenCL and study how the work is balanced.
 *
 * main() reads as the pipeline every mode shares: options -> scene -> job
 * (what to render, job/job.h) -> output plan (what to write, checked before
 * any work, output/plan.h) -> mode (one image, --frames or --mpi, run/mode.h)
 * -> write (one commit) -> report (the summary). Every failure ends here with one
 * message on stderr and no output file written; an interrupt ends the
 * process from interrupt.c's thread, leaving the previous outputs or the
 * complete new ones.
 */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/embedded.h"
#include "base/files.h"
#include "base/interrupt.h"
#include "base/progress.h"
#include "base/quote.h"
#include "base/test_hooks.h"
#include "base/timing.h"
#include "cmd/cli.h"
#include "device/device.h"
#include "job/job.h"
#include "job/record.h"
#include "output/plan.h"
#include "render/render.h"
#include "run/mode.h"
#include "scene/mesh.h"
#include "scene/scene.h"

#define DEFAULT_SCENE "paper60.json"
#define ERR_SIZE 65536 /* room for a kernel build log */

static int load_scene(const struct options *opt, struct scene *scene, char *err, size_t err_size)
{
	/* The argument may be a model file to render alone; -s names a scene. */
	if (opt->scene_path && opt->scene_is_argument && scene_is_model_file(opt->scene_path)) {
		struct model_view view = {opt->size[0], opt->size[1],
					  opt->camera.fov_given ? opt->camera.fov : 0};
		return scene_load_model(scene, opt->scene_path, &view, err, err_size);
	}
	if (opt->scene_path) {
		char hint[2 * PATH_MAX + 200];
		int failed = scene_load_file(scene, opt->scene_path, err, err_size);
		size_t length = strlen(err);
		if (failed)
			snprintf(err + length, err_size - length, "%s",
				 scene_model_hint(opt->scene_path, hint, sizeof(hint)));
		return failed;
	}
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

/* What each mesh file brought: materials, textures, what was not understood. */
static void print_mesh_reports(const struct scene *scene)
{
	for (int i = 0; i < scene->mesh_report_count; i++)
		fprintf(stderr, "rtcl: %s\n", scene->mesh_reports[i]);
}

/* Whether the progress line is shown: on a terminal, unless -q. Under
 * mpirun a rank's stderr is a pipe even when mpirun's is a terminal, which
 * the rank's stdout (a pseudo-terminal then) tells; other ranks than 0 turn
 * it off (run/mpi_render.c). */
static int shows_progress(const struct options *opt)
{
	return !opt->quiet && (isatty(STDERR_FILENO) || (opt->mpi && isatty(STDOUT_FILENO)));
}

/* What the integrator makes of fields that only the other one reads
 * (SCENE.md, "Path tracing"). */
static void print_integrator_warnings(const struct scene *scene)
{
	const char *source = quote_text(scene->source);

	if (scene->integrator == SCENE_INTEGRATOR_PATH && scene->ambient_given)
		fprintf(stderr,
			"rtcl: warning: %s: ambient: has no meaning under the path integrator "
			"(indirect light is traced); it is ignored\n",
			source);
	if (scene->integrator == SCENE_INTEGRATOR_WHITTED && scene->environment.file)
		fprintf(stderr,
			"rtcl: warning: %s: environment: is used only by the path integrator; it "
			"is ignored\n",
			source);
}

/* Under -v and the path integrator, what lights the scene (RENDERING.md,
 * "Lights and their selection"): the scene's lights, the emitting triangles
 * and spheres, the environment. */
static void print_path_lights(const struct scene *scene)
{
	const struct scene_environment *env = &scene->environment;
	int triangles = 0, spheres = 0;

	if (scene->integrator != SCENE_INTEGRATOR_PATH)
		return;
	for (int i = 0; i < scene->triangle_count; i++)
		triangles += scene_material_emits(&scene->materials[scene->triangles[i].material]);
	for (int i = 0; i < scene->sphere_count; i++)
		spheres += scene_material_emits(&scene->materials[scene->spheres[i].material]);
	fprintf(stderr, "rtcl: path integrator: %d light%s, %d emitting triangle%s, %d emitting "
			"sphere%s, ",
		scene->light_count, scene->light_count == 1 ? "" : "s", triangles,
		triangles == 1 ? "" : "s", spheres, spheres == 1 ? "" : "s");
	if (env->rgb)
		fprintf(stderr, "environment map %dx%d (scale %g, rotate %g)\n", env->width,
			env->height, env->scale, env->rotate);
	else if (scene->background[0] > 0 || scene->background[1] > 0 || scene->background[2] > 0)
		fprintf(stderr, "uniform environment [%g, %g, %g]\n", scene->background[0],
			scene->background[1], scene->background[2]);
	else
		fprintf(stderr, "no environment\n");
}

/* The job: the options, else the scene's own values. */
static void make_job(struct job *job, const struct options *opt, const struct scene *scene)
{
	struct render_settings *s = &job->settings;

	memset(job, 0, sizeof(*job));
	job->scene = scene;
	s->kernel = render_find_kernel(opt->kernel); /* NULL: the reference */
	memcpy(s->workgroup, opt->workgroup, sizeof(s->workgroup));
	memcpy(s->groups, opt->groups, sizeof(s->groups));
	s->width = opt->size[0] ? opt->size[0] : scene->width;
	s->height = opt->size[1] ? opt->size[1] : scene->height;
	s->max_depth = opt->depth >= 0 ? opt->depth : scene->max_depth;
	s->samples = opt->spp ? opt->spp : scene->samples;
	s->samples_per_pass = hook_pass_samples();
	s->repeat = opt->repeat ? opt->repeat : 1;
	s->warm_up = opt->repeat > 0;
	s->batch = opt->batch;
	s->fetch = opt->fetch;
	s->regenerate = opt->regenerate;
	s->wavefront_stages = opt->wavefront_stages;
	s->wavefront_form_given = opt->wavefront_form_given;
	s->paths_in_flight = opt->paths_in_flight;
	s->queues = opt->queues;
	s->source_dir = getenv("RTCL_CL_DIR");
	s->progress = 1; /* one image on one device: render() runs the line */
	s->verbose = opt->verbose;
	s->accel = opt->accel;
	s->aov = opt->outputs.aov || opt->outputs.denoise;
	job->denoise = opt->outputs.denoise;
	job->counting = opt->outputs.flops || opt->outputs.work_map;
	job->mapping = opt->outputs.schedule_map != NULL;
	job->devices = opt->devices;
	job->split = (enum split)opt->split;
	job->split_given = opt->split_given;
	job->row_order_given = opt->row_order_given;
	job->piece_rows = opt->piece_rows;
	job->row_order = (enum row_order)opt->row_order;
	job->row_classes = opt->row_classes;
	job->animation = opt->frames_given;
	job->first_frame = opt->frames[0];
	job->last_frame = opt->frames[1];
	job->mpi = opt->mpi;
	job->all_or_nothing = opt->no_partial;
	job->checkpoint_seconds = opt->checkpoint_seconds;
	job->verbose = opt->verbose;
	job->quiet = opt->quiet;
}

/* Prints err's message (unless the mode printed its own) and returns status. */
static int fail(const char *err, int status)
{
	if (err[0])
		fprintf(stderr, "rtcl: %s\n", err);
	return status;
}

/* After a render an interrupt stopped (interrupt_allow_stop) and whose
 * outputs were written: says what they hold, returns the interrupt's exit
 * status. */
static int report_stopped(const struct job *job, const struct record *record,
			  const struct output_plan *plan)
{
	int samples = settings_samples(&job->settings),
	    done = record_samples_done(&job->settings, record);

	if (job->animation)
		fprintf(stderr, "rtcl: interrupted; wrote the %d frame%s finished of %d\n",
			plan->frames_written, plan->frames_written == 1 ? "" : "s", plan->frames);
	else if (done < samples)
		fprintf(stderr, "rtcl: interrupted; wrote %s with %d of %d samples per pixel\n",
			quote_text(plan->request->image), done, samples);
	else
		fprintf(stderr,
			"rtcl: interrupted after the last pass; the outputs were written\n");
	return 128 + interrupt_stop_signal();
}

/* The pipeline every mode shares: the output plan checked before any work,
 * the mode's render, the outputs written all at once, the summary. Returns
 * the exit status. */
static int render_and_write(const struct job *job, const struct output_request *request,
			    struct record *record, char *err, size_t err_size)
{
	const struct mode *mode = mode_for(job);
	struct output_plan plan;
	struct mode_run run = {job, &plan, record, 1, NULL};
	int status = 0, checked = 0;

	err[0] = '\0';
	if (output_plan_open(&plan, request, job, err, err_size))
		return fail(err, EXIT_FAILED);
	if (mode->begin)
		status = mode->begin(&run, err, err_size);
	if (status == 0 && run.writes)
		checked = output_plan_check(&plan, err, err_size);
	if (checked && !mode->checks_in_render)
		status = checked == OUTPUT_CLASH ? EXIT_USAGE : EXIT_FAILED;
	if (status == 0)
		status = mode->render(&run, checked, err, err_size);
	if (mode->end)
		mode->end(&run, status);
	if (status == 0 && run.writes && output_plan_commit(&plan, record, err, err_size))
		status = EXIT_FAILED;
	if (status)
		fail(err, status);
	else if (run.writes && !job->quiet)
		mode->summary(&run, stdout);
	if (status == 0 && run.writes && interrupt_stop_signal()) {
		fflush(stdout);
		status = report_stopped(job, record, &plan);
	}
	if (mode->release)
		mode->release(&run);
	output_plan_close(&plan);
	return status;
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

int main(int argc, char **argv)
{
	static char err[ERR_SIZE];
	double start = timing_now();
	struct options opt;
	struct scene scene;
	struct job job;
	struct record record;
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
	if (scene_override_camera(&scene, &opt.camera, err, sizeof(err))) {
		fprintf(stderr, "rtcl: %s\n", err);
		scene_free(&scene);
		return EXIT_USAGE;
	}
	if (opt.integrator >= 0)
		scene.integrator = opt.integrator;
	for (int i = 0; i < scene.warning_count; i++)
		fprintf(stderr, "rtcl: warning: %s\n", scene.warnings[i]);
	print_integrator_warnings(&scene);
	if (opt.verbose) {
		print_mesh_reports(&scene);
		print_scene_bounds(&scene);
		print_path_lights(&scene);
	}
	make_job(&job, &opt, &scene);
	if (render_check_integrator(&scene, &job.settings, err, sizeof(err))) {
		fprintf(stderr, "rtcl: %s\n", err);
		scene_free(&scene);
		return EXIT_USAGE;
	}
	memset(&record, 0, sizeof(record));
	record.start = start;
	status = render_and_write(&job, &opt.outputs, &record, err, sizeof(err));
	record_free(&record);
	scene_free(&scene);
	if (status == 0)
		interrupt_settle();
	return status;
}
