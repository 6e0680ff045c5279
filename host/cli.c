#include "cli.h"

#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "render.h"
#include "scene.h"

enum long_only_option {
	OPT_GROUPS = 256,
	OPT_BATCH,
	OPT_SIZE,
	OPT_DEPTH,
	OPT_LIST_DEVICES,
	OPT_STATS,
	OPT_FLOPS,
	OPT_WORK_MAP,
	OPT_VERSION,
};

static const struct option long_options[] = {
	{"kernel", required_argument, NULL, 'k'},
	{"workgroup", required_argument, NULL, 'w'},
	{"groups", required_argument, NULL, OPT_GROUPS},
	{"batch", required_argument, NULL, OPT_BATCH},
	{"scene", required_argument, NULL, 's'},
	{"output", required_argument, NULL, 'o'},
	{"size", required_argument, NULL, OPT_SIZE},
	{"depth", required_argument, NULL, OPT_DEPTH},
	{"platform", required_argument, NULL, 'p'},
	{"device", required_argument, NULL, 'd'},
	{"list-devices", no_argument, NULL, OPT_LIST_DEVICES},
	{"repeat", required_argument, NULL, 'r'},
	{"stats", required_argument, NULL, OPT_STATS},
	{"flops", required_argument, NULL, OPT_FLOPS},
	{"work-map", required_argument, NULL, OPT_WORK_MAP},
	{"quiet", no_argument, NULL, 'q'},
	{"verbose", no_argument, NULL, 'v'},
	{"help", no_argument, NULL, 'h'},
	{"version", no_argument, NULL, OPT_VERSION},
	{NULL, 0, NULL, 0},
};

void cli_print_help(FILE *out)
{
	fprintf(out,
		"Usage: rtcl [OPTION]...\n"
		"Ray-trace a scene with OpenCL, scheduling pixels over work-items with one of\n"
		"several kernels, and write the image.\n"
		"\n"
		"Examples:\n"
		"  rtcl                                  the built-in 60-ball scene, dynamic "
		"kernel\n"
		"  rtcl -k cyclic -w 8x8 --groups 25x25  the paper's cyclic geometry\n"
		"  rtcl -s scenes/two_balls.json -o balls.exr --size 800x600\n"
		"  rtcl -k naive -r 10 --stats run.json  median of 10 timed launches, as JSON\n"
		"\n"
		"Scheduling:\n"
		"  -k, --kernel NAME      which work-item traces which pixel (default dynamic):\n");
	for (int i = 0; i < render_kernel_count; i++)
		fprintf(out, "                           %-9s %s\n", render_kernels[i].name,
			render_kernels[i].summary);
	fprintf(out,
		"                           %-9s the CPU reference renderer (C++, double "
		"precision)\n"
		"  -w, --workgroup WxH    work-group shape, also the chunk shape (default 8x8)\n"
		"      --groups GXxGY     persistent work-groups for cyclic, dynamic and "
		"persistent\n"
		"                         (default: enough to fill the device); at most\n"
		"                         2^31 work-items in all, GX*GY times -w's W*H\n"
		"      --batch N          pixels a work-item of the persistent kernel fetches\n"
		"                         at a time (default 1); the image's pixels plus N per\n"
		"                         work-item must stay below 2^32\n"
		"\n"
		"Scene and image:\n"
		"  -s, --scene FILE       scene file (SCENE.md); default: the built-in paper60\n"
		"  -o, --output FILE      image file, format from the extension (default "
		"render.png)\n"
		"      --size WxH         image size, overriding the scene's (1..%d each)\n"
		"      --depth N          reflection/refraction depth, overriding max_depth "
		"(0..%d)\n"
		"\n"
		"Device:\n"
		"  -p, --platform N       OpenCL platform index (default: the first with a GPU)\n"
		"  -d, --device N         device index within the platform (default: its first "
		"GPU,\n"
		"                         else its first device)\n"
		"      --list-devices     list platforms and devices with their indices, and exit\n"
		"\n"
		"Measuring:\n"
		"  -r, --repeat N         timed launches after one warm-up launch (default 1);\n"
		"                         prints the median, min and max kernel time\n"
		"      --stats FILE       write every printed figure to FILE as JSON\n"
		"      --flops FILE.npy   count floating-point operations (RENDERING.md) in a\n"
		"                         separate, untimed run; write one count per launched\n"
		"                         work-item as a .npy array shaped like the NDRange, with\n"
		"                         the launch geometry in FILE.npy.json; print GFLOP/s\n"
		"                         (over the uncounted run's time) and parallel efficiency\n"
		"      --work-map IMAGE   write the flops spent on each pixel as an image, with\n"
		"                         a colour scale bar (implies a counting run)\n"
		"\n"
		"Other:\n"
		"  -q, --quiet            print nothing but errors\n"
		"  -v, --verbose          say more: build options, where the scene lives\n"
		"  -h, --help             show this help and exit\n"
		"      --version          show the version and exit\n"
		"\n"
		"Environment, for kernel development:\n"
		"  RTCL_CL_DIR=DIR          load the OpenCL sources from DIR instead of the\n"
		"                           copies built into the binary\n"
		"  RTCL_BUILD_OPTIONS=OPTS  add OPTS to the program build options, e.g.\n"
		"                           -cl-nv-verbose (its report shows with -v)\n"
		"  RTCL_DUMP_BINARY=FILE    write the built program binary (PTX on NVIDIA)\n"
		"Exit status: 0 on success, 1 on a failure (scene, device, build, file), 2 on a\n"
		"bad option.\n",
		"reference", SCENE_MAX_IMAGE_SIDE, SCENE_MAX_DEPTH);
}

