/* The job every --mpi rank must share, as numbers (run/job_digest.h): two
 * ranks of one job agree, and a rank that differs is told what differs
 * first, as the options name it. No MPI: the digests are compared here as
 * rank 0 compares those the ranks gathered. */
#include <criterion/criterion.h>

#include <string.h>

#include "render/render.h"
#include "run/job_digest.h"
#include "scene/scene.h"

#define SCENE_JSON(radius)                                                                         \
	"{\"format\": \"rtcl-scene\", \"version\": 1, "                                            \
	"\"camera\": {\"eye\": [0, 1, -5], \"look_at\": [0, 1, 0]}, "                              \
	"\"materials\": {\"red\": {\"color\": [0.8, 0.1, 0.1]}}, "                                 \
	"\"spheres\": [{\"center\": [0, 1, 0], \"radius\": " radius ", \"material\": \"red\"}]}"

static struct scene scene_a, scene_b;

static void load(struct scene *s, const char *json, const char *name)
{
	char err[512] = "";

	cr_assert_eq(scene_load_string(s, json, name, err, sizeof(err)), 0, "%s", err);
}

static void load_scenes(void)
{
	load(&scene_a, SCENE_JSON("1"), "a.json");
	load(&scene_b, SCENE_JSON("2"), "a.json");
}

static void free_scenes(void)
{
	scene_free(&scene_a);
	scene_free(&scene_b);
}

/* A job of one 32x24 image at --spp 2 with the dynamic kernel. */
static struct job make_job(const struct scene *scene)
{
	struct job job;

	memset(&job, 0, sizeof(job));
	job.scene = scene;
	job.settings.kernel = render_find_kernel("dynamic");
	job.settings.width = 32;
	job.settings.height = 24;
	job.settings.samples = 2;
	job.settings.max_depth = 5;
	job.settings.workgroup[0] = job.settings.workgroup[1] = 8;
	job.settings.batch = 1;
	job.settings.accel = ACCEL_BVH;
	job.split = SPLIT_DYNAMIC;
	return job;
}

/* Whether rank 1's job differs from rank 0's, with the message in out. */
static int differs(const struct job *root, const struct job *other, char *out, size_t size)
{
	struct job_digest a, b;

	job_digest_fill(root, &a);
	job_digest_fill(other, &b);
	out[0] = '\0';
	return job_digest_differs(&a, &b, 1, out, size);
}

TestSuite(job_digest, .init = load_scenes, .fini = free_scenes);

Test(job_digest, two_identical_jobs_agree)
{
	struct job root = make_job(&scene_a), other = make_job(&scene_a);
	char message[512];

	cr_assert_eq(differs(&root, &other, message, sizeof(message)), 0, "%s", message);
	cr_assert_str_eq(message, "");
}

Test(job_digest, the_devices_and_what_is_shown_may_differ)
{
	struct job root = make_job(&scene_a), other = make_job(&scene_a);
	char message[512];

	other.settings.progress = 1;
	other.settings.check_writes = 1;
	other.verbose = 1;
	other.devices.platform = 1;
	other.devices.device = 2;
	cr_assert_eq(differs(&root, &other, message, sizeof(message)), 0, "%s", message);
}

Test(job_digest, another_spp_is_named_as_the_option)
{
	struct job root = make_job(&scene_a), other = make_job(&scene_a);
	char message[512];

	other.settings.samples = 4;
	cr_assert_eq(differs(&root, &other, message, sizeof(message)), 1);
	cr_assert_str_eq(message, "rank 1 renders another job: --spp 4 against rank 0's --spp 2");
}

/* Rank 1's job changed by change(), then what it is told. */
static void expect_named(void (*change)(struct job *), const char *expected)
{
	struct job root = make_job(&scene_a), other = make_job(&scene_a);
	char message[512];

	change(&other);
	cr_assert_eq(differs(&root, &other, message, sizeof(message)), 1, "%s", expected);
	cr_expect_str_eq(message, expected);
}

