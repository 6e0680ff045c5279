#include "cmd/cli.h"

#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "scene/mesh.h"
#include "base/quote.h"
#include "render/render.h"
#include "render/stages.h"
#include "scene/scene.h"
#include "base/suggest.h"
#include "output/workmap.h"

enum long_only_option {
	OPT_GROUPS = 256,
	OPT_BATCH,
	OPT_FETCH,
	OPT_REGENERATE,
	OPT_QUEUES,
	OPT_SIZE,
	OPT_DEPTH,
	OPT_LIST_DEVICES,
	OPT_STATS,
	OPT_FLOPS,
	OPT_WORK_MAP,
	OPT_ENCODING,
	OPT_WORK_MAP_SCALE,
	OPT_WORK_MAP_BAR,
	OPT_SCHEDULE_MAP,
	OPT_AOV,
	OPT_DENOISE,
	OPT_VERSION,
	OPT_SPP,
	OPT_DEVICES,
	OPT_SPLIT,
	OPT_FRAMES,
	OPT_MPI,
	OPT_ACCEL,
	OPT_PIECE_ROWS,
	OPT_ROW_ORDER,
	OPT_MESH_TIME_LIMIT,
	OPT_MESH_MEMORY_LIMIT,
	OPT_EYE,
	OPT_LOOK_AT,
	OPT_FOV,
	OPT_APERTURE,
	OPT_FOCUS_DISTANCE,
	OPT_CHECKPOINT,
	OPT_NO_PARTIAL,
	OPT_INTEGRATOR,
	OPT_WAVEFRONT_FORM,
	OPT_PATHS_IN_FLIGHT,
};

static const struct option long_options[] = {
	{"kernel", required_argument, NULL, 'k'},
	{"workgroup", required_argument, NULL, 'w'},
	{"groups", required_argument, NULL, OPT_GROUPS},
	{"batch", required_argument, NULL, OPT_BATCH},
	{"fetch", required_argument, NULL, OPT_FETCH},
	{"regenerate", no_argument, NULL, OPT_REGENERATE},
	{"queues", required_argument, NULL, OPT_QUEUES},
	{"wavefront-form", required_argument, NULL, OPT_WAVEFRONT_FORM},
	{"paths-in-flight", required_argument, NULL, OPT_PATHS_IN_FLIGHT},
	{"scene", required_argument, NULL, 's'},
	{"output", required_argument, NULL, 'o'},
	{"size", required_argument, NULL, OPT_SIZE},
	{"depth", required_argument, NULL, OPT_DEPTH},
	{"spp", required_argument, NULL, OPT_SPP},
	{"integrator", required_argument, NULL, OPT_INTEGRATOR},
	{"eye", required_argument, NULL, OPT_EYE},
	{"look-at", required_argument, NULL, OPT_LOOK_AT},
	{"fov", required_argument, NULL, OPT_FOV},
	{"aperture", required_argument, NULL, OPT_APERTURE},
	{"focus-distance", required_argument, NULL, OPT_FOCUS_DISTANCE},
	{"platform", required_argument, NULL, 'p'},
	{"device", required_argument, NULL, 'd'},
	{"type", required_argument, NULL, 't'},
	{"list-devices", no_argument, NULL, OPT_LIST_DEVICES},
	{"devices", required_argument, NULL, OPT_DEVICES},
	{"split", required_argument, NULL, OPT_SPLIT},
	{"frames", required_argument, NULL, OPT_FRAMES},
	{"mpi", no_argument, NULL, OPT_MPI},
	{"piece-rows", required_argument, NULL, OPT_PIECE_ROWS},
	{"row-order", required_argument, NULL, OPT_ROW_ORDER},
	{"repeat", required_argument, NULL, 'r'},
	{"checkpoint", required_argument, NULL, OPT_CHECKPOINT},
	{"no-partial", no_argument, NULL, OPT_NO_PARTIAL},
	{"stats", required_argument, NULL, OPT_STATS},
	{"flops", required_argument, NULL, OPT_FLOPS},
	{"work-map", required_argument, NULL, OPT_WORK_MAP},
	{"encoding", required_argument, NULL, OPT_ENCODING},
	{"work-map-scale", required_argument, NULL, OPT_WORK_MAP_SCALE},
	{"work-map-bar", required_argument, NULL, OPT_WORK_MAP_BAR},
	{"schedule-map", required_argument, NULL, OPT_SCHEDULE_MAP},
	{"aov", required_argument, NULL, OPT_AOV},
	{"denoise", no_argument, NULL, OPT_DENOISE},
	{"quiet", no_argument, NULL, 'q'},
	{"verbose", no_argument, NULL, 'v'},
	{"help", no_argument, NULL, 'h'},
	{"version", no_argument, NULL, OPT_VERSION},
	{"accel", required_argument, NULL, OPT_ACCEL},
	{"mesh-time-limit", required_argument, NULL, OPT_MESH_TIME_LIMIT},
	{"mesh-memory-limit", required_argument, NULL, OPT_MESH_MEMORY_LIMIT},
	{NULL, 0, NULL, 0},
};