/* Parses a decimal integer in [min, max]; the whole string must be a number. */
static int parse_int(const char *text, long min, long max, long *value)
{
	char *end;

	errno = 0;
	*value = strtol(text, &end, 10);
	return text[0] == '\0' || *end != '\0' || errno || *value < min || *value > max ? -1 : 0;
}

/* Parses "WxH" with each side in [1, max]. */
static int parse_shape(const char *option, const char *text, long max, int out[2], char *err,
		       size_t err_size)
{
	const char *x = strchr(text, 'x');
	char first[32];
	long w, h;

	if (!x || (size_t)(x - text) >= sizeof(first)) {
		snprintf(err, err_size, "%s: expected WxH (e.g. 8x8), got \"%s\"", option, text);
		return -1;
	}
	memcpy(first, text, (size_t)(x - text));
	first[x - text] = '\0';
	if (parse_int(first, LONG_MIN, LONG_MAX, &w) || parse_int(x + 1, LONG_MIN, LONG_MAX, &h)) {
		snprintf(err, err_size, "%s: expected WxH (e.g. 8x8), got \"%s\"", option, text);
		return -1;
	}
	if (w < 1 || h < 1 || w > max || h > max) {
		snprintf(err, err_size, "%s: each size must be between 1 and %ld, got %s", option,
			 max, text);
		return -1;
	}
	out[0] = (int)w;
	out[1] = (int)h;
	return 0;
}

static int parse_bounded(const char *option, const char *text, long min, long max, int *out,
			 char *err, size_t err_size)
{
	long value;

	if (parse_int(text, min, max, &value)) {
		snprintf(err, err_size, "%s: expected an integer between %ld and %ld, got \"%s\"",
			 option, min, max, text);
		return -1;
	}
	*out = (int)value;
	return 0;
}

static int check_kernel(const char *name, char *err, size_t err_size)
{
	if (strcmp(name, "reference") == 0 || render_find_kernel(name))
		return 0;
	int n = snprintf(err, err_size, "-k/--kernel: unknown kernel \"%s\" (choose from", name);
	for (int i = 0; i < render_kernel_count && n >= 0 && (size_t)n < err_size; i++)
		n += snprintf(err + n, err_size - (size_t)n, " %s,", render_kernels[i].name);
	if (n >= 0 && (size_t)n < err_size)
		snprintf(err + n, err_size - (size_t)n, " reference)");
	return -1;
}