static void wider(struct job *j)
{
	j->settings.width = 64;
}
static void shallower(struct job *j)
{
	j->settings.max_depth = 3;
}
static void animated(struct job *j)
{
	j->animation = 1;
	j->last_frame = 2;
}
static void in_bands(struct job *j)
{
	j->piece_rows = 3;
}
static void static_split(struct job *j)
{
	j->split = SPLIT_STATIC;
	j->split_given = 1;
}
static void scan_rows(struct job *j)
{
	j->row_order = ROWS_SCAN;
}
static void three_classes(struct job *j)
{
	j->row_classes = 3;
}
static void cyclic(struct job *j)
{
	j->settings.kernel = render_find_kernel("cyclic");
}
static void wide_groups(struct job *j)
{
	j->settings.workgroup[0] = 16;
}
static void some_groups(struct job *j)
{
	j->settings.groups[0] = j->settings.groups[1] = 4;
}
static void batched(struct job *j)
{
	j->settings.batch = 2;
}
static void brute_force(struct job *j)
{
	j->settings.accel = ACCEL_NONE;
}
static void fetched_by_warps(struct job *j)
{
	j->settings.fetch = FETCH_SUBGROUP;
}
static void regenerated(struct job *j)
{
	j->settings.regenerate = 1;
}
static void in_stages(struct job *j)
{
	j->settings.wavefront_stages = 1;
}
static void few_paths(struct job *j)
{
	j->settings.paths_in_flight = 4096;
}

Test(job_digest, each_setting_is_named_as_the_option)
{
	const char *head = "rank 1 renders another job: ";
	char expected[256];
	static const struct {
		void (*change)(struct job *);
		const char *message;
	} cases[] = {
		{wider, "--size 64x24 against rank 0's --size 32x24"},
		{shallower, "--depth 3 against rank 0's --depth 5"},
		{animated, "--frames 0:2 against rank 0's one image (no --frames)"},
		{in_bands, "--piece-rows 3 against rank 0's no --piece-rows"},
		{static_split, "--split static against rank 0's --split dynamic (the default)"},
		{scan_rows, "--row-order scan against rank 0's --row-order interleave"},
		{three_classes, "--row-order interleave:3 against rank 0's --row-order interleave"},
		{cyclic, "-k cyclic against rank 0's -k dynamic"},
		{wide_groups, "-w 16x8 against rank 0's -w 8x8"},
		{some_groups, "--groups 4x4 against rank 0's --groups 0x0"},
		{batched, "--batch 2 against rank 0's --batch 1"},
		{brute_force, "--accel none against rank 0's --accel bvh"},
		{fetched_by_warps, "--fetch subgroup against rank 0's --fetch item"},
		{regenerated, "--regenerate against rank 0's no --regenerate"},
		{in_stages, "--wavefront-form stages against rank 0's --wavefront-form bounce"},
		{few_paths,
		 "--paths-in-flight 4096 against rank 0's no --paths-in-flight"},
	};

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		snprintf(expected, sizeof(expected), "%s%s", head, cases[i].message);
		expect_named(cases[i].change, expected);
	}
}

Test(job_digest, the_first_setting_that_differs_is_named)
{
	struct job root = make_job(&scene_a), other = make_job(&scene_a);
	char message[512];

	other.settings.samples = 4;
	other.settings.batch = 2;
	other.settings.width = 64;
	cr_assert_eq(differs(&root, &other, message, sizeof(message)), 1);
	cr_assert_str_eq(message,
			 "rank 1 renders another job: --size 64x24 against rank 0's --size 32x24");
}

Test(job_digest, another_scene_is_named_before_any_setting)
{
	struct job root = make_job(&scene_a), other = make_job(&scene_b);
	char message[512];

	other.settings.samples = 4;
	cr_assert_eq(differs(&root, &other, message, sizeof(message)), 1);
	cr_assert_str_eq(message, "rank 1 renders another job: the scene differs (file a.json on "
				  "rank 0, a.json on rank 1, with other contents)");
}

Test(job_digest, another_scene_file_is_named)
{
	struct scene renamed;
	struct job root = make_job(&scene_a), other = make_job(&renamed);
	char message[512];

	load(&renamed, SCENE_JSON("2"), "b.json");
	cr_assert_eq(differs(&root, &other, message, sizeof(message)), 1);
	cr_expect_str_eq(message, "rank 1 renders another job: the scene differs (file a.json on "
				  "rank 0, b.json on rank 1)");
	scene_free(&renamed);
}

Test(job_digest, the_scene_file_name_alone_does_not_differ)
{
	struct scene renamed;
	struct job root = make_job(&scene_a), other = make_job(&renamed);
	char message[512];

	load(&renamed, SCENE_JSON("1"), "b.json");
	cr_expect_eq(differs(&root, &other, message, sizeof(message)), 0, "%s", message);
	scene_free(&renamed);
}