/* --help from the reference renderer on: the options after the kernels. */
static void print_help_after_kernels(FILE *out)
{
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
		"      --fetch item|group|subgroup  how a work-item of the persistent kernel\n"
		"                         takes its pixels: an atomic of its own (item, the\n"
		"                         default), from a block its work-group takes\n"
		"                         (group), or with one atomic for its warp's\n"
		"                         active lanes (subgroup; NVIDIA compute capability\n"
		"                         7.0 or more, elsewhere each work-item fetches alone)\n"
		"      --regenerate       path regeneration in the persistent kernel (the path\n"
		"                         integrator): a work-item whose path ended starts the\n"
		"                         next at once, so a warp's lanes step together\n"
		"      --queues N         in-order queues a device renders with, 1 to 4: the\n"
		"                         image's columns in N parts whose launches alternate,\n"
		"                         so that one fills the device while another ends\n"
		"                         (default on a GPU for a render of several passes:\n"
		"                         2 for the whole image, 4 for a device's share of\n"
		"                         it; else 1. The image is the same; the counting\n"
		"                         run of --flops uses 1). Not for serial, wavefront\n"
		"                         or reference, which render on one queue\n"
		"      --wavefront-form bounce|stages  how -k wavefront splits the paths of the\n"
		"                         path integrator: one launch per bounce over the\n"
		"                         live paths (default), or in stages (Laine, Karras\n"
		"                         and Aila 2013): a logic kernel, new paths, a shade\n"
		"                         kernel per BSDF kind, extension and shadow rays,\n"
		"                         each over its own queue; the same image\n"
		"      --paths-in-flight N  the stages form's pool of paths, 1 to %d\n"
		"                         (default %d on a GPU, %d a compute unit on a\n"
		"                         CPU, within an eighth of the device's memory, or\n"
		"                         the render's paths when fewer); %d bytes each\n"
		"      --accel bvh|bvh-compact|none  how a ray finds the spheres and\n"
		"                         triangles it hits: through a BVH built on the host\n"
		"                         (default); bvh-compact, one with larger leaves of\n"
		"                         triangles and no copy of them in leaf order, about\n"
		"                         51 device bytes a triangle against 118 and slower\n"
		"                         on meshes; or by testing every one,\n"
		"                         the paper's brute force. The same image with each\n"
		"                         of them\n"
		"\n"
		"Scene and image:\n"
		"  -s, --scene FILE       scene file (SCENE.md), the same as giving it as SCENE\n"
		"                         (a model file is given as MODEL, not with -s);\n"
		"                         default: the built-in paper60\n"
		"  -o, --output FILE      image file, format from the extension (default "
		"render.png)\n"
		"      --size WxH         image size, overriding the scene's (1..%d each)\n"
		"      --depth N          reflection/refraction depth, overriding max_depth "
		"(0..%d)\n"
		"      --spp N            samples per pixel, overriding image.samples (1..%d;\n"
		"                         default 1, the pixel centre): antialiasing with a\n"
		"                         box filter, traced in passes with progress\n"
		"      --integrator whitted|path  the light transport, overriding the scene's\n"
		"                         integrator: Whitted ray tracing (the default), or a\n"
		"                         path tracer (bounced light, BSDFs, emitters; converges\n"
		"                         with --spp)\n"
		"      --eye X,Y,Z        the camera's eye, overriding camera.eye\n"
		"      --look-at X,Y,Z    the point the camera looks at, overriding\n"
		"                         camera.look_at\n"
		"      --fov DEG          vertical field of view, 0 < DEG < 180, overriding\n"
		"                         camera.fov\n"
		"      --aperture A       lens radius in world units (>= 0), overriding\n"
		"                         camera.aperture: > 0 gives depth of field, which\n"
		"                         converges with --spp\n"
		"      --focus-distance F distance of the sharp plane (> 0), overriding\n"
		"                         camera.focus_distance (default: eye to look_at)\n"
		"      --encoding srgb|linear  how 8-bit formats (PNG, JPEG, TIFF, PPM...) store\n"
		"                         the linear colours: the sRGB curve (default), or\n"
		"                         round(255 c) as in the paper; EXR, HDR and PFM are\n"
		"                         always linear\n"
		"      --aov LIST         also write auxiliary images, LIST of albedo, normal\n"
		"                         and depth (comma-separated), each the mean over the\n"
		"                         pixel's samples of its primary rays' first hits, as\n"
		"                         linear .pfm files beside -o: out.png gives\n"
		"                         out.albedo.pfm, out.normal.pfm, out.depth.pfm\n"
		"      --denoise          denoise the image with Intel Open Image Denoise (its\n"
		"                         RT filter, on the host's CPU, fed with the albedo\n"
		"                         and normal images); `make deps` installs it.\n"
		"                         --aov and --denoise need one image on one OpenCL\n"
		"                         device (not reference, --devices, --piece-rows,\n"
		"                         --frames or --mpi)\n"
		"      --mesh-time-limit SECONDS  refuse a mesh file whose import takes\n"
		"                         longer (default 60; 0: no limit)\n"
		"      --mesh-memory-limit MIB  the memory a mesh file's import may take\n"
		"                         (default: half the machine's; 0: no limit)\n"
		"\n"
		"Device:\n"
		"  -p, --platform N       OpenCL platform index (default: the first with a GPU)\n"
		"  -d, --device N         device index within the platform (default: its first "
		"GPU,\n"
		"                         else its first device)\n"
		"  -t, --type gpu|cpu|all the kind of device: the first GPU or CPU (of -p's\n"
		"                         platform, if given); with -p/-d or --devices, those\n"
		"                         must be of that kind (--devices all: those that are);\n"
		"                         all (default): the first GPU, else the first device\n"
		"      --list-devices     list platforms and devices with their indices, and exit\n"
		"\n"
		"Several devices and animations:\n"
		"      --devices LIST|all render on several devices at once: PLATFORM:DEVICE\n"
		"                         indices (e.g. 1:0,0:0), or all (every GPU and CPU);\n"
		"                         not with -p/-d\n"
		"      --split dynamic|static|samples  how the image goes to the devices:\n"
		"                         pieces of pixels, each device taking the next when\n"
		"                         it is free (dynamic), or equal shares (static); or\n"
		"                         samples: every device renders the whole image, a\n"
		"                         share of each pixel's samples by its speed, the same\n"
		"                         image (default: samples if every device is a GPU\n"
		"                         and their costs, measured at set-up, favour it,\n"
		"                         without --row-order; under --mpi the same over\n"
		"                         every rank's devices, unless a rank is bound to\n"
		"                         one core; else dynamic)\n"
		"      --frames A:B       render frames A to B (0..99999, at most %d), the\n"
		"                         camera's eye turned about look_at along up by\n"
		"                         360 (f-A)/(B-A+1) degrees; -o out.png writes\n"
		"                         out_0000.png.. (the frame number before the extension)\n"
		"      --mpi              run under mpirun: rank 0 hands the pieces out to every\n"
		"                         rank's devices and writes the outputs\n"
		"      --piece-rows N     one image over several devices or ranks goes out in\n"
		"                         row bands of N rows, each with all its samples\n"
		"                         (default: rectangles sized per device from its speed;\n"
		"                         --split static: one band per device; --mpi: one\n"
		"                         per device if all are GPUs, else about 32 each);\n"
		"                         with one device (--devices P:D) it measures what\n"
		"                         bands of N rows cost that device\n"
		"      --row-order interleave[:S]|scan  which image rows the pieces take:\n"
		"                         bands of a work-group's height dealt to S classes\n"
		"                         (default S: the GPUs, else the devices; under --mpi\n"
		"                         every rank's devices), so an equal share of the\n"
		"                         image is every S-th band; or the rows in order\n"
		"\n"
		"Interrupts and long renders:\n"
		"      Ctrl-C (SIGINT) or SIGTERM during a render of several passes stops it\n"
		"                         after the pass under way and writes the image of\n"
		"                         the samples done, saying how many (the summary,\n"
		"                         the file's metadata); a second one stops at once,\n"
		"                         writing nothing. --frames keeps the frames\n"
		"                         finished; -r, --mpi and pieces of pixels over\n"
		"                         several devices write nothing\n"
		"      --checkpoint SECONDS  also write the image of the samples done every\n"
		"                         SECONDS (1..%d) during the passes, each a\n"
		"                         complete file; one device or -k reference\n"
		"      --no-partial       all or nothing: an interrupt writes nothing\n"
		"\n"
		"Measuring:\n"
		"  -r, --repeat N         N timed launches after one warm-up launch; without\n"
		"                         -r, one launch: the image, timed, no warm-up;\n"
		"                         prints the median, min and max kernel time\n"
		"      --stats FILE       write every printed figure to FILE as JSON\n"
		"      --flops FILE.npy   count floating-point operations (RENDERING.md) in a\n"
		"                         separate, untimed run; write one count per launched\n"
		"                         work-item as a .npy array shaped like the NDRange, with\n"
		"                         the launch geometry in FILE.npy.json; print GFLOP/s\n"
		"                         (over the uncounted run's time) and parallel efficiency\n"
		"      --work-map FILE    write the flops spent on each pixel (implies a counting\n"
		"                         run): FILE.npy or a float image (.exr, .pfm, .hdr)\n"
		"                         holds the counts themselves (uint64 in the .npy,\n"
		"                         height x width); any other image format, a picture\n"
		"                         of them the size of the render, whose colour scale\n"
		"                         bar --work-map-bar writes to a file of its own\n"
		"      --work-map-scale linear|log  the picture's colour scale (default linear);\n"
		"                         log spreads the many cheap pixels\n"
		"      --work-map-bar FILE  write the --work-map picture's colour scale bar to\n"
		"                         the image FILE (needs --work-map with a picture): as\n"
		"                         wide as the render (at least 170 pixels), labels 0,\n"
		"                         middle and max, and the unit \"flops per pixel\"\n"
		"      --schedule-map FILE  record which work-item traced each pixel, and when\n"
		"                         (an instrumented run, the same image): FILE.npy holds\n"
		"                         height x width x 3 uint32 (work-group, work-item in\n"
		"                         it, ticket: the order pixels started); any image\n"
		"                         format, the pixels coloured by work-group. One device,\n"
		"                         a single-pass kernel (not the wavefront or reference)\n"
		"\n"
		"Other:\n"
		"  -q, --quiet            print nothing but errors (on a terminal, rtcl otherwise\n"
		"                         shows on stderr the share done and the time left)\n"
		"  -v, --verbose          say more: the scene's bounds, build options, where the\n"
		"                         scene lives\n"
		"  -h, --help             show this help and exit\n"
		"      --version          show the version and exit\n"
		"\n"
		"Environment:\n"
		"  RTCL_MESH_TIME_LIMIT=SECONDS  --mesh-time-limit, when not given\n"
		"  RTCL_MESH_MEMORY_LIMIT=MIB  --mesh-memory-limit, when not given\n"
		"  RTCL_OIDN_LIBRARY=FILE  the Open Image Denoise library --denoise loads\n"
		"                           (default: the one `make deps` installs)\n"
		"For kernel development:\n"
		"  RTCL_CL_DIR=DIR          load the OpenCL sources from DIR instead of the\n"
		"                           copies built into the binary\n"
		"  RTCL_BUILD_OPTIONS=OPTS  add OPTS to the program build options, e.g.\n"
		"                           -cl-nv-verbose (its report shows with -v)\n"
		"  RTCL_DUMP_BINARY=FILE    write the built program binary (PTX on NVIDIA)\n"
		"  RTCL_MPI_SUMS=WAY        --mpi split by samples on one node: how a rank's\n"
		"                           sums reach the shared memory: host-ptr (default),\n"
		"                           copy or read (docs/GUIDE.md, MPI)\n"
		"  RTCL_FRAMES_READ=WAY     --frames: how a device's frames come back:\n"
		"                           pageable (default: beside its next frame), aside\n"
		"                           or inline (docs/GUIDE.md, Animations)\n"
		"  RTCL_CACHE=0             do not keep or load built programs in\n"
		"                           $XDG_CACHE_HOME/rtcl (default: ~/.cache/rtcl)\n"
		"  POCL_CACHE_DIR=DIR       PoCL's kernel cache; PoCL finds no device unless it\n"
		"                           can write there (default: ~/.cache/pocl)\n"
		"An option that sets something the run does not have is refused, naming what\n"
		"it needs: --groups with -k naive, --batch, --fetch or --regenerate without\n"
		"-k persistent (--regenerate also without the path integrator),\n"
		"--wavefront-form without -k wavefront and the path integrator,\n"
		"--paths-in-flight without --wavefront-form stages, --queues with serial,\n"
		"wavefront or reference, --work-map-scale without a --work-map picture,\n"
		"--split without --devices or --mpi.\n"
		"Exit status: 0 on success, 1 on a failure (scene, device, build, file), 2 on a\n"
		"bad option.\n",
		"reference", STAGES_MAX_PATHS, STAGES_GPU_PATHS, STAGES_CPU_PATHS_PER_UNIT, STAGES_PATH_BYTES, SCENE_MAX_IMAGE_SIDE, SCENE_MAX_DEPTH, SCENE_MAX_SAMPLES, FRAMES_MAX,
		CHECKPOINT_MAX_SECONDS);
}