int cli_parse(int argc, char **argv, struct options *o, char *err, size_t err_size)
{
	int c;

	memset(o, 0, sizeof(*o));
	o->kernel = "dynamic";
	o->workgroup[0] = o->workgroup[1] = 8;
	o->output = "render.png";
	o->depth = -1;
	o->platform = o->device = -1;
	o->repeat = 1;
	o->batch = 1;

	opterr = 0;
	optind = 1;
	while ((c = getopt_long(argc, argv, ":k:w:s:o:p:d:r:qvh", long_options, NULL)) != -1) {
		int failed = 0;

		switch (c) {
		case 'k':
			o->kernel = optarg;
			failed = check_kernel(optarg, err, err_size);
			break;
		case 'w':
			failed = parse_shape("-w/--workgroup", optarg, 65536, o->workgroup, err,
					     err_size);
			break;
		case OPT_BATCH:
			failed =
				parse_bounded("--batch", optarg, 1, 4096, &o->batch, err, err_size);
			break;
		case OPT_GROUPS:
			failed = parse_shape("--groups", optarg, 65536, o->groups, err, err_size);
			break;
		case 's':
			o->scene_path = optarg;
			break;
		case 'o':
			o->output = optarg;
			if (optarg[0] == '\0') {
				snprintf(err, err_size, "-o/--output: the file name is empty");
				failed = 1;
			}
			break;
		case OPT_SIZE:
			failed = parse_shape("--size", optarg, SCENE_MAX_IMAGE_SIDE, o->size, err,
					     err_size);
			break;
		case OPT_DEPTH:
			failed = parse_bounded("--depth", optarg, 0, SCENE_MAX_DEPTH, &o->depth,
					       err, err_size);
			break;
		case 'p':
			failed = parse_bounded("-p/--platform", optarg, 0, 1000, &o->platform, err,
					       err_size);
			break;
		case 'd':
			failed = parse_bounded("-d/--device", optarg, 0, 1000, &o->device, err,
					       err_size);
			break;
		case OPT_LIST_DEVICES:
			o->list_devices = 1;
			break;
		case 'r':
			failed = parse_bounded("-r/--repeat", optarg, 1, 100000, &o->repeat, err,
					       err_size);
			break;
		case OPT_STATS:
			o->stats_path = optarg;
			break;
		case OPT_FLOPS:
			o->flops_path = optarg;
			break;
		case OPT_WORK_MAP:
			o->work_map_path = optarg;
			break;
		case 'q':
			o->quiet = 1;
			break;
		case 'v':
			o->verbose = 1;
			break;
		case 'h':
			o->help = 1;
			break;
		case OPT_VERSION:
			o->version = 1;
			break;
		case ':':
			snprintf(err, err_size, "%s needs a value (see --help)", argv[optind - 1]);
			failed = 1;
			break;
		default:
			if (optopt)
				snprintf(err, err_size, "unknown option -%c (see --help)", optopt);
			else
				snprintf(err, err_size, "unknown option %s (see --help)",
					 argv[optind - 1]);
			failed = 1;
			break;
		}
		if (failed)
			return -1;
	}
	if (optind < argc) {
		snprintf(err, err_size, "unexpected argument \"%s\" (options only; see --help)",
			 argv[optind]);
		return -1;
	}
	if (strcmp(o->kernel, "reference") == 0 && (o->flops_path || o->work_map_path)) {
		snprintf(err, err_size,
			 "--flops and --work-map count the OpenCL kernels' work; the reference "
			 "renderer does not count (choose an OpenCL kernel)");
		return -1;
	}
	if (o->quiet && o->verbose) {
		snprintf(err, err_size, "-q/--quiet and -v/--verbose contradict each other");
		return -1;
	}
	return 0;
}