void cli_print_help(FILE *out)
{
	fprintf(out,
		"Usage: rtcl [OPTION]... [SCENE | MODEL]\n"
		"Ray-trace a scene with OpenCL, scheduling pixels over work-items with one of\n"
		"several kernels, and write the image. SCENE is a scene file (SCENE.md), as\n"
		"with -s; without one, the built-in 60-ball scene. MODEL is a model file\n"
		"(OBJ, PLY, STL, glTF 2.0, FBX, ...: what the Open Asset Import Library\n"
		"reads) rendered alone with its own materials, textures, camera and lights;\n"
		"without a camera, a view framed from its bounds, without lights a default\n"
		"stage (SCENE.md, \"A model file alone\").\n"
		"Scenes hold spheres, triangle meshes with their own materials, textures\n"
		"and alpha cut-outs, and planes with an optional checkerboard, lit by point\n"
		"lights, sphere lights and directional lights (soft shadows from the last\n"
		"two), shaded Whitted-style (Blinn-Phong, shadows, reflection, refraction,\n"
		"an optional Fresnel term), seen through a pinhole, a thin lens (depth of\n"
		"field) or a glTF camera, with antialiasing (--spp). Or a physically based\n"
		"path tracer (--integrator path): global illumination, emission, microfacet\n"
		"BSDFs (diffuse, GGX conductor, rough or smooth glass, glTF's principled),\n"
		"multiple importance sampling, a uniform sky or an environment map (.hdr).\n"
		"\n"
		"Examples:\n"
		"  rtcl scenes/cornell.json              a path-traced Cornell box\n"
		"  rtcl                                  the built-in 60-ball scene, dynamic "
		"kernel\n"
		"  rtcl scenes/two_balls.json -o balls.exr --size 800x600\n"
		"  rtcl scenes/models/crate.obj -o crate.png  a model alone, framed and lit\n"
		"  rtcl -k cyclic -w 8x8 --groups 25x25  the paper's cyclic geometry\n"
		"  rtcl -k naive -r 10 --stats run.json  median of 10 timed launches, as JSON\n"
		"  rtcl -t cpu -v                        on the first CPU device, saying more\n"
		"\n"
		"Scheduling:\n"
		"  -k, --kernel NAME      which work-item traces which pixel (default dynamic):\n");
	for (int i = 0; i < render_kernel_count; i++)
		fprintf(out, "                           %-9s %s\n", render_kernels[i].name,
			render_kernels[i].summary);
	print_help_after_kernels(out);
}

/* Parses the first len characters of text as a decimal number in [min, max]:
 * digits only, no sign, no spaces. Returns 0, -1 when they are not such a
 * number, or -2 when it is out of range. */
static int parse_decimal(const char *text, size_t len, long min, long max, long *value)
{
	if (len == 0)
		return -1;
	*value = 0;
	for (size_t i = 0; i < len; i++) {
		if (text[i] < '0' || text[i] > '9')
			return -1;
	}
	for (size_t i = 0; i < len; i++) {
		*value = *value * 10 + (text[i] - '0');
		if (*value > max)
			return -2;
	}
	return *value < min ? -2 : 0;
}

/* Parses "WxH" with each side in [1, max]. */
static int parse_shape(const char *option, const char *text, long max, int out[2], char *err,
		       size_t err_size)
{
	const char *x = strchr(text, 'x');
	long w, h;
	int w_status = x ? parse_decimal(text, (size_t)(x - text), 1, max, &w) : -1;
	int h_status = x ? parse_decimal(x + 1, strlen(x + 1), 1, max, &h) : -1;

	if (w_status == -1 || h_status == -1) {
		snprintf(err, err_size, "%s: expected WxH (e.g. 8x8), got \"%s\"", option,
			 quote_text(text));
		return -1;
	}
	if (w_status || h_status) {
		snprintf(err, err_size, "%s: each size must be between 1 and %ld, got %s", option,
			 max, quote_text(text));
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

	if (parse_decimal(text, strlen(text), min, max, &value)) {
		snprintf(err, err_size, "%s: expected an integer between %ld and %ld, got \"%s\"",
			 option, min, max, quote_text(text));
		return -1;
	}
	*out = (int)value;
	return 0;
}

/* Parses a number of the scene's rules (SCENE.md): finite, and 0 or of a
 * magnitude between 1e-18 and 1e18 (rtcl computes in float). Returns 0, or
 * -1 when text is not such a number. */
static int parse_scene_number(const char *text, size_t len, double *out)
{
	char buf[64], *end;

	if (len == 0 || len >= sizeof(buf) || strchr(" \t\n", text[0]))
		return -1;
	memcpy(buf, text, len);
	buf[len] = '\0';
	*out = strtod(buf, &end);
	if (*end != '\0' || !isfinite(*out))
		return -1;
	return *out == 0 || (fabs(*out) >= 1e-18 && fabs(*out) <= 1e18) ? 0 : -1;
}

/* --eye X,Y,Z and --look-at X,Y,Z: three numbers of the scene's rules. */
static int parse_point(const char *option, const char *text, double out[3], int *given,
		       char *err, size_t err_size)
{
	const char *part = text;

	for (int i = 0; i < 3; i++) {
		size_t len = strcspn(part, ",");
		if ((part[len] == ',') != (i < 2) || parse_scene_number(part, len, &out[i])) {
			snprintf(err, err_size,
				 "%s: expected X,Y,Z, three numbers each 0 or of a magnitude "
				 "between 1e-18 and 1e18 (e.g. 0,6,-24), got \"%s\"",
				 option, quote_text(text));
			return -1;
		}
		part += len + 1;
	}
	*given = 1;
	return 0;
}

/* --fov, --aperture, --focus-distance: one number of the scene's rules, with
 * what it must be (min < x < max, or min <= x with min_inclusive). */
static int parse_camera_number(const char *option, const char *text, double min, double max,
			       int min_inclusive, const char *rule, double *out, int *given,
			       char *err, size_t err_size)
{
	double v;

	if (parse_scene_number(text, strlen(text), &v) || v < min || (v == min && !min_inclusive) ||
	    v >= max) {
		snprintf(err, err_size, "%s: expected %s, got \"%s\"", option, rule,
			 quote_text(text));
		return -1;
	}
	*out = v;
	*given = 1;
	return 0;
}

/* A mesh import limit (mesh.h) from `source` (an option or an environment
 * variable): a whole number, 0 for none, at most `max`. */
static int parse_limit(const char *source, const char *text, const char *unit, long max,
		       unsigned long *out, char *err, size_t err_size)
{
	long value;

	if (parse_decimal(text, strlen(text), 0, max, &value)) {
		snprintf(err, err_size,
			 "%s: expected a whole number of %s from 0 (no limit) to %ld, got \"%s\"",
			 source, unit, max, text);
		return -1;
	}
	*out = (unsigned long)value;
	return 0;
}

/* The limits not given as options, from the environment. */
static int mesh_limits_from_environment(struct options *o, char *err, size_t err_size)
{
	const char *time = getenv(MESH_TIME_LIMIT_ENV), *memory = getenv(MESH_MEMORY_LIMIT_ENV);

	if (o->mesh_time_limit == ULONG_MAX && time &&
	    parse_limit(MESH_TIME_LIMIT_ENV, time, "seconds", MESH_TIME_LIMIT_MAX,
			&o->mesh_time_limit, err, err_size))
		return -1;
	if (o->mesh_memory_limit == ULONG_MAX && memory &&
	    parse_limit(MESH_MEMORY_LIMIT_ENV, memory, "MiB", MESH_MEMORY_LIMIT_MAX,
			&o->mesh_memory_limit, err, err_size))
		return -1;
	return 0;
}

/* Takes a file name for an option; an empty one is a usage error. */
static int take_file_name(const char *option, const char *name, const char **out, char *err,
			  size_t err_size)
{
	*out = name;
	if (name[0] != '\0')
		return 0;
	snprintf(err, err_size, "%s: the file name is empty", option);
	return -1;
}

/* --flops writes a NumPy array: its name must say so. */
static int take_flops_name(const char *name, const char **out, char *err, size_t err_size)
{
	size_t len = strlen(name);

	if (take_file_name("--flops", name, out, err, err_size))
		return -1;
	if (len > 4 && strcasecmp(name + len - 4, ".npy") == 0)
		return 0;
	snprintf(err, err_size,
		 "--flops: the file name must end in .npy (it holds a NumPy array), got \"%s\"",
		 quote_text(name));
	return -1;
}

static int check_kernel(const char *name, char *err, size_t err_size)
{
	if (strcmp(name, "reference") == 0 || render_find_kernel(name))
		return 0;
	int n = snprintf(err, err_size, "-k/--kernel: unknown kernel \"%s\" (choose from",
			 quote_text(name));
	for (int i = 0; i < render_kernel_count && n >= 0 && (size_t)n < err_size; i++)
		n += snprintf(err + n, err_size - (size_t)n, " %s,", render_kernels[i].name);
	if (n >= 0 && (size_t)n < err_size)
		snprintf(err + n, err_size - (size_t)n, " reference)");
	return -1;
}

/* Applies option c with its value arg (NULL for an option without one).
 * Returns 0, or -1 with a message; a flat switch, one case per option. */
/* One of two words: *second is set when it is the second. */
/* --aov LIST: albedo, normal and depth, comma-separated, each once. */
static int parse_aov(const char *text, int *bits, char *err, size_t err_size)
{
	const char *p = text;

	*bits = 0;
	for (;;) {
		size_t length = strcspn(p, ",");
		int kind = -1;
		for (int k = 0; k < OUTPUT_AOV_KINDS; k++)
			if (length == strlen(output_aov_kind_name(k)) &&
			    strncmp(p, output_aov_kind_name(k), length) == 0)
				kind = k;
		if (kind < 0 || (*bits & (1 << kind))) {
			snprintf(err, err_size,
				 "--aov: %s is not a list of albedo, normal and depth, each once "
				 "(e.g. --aov albedo,normal,depth)",
				 quote_text(text));
			return -1;
		}
		*bits |= 1 << kind;
		if (p[length] == '\0')
			return 0;
		p += length + 1;
	}
}

static int parse_choice(const char *option, const char *text, const char *first, const char *second,
			int *is_second, char *err, size_t err_size)
{
	if (strcmp(text, first) != 0 && strcmp(text, second) != 0) {
		snprintf(err, err_size, "%s: expected %s or %s, got \"%s\"", option, first, second,
			 quote_text(text));
		return -1;
	}
	*is_second = strcmp(text, second) == 0;
	return 0;
}

/* --fetch item|group|subgroup into *fetch (enum fetch). */
static int parse_fetch(const char *text, int *fetch, char *err, size_t err_size)
{
	static const enum fetch choices[] = {FETCH_ITEM, FETCH_GROUP, FETCH_SUBGROUP};

	for (size_t i = 0; i < sizeof(choices) / sizeof(choices[0]); i++)
		if (strcmp(text, fetch_name(choices[i])) == 0) {
			*fetch = choices[i];
			return 0;
		}
	snprintf(err, err_size, "--fetch: expected item, group or subgroup, got \"%s\"",
		 quote_text(text));
	return -1;
}

/* --split dynamic|static|samples into *split (enum split). */
static int parse_split(const char *text, int *split, char *err, size_t err_size)
{
	static const enum split choices[] = {SPLIT_DYNAMIC, SPLIT_STATIC, SPLIT_SAMPLES};

	for (size_t i = 0; i < sizeof(choices) / sizeof(choices[0]); i++)
		if (strcmp(text, split_name(choices[i])) == 0) {
			*split = choices[i];
			return 0;
		}
	snprintf(err, err_size, "--split: expected dynamic, static or samples, got \"%s\"",
		 quote_text(text));
	return -1;
}

/* --row-order interleave[:S]|scan into o (enum row_order, S). */
static int parse_row_order(const char *text, struct options *o, char *err, size_t err_size)
{
	static const char interleave[] = "interleave";
	long classes;

	o->row_classes = 0;
	if (strcmp(text, "scan") == 0) {
		o->row_order = ROWS_SCAN;
		return 0;
	}
	if (strncmp(text, interleave, sizeof(interleave) - 1) == 0) {
		const char *rest = text + sizeof(interleave) - 1;
		o->row_order = ROWS_INTERLEAVE;
		if (*rest == '\0')
			return 0;
		if (*rest == ':' && parse_decimal(rest + 1, strlen(rest + 1), 1, ROWS_CLASSES_MAX,
						  &classes) == 0) {
			o->row_classes = (int)classes;
			return 0;
		}
	}
	snprintf(err, err_size,
		 "--row-order: expected interleave, interleave:S (S classes, 1..%d) or scan, got "
		 "\"%s\"",
		 ROWS_CLASSES_MAX, quote_text(text));
	return -1;
}

/* --accel none|bvh|bvh-compact into *accel (enum accel). */
static int parse_accel(const char *text, int *accel, char *err, size_t err_size)
{
	static const int choices[] = {ACCEL_NONE, ACCEL_BVH, ACCEL_BVH_COMPACT};

	for (size_t i = 0; i < sizeof(choices) / sizeof(choices[0]); i++) {
		if (strcmp(text, accel_name(choices[i])) == 0) {
			*accel = choices[i];
			return 0;
		}
	}
	snprintf(err, err_size, "--accel: expected bvh, bvh-compact or none, got \"%s\"",
		 quote_text(text));
	return -1;
}

/* --frames A:B, 0 <= A <= B <= 99999, at most FRAMES_MAX frames. */
static int parse_frames(const char *text, int frames[2], char *err, size_t err_size)
{
	const char *colon = strchr(text, ':');
	long a, b;

	if (!colon || parse_decimal(text, (size_t)(colon - text), 0, 99999, &a) ||
	    parse_decimal(colon + 1, strlen(colon + 1), 0, 99999, &b)) {
		snprintf(err, err_size,
			 "--frames: expected A:B, frame numbers from 0 to 99999 (e.g. 1:120), "
			 "got \"%s\"",
			 quote_text(text));
		return -1;
	}
	if (b < a || b - a + 1 > FRAMES_MAX) {
		snprintf(err, err_size,
			 "--frames: the last frame must not come before the first, and at most %d "
			 "frames, got %s",
			 FRAMES_MAX, quote_text(text));
		return -1;
	}
	frames[0] = (int)a;
	frames[1] = (int)b;
	return 0;
}

/* -t/--type gpu|cpu|all, as the Khronos OpenCL SDK samples take it. */
static int parse_device_kind(const char *text, enum device_kind *kind, char *err, size_t err_size)
{
	if (strcmp(text, "gpu") == 0)
		*kind = DEVICE_KIND_GPU;
	else if (strcmp(text, "cpu") == 0)
		*kind = DEVICE_KIND_CPU;
	else if (strcmp(text, "all") == 0)
		*kind = DEVICE_KIND_ANY;
	else {
		snprintf(err, err_size, "-t/--type: expected gpu, cpu or all, got \"%s\"",
			 quote_text(text));
		return -1;
	}
	return 0;
}

static int apply_option(int c, const char *arg, struct options *o, char *err, size_t err_size)
{
	switch (c) {
	case 'k':
		o->kernel = arg;
		return check_kernel(arg, err, err_size);
	case 'w':
		return parse_shape("-w/--workgroup", arg, 65536, o->workgroup, err, err_size);
	case OPT_GROUPS:
		return parse_shape("--groups", arg, 65536, o->groups, err, err_size);
	case OPT_BATCH:
		o->batch_given = 1;
		return parse_bounded("--batch", arg, 1, 4096, &o->batch, err, err_size);
	case OPT_FETCH:
		o->fetch_given = 1;
		return parse_fetch(arg, &o->fetch, err, err_size);
	case OPT_REGENERATE:
		o->regenerate = 1;
		return 0;
	case OPT_WAVEFRONT_FORM:
		o->wavefront_form_given = 1;
		return parse_choice("--wavefront-form", arg, "bounce", "stages", &o->wavefront_stages,
				    err, err_size);
	case OPT_PATHS_IN_FLIGHT:
		return parse_bounded("--paths-in-flight", arg, 1, STAGES_MAX_PATHS,
				     &o->paths_in_flight, err, err_size);
	case OPT_QUEUES:
		return parse_bounded("--queues", arg, 1, RENDER_MAX_QUEUES, &o->queues, err,
				     err_size);
	case 's':
		return take_file_name("-s/--scene", arg, &o->scene_path, err, err_size);
	case 'o':
		return take_file_name("-o/--output", arg, &o->outputs.image, err, err_size);
	case OPT_SIZE:
		return parse_shape("--size", arg, SCENE_MAX_IMAGE_SIDE, o->size, err, err_size);
	case OPT_DEPTH:
		return parse_bounded("--depth", arg, 0, SCENE_MAX_DEPTH, &o->depth, err, err_size);
	case OPT_CHECKPOINT: {
		int seconds;
		if (parse_bounded("--checkpoint", arg, 1, CHECKPOINT_MAX_SECONDS, &seconds, err,
				  err_size))
			return -1;
		o->checkpoint_seconds = seconds;
		return 0;
	}
	case OPT_NO_PARTIAL:
		o->no_partial = 1;
		return 0;
	case OPT_SPP:
		return parse_bounded("--spp", arg, 1, SCENE_MAX_SAMPLES, &o->spp, err, err_size);
	case OPT_EYE:
		return parse_point("--eye", arg, o->camera.eye, &o->camera.eye_given, err, err_size);
	case OPT_LOOK_AT:
		return parse_point("--look-at", arg, o->camera.look_at, &o->camera.look_at_given,
				   err, err_size);
	case OPT_FOV:
		return parse_camera_number("--fov", arg, 0, 180, 0,
					   "degrees, a number greater than 0 and less than 180",
					   &o->camera.fov, &o->camera.fov_given, err, err_size);
	case OPT_APERTURE:
		return parse_camera_number("--aperture", arg, 0, HUGE_VAL, 1,
					   "the lens radius, a number >= 0 (0: a pinhole; else "
					   "between 1e-18 and 1e18)",
					   &o->camera.aperture, &o->camera.aperture_given, err,
					   err_size);
	case OPT_FOCUS_DISTANCE:
		return parse_camera_number("--focus-distance", arg, 0, HUGE_VAL, 0,
					   "a distance > 0 (between 1e-18 and 1e18)",
					   &o->camera.focus_distance, &o->camera.focus_given, err,
					   err_size);
	case 'p':
		return parse_bounded("-p/--platform", arg, 0, 1000, &o->devices.platform, err, err_size);
	case 'd':
		return parse_bounded("-d/--device", arg, 0, 1000, &o->devices.device, err, err_size);
	case 't':
		return parse_device_kind(arg, &o->devices.kind, err, err_size);
	case 'r':
		return parse_bounded("-r/--repeat", arg, 1, 100000, &o->repeat, err, err_size);
	case OPT_STATS:
		return take_file_name("--stats", arg, &o->outputs.stats, err, err_size);
	case OPT_FLOPS:
		return take_flops_name(arg, &o->outputs.flops, err, err_size);
	case OPT_WORK_MAP:
		return take_file_name("--work-map", arg, &o->outputs.work_map, err, err_size);
	case OPT_WORK_MAP_BAR:
		return take_file_name("--work-map-bar", arg, &o->outputs.work_map_bar, err, err_size);
	case OPT_SCHEDULE_MAP:
		return take_file_name("--schedule-map", arg, &o->outputs.schedule_map, err,
				      err_size);
	case OPT_WORK_MAP_SCALE:
		o->work_map_scale_given = 1;
		return parse_choice("--work-map-scale", arg, "linear", "log", &o->outputs.work_map_log, err,
				    err_size);
	case OPT_AOV:
		return parse_aov(arg, &o->outputs.aov, err, err_size);
	case OPT_DENOISE:
		o->outputs.denoise = 1;
		return 0;
	case OPT_ENCODING:
		return parse_choice("--encoding", arg, "srgb", "linear", &o->outputs.linear_encoding, err,
				    err_size);
	case OPT_DEVICES:
		o->devices.list_given = 1;
		return devices_parse(arg, &o->devices.list, err, err_size);
	case OPT_SPLIT:
		o->split_given = 1;
		return parse_split(arg, &o->split, err, err_size);
	case OPT_FRAMES:
		o->frames_given = 1;
		return parse_frames(arg, o->frames, err, err_size);
	case OPT_MPI:
		o->mpi = 1;
		return 0;
	case OPT_ACCEL:
		return parse_accel(arg, &o->accel, err, err_size);
	case OPT_INTEGRATOR:
		return parse_choice("--integrator", arg, "whitted", "path", &o->integrator, err,
				    err_size);
	case OPT_MESH_TIME_LIMIT:
		return parse_limit("--mesh-time-limit", arg, "seconds", MESH_TIME_LIMIT_MAX,
				   &o->mesh_time_limit, err, err_size);
	case OPT_MESH_MEMORY_LIMIT:
		return parse_limit("--mesh-memory-limit", arg, "MiB", MESH_MEMORY_LIMIT_MAX,
				   &o->mesh_memory_limit, err, err_size);
	case OPT_ROW_ORDER:
		o->row_order_given = 1;
		return parse_row_order(arg, o, err, err_size);
	case OPT_PIECE_ROWS:
		return parse_bounded("--piece-rows", arg, 1, SCENE_MAX_IMAGE_SIDE, &o->piece_rows,
				     err, err_size);
	case OPT_LIST_DEVICES:
		o->list_devices = 1;
		return 0;
	case 'q':
		o->quiet = 1;
		return 0;
	case 'v':
		o->verbose = 1;
		return 0;
	case 'h':
		o->help = 1;
		return 0;
	case OPT_VERSION:
		o->version = 1;
		return 0;
	}
	snprintf(err, err_size, "unknown option (see --help)");
	return -1;
}

/* The long option that arg ("--name" or "--name=value") names, getopt_long
 * taking unambiguous abbreviations, or NULL; *matches counts the candidates. */
static const struct option *find_long_option(const char *arg, int *matches)
{
	const char *name = arg + 2;
	size_t len = strcspn(name, "=");
	const struct option *found = NULL;

	*matches = 0;
	for (const struct option *opt = long_options; opt->name; opt++) {
		if (strncmp(opt->name, name, len) != 0)
			continue;
		if (strlen(opt->name) == len) {
			*matches = 1;
			return opt;
		}
		found = opt;
		(*matches)++;
	}
	return found;
}

/* Appends the long option nearest to the unknown name[len] to err. */
static void suggest_option(const char *name, int len, char *err, size_t err_size)
{
	enum { COUNT = sizeof(long_options) / sizeof(long_options[0]) - 1 };
	const char *names[COUNT];
	char word[SUGGEST_MAX_LENGTH + 1];

	if (len > SUGGEST_MAX_LENGTH)
		return;
	snprintf(word, sizeof(word), "%.*s", len, name);
	for (int i = 0; i < COUNT; i++)
		names[i] = long_options[i].name;
	suggest_append(err, err_size, word, names, COUNT, "--");
}

/* Describes the option getopt_long refused ('?') or found without its value
 * (':'). It reports a long option given a value it does not take as its
 * short form ("--quiet=1" as optopt 'q'), and does not advance optind
 * within a cluster of short options, so the argument's own text decides. */
static void describe_bad_option(int c, int argc, char **argv, char *err, size_t err_size)
{
	const char *arg = optind >= 1 && optind <= argc ? argv[optind - 1] : "";
	int is_long = strncmp(arg, "--", 2) == 0 && arg[2] != '\0';
	int matches = 0;
	const struct option *opt = is_long ? find_long_option(arg, &matches) : NULL;
	int name_len = (int)strcspn(arg, "=");

	if (is_long && opt && matches == 1 && opt->val == optopt) {
		if (c == ':')
			snprintf(err, err_size, "--%s needs a value (see --help)", opt->name);
		else
			snprintf(err, err_size, "option --%s takes no value (see --help)",
				 opt->name);
	} else if (is_long && optopt == 0) {
		char name[512];

		snprintf(name, sizeof(name), "%.*s", name_len, arg);
		snprintf(err, err_size, "%s option %s (see --help)",
			 matches > 1 ? "ambiguous" : "unknown", quote_text(name));
		if (matches == 0)
			suggest_option(arg + 2, name_len - 2, err, err_size);
	} else if (optopt > 0 && optopt < OPT_GROUPS) {
		char letter[QUOTE_BYTE_SIZE];

		snprintf(err, err_size,
			 c == ':' ? "-%s needs a value (see --help)"
				  : "unknown option -%s (see --help)",
			 quote_byte((unsigned char)optopt, 0, letter));
	} else {
		snprintf(err, err_size, "bad option %s (see --help)", quote_text(arg));
	}
}

/* One image over several devices or ranks (tiles.h): what does not apply. */
static int check_several_devices(const struct options *o, char *err, size_t err_size)
{
	int several = o->mpi || (o->devices.list_given && (o->devices.list.all || o->devices.list.count > 1));

	if (o->piece_rows && (!(o->devices.list_given || o->mpi) || o->frames_given)) {
		snprintf(err, err_size,
			 "--piece-rows cuts one image into bands for the devices of --devices or "
			 "--mpi (one device too: --devices P:D); it does not apply to %s",
			 o->frames_given ? "--frames, whose pieces are whole frames"
					 : "a render without them");
		return -1;
	}
	if (o->row_order_given && (!(o->devices.list_given || o->mpi) || o->frames_given)) {
		snprintf(err, err_size,
			 "--row-order orders the rows that pieces of one image take on the devices "
			 "of --devices or --mpi; it does not apply to %s",
			 o->frames_given ? "--frames, whose pieces are whole frames"
					 : "a render without them");
		return -1;
	}
	if (o->split_given && !(o->devices.list_given || o->mpi)) {
		snprintf(err, err_size,
			 "--split chooses how pieces go to the devices of --devices or --mpi; it "
			 "does not apply to a render without them");
		return -1;
	}
	if (o->split == SPLIT_SAMPLES && o->split_given) {
		const char *other = o->frames_given			? "--frames"
				    : o->row_order_given		? "--row-order"
				    : o->piece_rows > 0			? "--piece-rows"
				    : o->outputs.work_map		? "--work-map"
				    : o->outputs.schedule_map		? "--schedule-map"
								: NULL;
		if (other) {
			snprintf(err, err_size,
				 "--split samples renders the whole image on every device, each a "
				 "share of every pixel's samples; it does not go with %s (use "
				 "--split dynamic or static)",
				 other);
			return -1;
		}
	}
	if (several && o->outputs.flops) {
		snprintf(err, err_size,
			 "--flops writes one device's NDRange of work-items; with several devices "
			 "or --mpi use --work-map FILE.npy (per pixel) or one device");
		return -1;
	}
	if (o->mpi && !o->frames_given && (o->repeat || o->outputs.work_map)) {
		snprintf(err, err_size,
			 "--mpi renders the image once and sends only its pixels to rank 0: "
			 "-r/--repeat and --work-map need --devices in one process");
		return -1;
	}
	return 0;
}

/* --checkpoint and --no-partial: what a render stopped early keeps. */
static int check_partial(const struct options *o, char *err, size_t err_size)
{
	const char *other = o->frames_given ? "--frames (an interrupt keeps the frames finished)"
			    : o->mpi	    ? "--mpi"
			    : o->repeat	    ? "-r/--repeat, whose launches are timed"
			    : o->no_partial ? "--no-partial"
					    : NULL;

	if (o->checkpoint_seconds > 0 && other) {
		snprintf(err, err_size,
			 "--checkpoint writes the image of one render as it goes: it does not go "
			 "with %s",
			 other);
		return -1;
	}
	return 0;
}

/* --schedule-map: one launch's work-items over the whole image. */
static int check_schedule_map(const struct options *o, char *err, size_t err_size)
{
	if (!o->outputs.schedule_map)
		return 0;
	if (strcmp(o->kernel, "reference") == 0 || strcmp(o->kernel, "wavefront") == 0) {
		snprintf(err, err_size,
			 "--schedule-map records which work-item traced each pixel: %s; choose "
			 "serial, naive, cyclic, dynamic or persistent",
			 strcmp(o->kernel, "reference") == 0
				 ? "the reference renderer has none"
				 : "the wavefront's work-items take rays, not pixels, and every "
				   "bounce hands them out anew");
		return -1;
	}
	if (o->devices.list_given || o->frames_given || o->mpi) {
		snprintf(err, err_size,
			 "--schedule-map records one device's launches over the whole image: it "
			 "does not apply to %s",
			 o->frames_given ? "--frames" : o->mpi ? "--mpi" : "--devices");
		return -1;
	}
	return 0;
}

/* The rule for an option that sets something the run does not have
 * (docs/GUIDE.md, "Options that do not apply"): refused, with what it
 * needs. The kernel's options: */
static int check_kernel_options(const struct options *o, char *err, size_t err_size)
{
	const struct kernel_info *k = render_find_kernel(o->kernel); /* NULL: the reference */

	if (o->groups[0] > 0 && !(k && k->uses_groups)) {
		snprintf(err, err_size,
			 "--groups sets the persistent work-groups of -k cyclic, dynamic and "
			 "persistent; it does not apply to -k %s",
			 o->kernel);
		return -1;
	}
	if (o->batch_given && !(k && k->pixel_counter)) {
		snprintf(err, err_size,
			 "--batch sets the pixels a work-item of -k persistent fetches at a "
			 "time; it does not apply to -k %s",
			 o->kernel);
		return -1;
	}
	if ((o->fetch_given || o->regenerate) && !(k && k->pixel_counter)) {
		snprintf(err, err_size,
			 "%s sets how the work-items of -k persistent take their work; it does "
			 "not apply to -k %s",
			 o->regenerate ? "--regenerate" : "--fetch", o->kernel);
		return -1;
	}
	if (o->wavefront_form_given && !(k && k->multi_pass)) {
		snprintf(err, err_size,
			 "--wavefront-form chooses how -k wavefront splits paths; it does not "
			 "apply to -k %s",
			 o->kernel);
		return -1;
	}
	if (o->paths_in_flight > 0 && !o->wavefront_stages) {
		snprintf(err, err_size,
			 "--paths-in-flight sets the pool of paths of -k wavefront "
			 "--wavefront-form stages; it does not apply to %s%s",
			 k && k->multi_pass ? "" : "-k ",
			 k && k->multi_pass ? "the bounce form (give --wavefront-form stages)"
					    : o->kernel);
		return -1;
	}
	if (o->queues > 0 && !(k && !k->single_item && !k->multi_pass)) {
		snprintf(err, err_size,
			 "--queues sets the command queues of -k naive, cyclic, dynamic and "
			 "persistent; it does not apply to -k %s, which renders on one",
			 o->kernel);
		return -1;
	}
	return 0;
}

/* Rules between options, checked once all are read. */
static int check_combination(const struct options *o, char *err, size_t err_size)
{
	if (strcmp(o->kernel, "reference") == 0 && (o->outputs.flops || o->outputs.work_map)) {
		snprintf(err, err_size,
			 "--flops and --work-map count the OpenCL kernels' work; the reference "
			 "renderer does not count (choose an OpenCL kernel)");
		return -1;
	}
	if (o->devices.list_given && (o->devices.platform >= 0 || o->devices.device >= 0)) {
		snprintf(err, err_size,
			 "--devices and -p/-d both choose devices: give one or the other");
		return -1;
	}
	if ((o->devices.list_given || o->frames_given || o->mpi) &&
	    strcmp(o->kernel, "reference") == 0) {
		snprintf(err, err_size,
			 "--devices, --frames and --mpi render on OpenCL devices; the reference "
			 "renderer runs on the host (choose an OpenCL kernel)");
		return -1;
	}
	if (o->frames_given && (o->repeat || o->outputs.flops || o->outputs.work_map)) {
		snprintf(err, err_size,
			 "--frames renders each frame once: -r/--repeat, --flops and --work-map "
			 "do not apply");
		return -1;
	}
	if ((o->outputs.aov || o->outputs.denoise) &&
	    (strcmp(o->kernel, "reference") == 0 || o->devices.list_given || o->piece_rows ||
	     o->frames_given || o->mpi)) {
		snprintf(err, err_size,
			 "--aov and --denoise render the auxiliary images on one OpenCL device "
			 "after one image: not with -k reference, --devices, --piece-rows, "
			 "--frames or --mpi");
		return -1;
	}
	if (o->outputs.work_map_bar &&
	    (!o->outputs.work_map || workmap_kind(o->outputs.work_map) != WORKMAP_PICTURE)) {
		snprintf(err, err_size,
			 "--work-map-bar: the bar is the legend of a --work-map picture; give "
			 "--work-map an image file (not .npy, .exr, .pfm or .hdr)");
		return -1;
	}
	if (o->work_map_scale_given &&
	    (!o->outputs.work_map || workmap_kind(o->outputs.work_map) != WORKMAP_PICTURE)) {
		snprintf(err, err_size,
			 "--work-map-scale sets the colours of a --work-map picture; give "
			 "--work-map an image file (not .npy, .exr, .pfm or .hdr)");
		return -1;
	}
	if (check_kernel_options(o, err, err_size) || check_several_devices(o, err, err_size) ||
	    check_schedule_map(o, err, err_size) || check_partial(o, err, err_size))
		return -1;
	if (o->quiet && o->verbose) {
		snprintf(err, err_size, "-q/--quiet and -v/--verbose contradict each other");
		return -1;
	}
	return 0;
}

/* The scene as the one argument after the options (getopt_long moves the
 * arguments behind them): rtcl scene.json works as rtcl -s scene.json. */
static int take_scene_argument(int count, char **args, struct options *o, char *err,
			       size_t err_size)
{
	if (count == 0)
		return 0;
	if (count > 1 || o->scene_path) {
		snprintf(err, err_size,
			 "two scenes given, \"%s\" and \"%s\": give one, as the argument or with "
			 "-s/--scene",
			 quote_text(o->scene_path ? o->scene_path : args[0]),
			 quote_text(o->scene_path ? args[0] : args[1]));
		return -1;
	}
	o->scene_is_argument = 1;
	return take_file_name("the scene argument", args[0], &o->scene_path, err, err_size);
}

int cli_parse(int argc, char **argv, struct options *o, char *err, size_t err_size)
{
	int c;

	memset(o, 0, sizeof(*o));
	o->kernel = "dynamic";
	o->workgroup[0] = o->workgroup[1] = 8;
	o->outputs.image = "render.png";
	o->depth = -1;
	o->integrator = -1;
	o->devices.platform = o->devices.device = -1;
	o->repeat = 0; /* not given: one launch, no warm-up */
	o->batch = 1;
	o->accel = ACCEL_BVH;
	o->mesh_time_limit = o->mesh_memory_limit = ULONG_MAX;

	opterr = 0;
	optind = 1;
	while ((c = getopt_long(argc, argv, ":k:w:s:o:p:d:t:r:qvh", long_options, NULL)) != -1) {
		if (c == '?' || c == ':') {
			describe_bad_option(c, argc, argv, err, err_size);
			return -1;
		}
		if (apply_option(c, optarg, o, err, err_size))
			return -1;
	}
	if (take_scene_argument(argc - optind, argv + optind, o, err, err_size) ||
	    mesh_limits_from_environment(o, err, err_size))
		return -1;
	return check_combination(o, err, err_size);
}
