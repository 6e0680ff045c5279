/* A model file rendered alone (docs/SCENE.md, "A model file alone"): the
 * scene of one mesh entry with the file's own materials, textures and
 * camera; where the file has no camera, a view framed from its bounds, and
 * where it has no light, the default stage (a light rig and a floor). */
#include <ctype.h>
#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "base/files.h"
#include "base/quote.h"
#include "scene/scene.h"
#include "scene/scene_loader.h"

#define PI 3.14159265358979323846

/* The image of a model when the command line gives none: large enough to
 * keep, a few samples against jagged edges. */
#define MODEL_WIDTH 800
#define MODEL_HEIGHT 600
#define MODEL_SAMPLES 4

/* The framed view: the eye looks at the centre of the model's box from
 * 45 degrees to the right of its front (+z) and 30 degrees above, far
 * enough that the box's bounding sphere fills MODEL_FILL of the narrower
 * field of view (vertical or horizontal). */
#define MODEL_AZIMUTH_DEG 45.0
#define MODEL_ELEVATION_DEG 30.0
#define MODEL_FILL 0.9

/* What the first bytes of a file say it is. */
#define SNIFF_BYTES 65536

static int has_extension(const char *path, const char *ext)
{
	return strcasecmp(files_extension(path), ext) == 0;
}

int scene_is_model_file(const char *path)
{
	char buf[SNIFF_BYTES + 1];
	size_t n, i = 0;
	struct stat st;
	FILE *file;

	if (has_extension(path, ".json"))
		return 0;
	if (has_extension(path, ".gltf") || has_extension(path, ".glb"))
		return 1;
	/* Not a regular file (a FIFO would block the open): the scene loader
	 * says what it is. */
	if (stat(path, &st) != 0 || !S_ISREG(st.st_mode))
		return 0;
	file = fopen(path, "rb");
	if (!file)
		return 0; /* the scene loader says why it cannot be read */
	n = fread(buf, 1, SNIFF_BYTES, file);
	fclose(file);
	buf[n] = '\0';
	if (n >= 3 && memcmp(buf, "\xef\xbb\xbf", 3) == 0)
		i = 3;
	while (i < n && isspace((unsigned char)buf[i]))
		i++;
	if (i == n)
		return 0; /* empty: the scene loader's message */
	if (buf[i] != '{')
		return 1; /* not a JSON object: the importer's to read */
	/* A JSON object: glTF's has an "asset" (glTF 2.0 requires it). */
	return strstr(buf + i, "\"asset\"") && !strstr(buf + i, "\"rtcl-scene\"");
}

const char *scene_model_hint(const char *path, char *out, size_t size)
{
	if (!scene_is_model_file(path) || has_extension(path, ".json")) {
		out[0] = '\0';
		return out;
	}
	snprintf(out, size,
		 "; %s is a model file, not an rtcl scene: render it alone with \"rtcl %s\", "
		 "or place it in a scene's \"meshes\" (SCENE.md)",
		 quote_text(path), quote_text(path));
	return out;
}

static void unit(double v[3])
{
	double length = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);

	for (int i = 0; i < 3; i++)
		v[i] /= length;
}

static void cross(const double a[3], const double b[3], double out[3])
{
	out[0] = a[1] * b[2] - a[2] * b[1];
	out[1] = a[2] * b[0] - a[0] * b[2];
	out[2] = a[0] * b[1] - a[1] * b[0];
}

/* The view framed from the model's bounds (MODEL_* above). */
static void frame_view(struct scene *s, const double lo[3], const double hi[3], double aspect,
		       double fov)
{
	struct scene_camera *cam = &s->camera;
	double radius = 0, centre[3], to_eye[3];
	double azimuth = MODEL_AZIMUTH_DEG * PI / 180, elevation = MODEL_ELEVATION_DEG * PI / 180;
	double half_v = fov * PI / 360, half_h = atan(tan(half_v) * aspect);
	double half = half_v < half_h ? half_v : half_h;

	for (int i = 0; i < 3; i++) {
		centre[i] = (lo[i] + hi[i]) / 2;
		radius += (hi[i] - lo[i]) * (hi[i] - lo[i]) / 4;
	}
	radius = radius > 0 ? sqrt(radius) : 1;
	/* The sphere seen under an angle of asin(radius / distance) from its
	 * centre's direction: that is MODEL_FILL of the half field of view. */
	double distance = radius / sin(MODEL_FILL * half);

	to_eye[0] = cos(elevation) * sin(azimuth);
	to_eye[1] = sin(elevation);
	to_eye[2] = cos(elevation) * cos(azimuth);
	for (int i = 0; i < 3; i++) {
		cam->eye[i] = centre[i] + distance * to_eye[i];
		cam->look_at[i] = centre[i];
		cam->up[i] = i == 1;
	}
	cam->fov = fov;
	loader_default_focus(cam);
}

/* Appends n zeroed entries of `size` bytes to *array of *count; returns the
 * first, or NULL when out of memory. */
static void *grow(void **array, int *count, int n, size_t size)
{
	char *grown = realloc(*array, (size_t)(*count + n) * size);

	if (!grown)
		return NULL;
	*array = grown;
	memset(grown + (size_t)*count * size, 0, (size_t)n * size);
	*count += n;
	return grown + (size_t)(*count - n) * size;
}

/* The default stage of a model without lights, for the Whitted renderer:
 * three directional lights placed about the view (a key light from above
 * the camera's left, a fill light from its right, a rim light from behind),
 * so that the model is lit whatever its size, and a grey floor under its
 * box that takes its shadows. The path tracer (cl/, to come) will light such
 * a model with a sky environment instead: this is the place to choose by
 * renderer. */
static int add_default_stage(struct scene *s, const double lo[3], const double hi[3])
{
	static const struct {
		double toward_camera, up, right; /* where the light comes from */
		double color, angle;
	} rig[] = {
		{0.5, 0.8, -0.6, 0.75, 2.0}, /* key */
		{0.6, 0.1, 0.8, 0.30, 0.0},  /* fill */
		{-0.8, 0.6, 0.0, 0.35, 0.0}, /* rim */
	};
	const struct scene_camera *cam = &s->camera;
	double forward[3], right[3], up[3], size = 0;
	int n = (int)(sizeof(rig) / sizeof(rig[0]));
	struct scene_light *lights = grow((void **)&s->lights, &s->light_count, n, sizeof(*lights));

	if (!lights)
		return -1;
	for (int i = 0; i < 3; i++)
		forward[i] = cam->look_at[i] - cam->eye[i];
	unit(forward);
	cross(forward, cam->up, right);
	unit(right);
	cross(right, forward, up);
	for (int k = 0; k < n; k++) {
		struct scene_light *l = &lights[k];
		for (int i = 0; i < 3; i++) {
			/* The way the light travels: from where it comes. */
			l->direction[i] = -(-rig[k].toward_camera * forward[i] + rig[k].up * up[i] +
					    rig[k].right * right[i]);
			l->color[i] = rig[k].color;
		}
		unit(l->direction);
		l->directional = 1;
		l->angle = rig[k].angle;
	}

	/* The floor: the plane y = the box's bottom, a checkerboard of squares
	 * a quarter of the box's largest side. */
	for (int i = 0; i < 3; i++)
		size = hi[i] - lo[i] > size ? hi[i] - lo[i] : size;
	struct scene_material floor = {.color = {0.55, 0.55, 0.55},
				       .ambient = 1,
				       .diffuse = 0.8,
				       .specular = 0.1,
				       .shininess = 16,
				       .ior = 1.5};
	struct scene_material *m = grow((void **)&s->materials, &s->material_count, 1, sizeof(*m));
	struct scene_plane *plane =
		m ? grow((void **)&s->planes, &s->plane_count, 1, sizeof(*plane)) : NULL;
	if (!plane)
		return -1;
	*m = floor;
	plane->point[1] = lo[1];
	plane->normal[1] = 1;
	plane->material = s->material_count - 1;
	plane->has_checker = size > 0;
	plane->checker_size = size > 0 ? size / 4 : 1;
	for (int i = 0; i < 3; i++)
		plane->checker_color[i] = 0.45;
	return 0;
}

/* Appends what -v says of the model to scene->mesh_reports. */
static int report(struct scene *s, const char *fmt, ...)
{
	char line[1024];
	va_list args;
	char **grown =
		realloc(s->mesh_reports, (size_t)(s->mesh_report_count + 1) * sizeof(*grown));

	if (!grown)
		return -1;
	s->mesh_reports = grown;
	va_start(args, fmt);
	vsnprintf(line, sizeof(line), fmt, args);
	va_end(args);
	grown[s->mesh_report_count] = strdup(line);
	if (!grown[s->mesh_report_count])
		return -1;
	s->mesh_report_count++;
	return 0;
}

/* The file's own lights (scene_mesh.c took them, with the file's colours
 * times intensities): rtcl's lights do not fall off and it has no exposure,
 * so a point or spot light of intensity I (candela in glTF) at distance d
 * from the model's centre gets I / d^2, what it gives the centre with
 * glTF's inverse-square falloff, and then every light is scaled by one
 * factor so that the strongest channel of the strongest light is 1: the
 * file's colours and relative strengths are kept. */
static void scale_file_lights(struct scene *s, const double centre[3])
{
	double strongest = 0;

	for (int i = 0; i < s->light_count; i++) {
		struct scene_light *l = &s->lights[i];
		double d2 = 0;
		for (int k = 0; !l->directional && k < 3; k++)
			d2 += (l->position[k] - centre[k]) * (l->position[k] - centre[k]);
		for (int k = 0; k < 3; k++) {
			if (d2 > 0)
				l->color[k] /= d2;
			strongest = l->color[k] > strongest ? l->color[k] : strongest;
		}
	}
	for (int i = 0; i < s->light_count; i++)
		for (int k = 0; k < 3; k++) {
			double *c = &s->lights[i].color[k];
			*c = strongest > 0 ? *c / strongest : 0;
			if (*c < SCENE_MIN_MAGNITUDE) /* what the scene rules allow */
				*c = 0;
		}
}

/* A model's messages name the file, not the mesh entry rtcl made of it:
 * "m.obj: meshes[0].file: cannot read ..." becomes "m.obj: cannot read ...". */
static void drop_entry_path(char *err)
{
	static const char *const entry[] = {
		"meshes[0].file: ", "meshes[0].camera: ", "meshes[0]: "};

	for (size_t i = 0; i < sizeof(entry) / sizeof(entry[0]); i++) {
		char *at = strstr(err, entry[i]);
		if (at) {
			memmove(at, at + strlen(entry[i]), strlen(at + strlen(entry[i])) + 1);
			return;
		}
	}
}

int scene_load_model(struct scene *scene, const char *path, const struct model_view *view,
		     char *err, size_t err_size)
{
	int width = view && view->width ? view->width : MODEL_WIDTH;
	int height = view && view->height ? view->height : MODEL_HEIGHT;
	double fov = view && view->fov > 0 ? view->fov : 45;
	json_t *doc = json_pack("{s:s, s:i, s:{s:i, s:i, s:i}, s:[{s:s}]}", "format", "rtcl-scene",
				"version", 2, "image", "width", MODEL_WIDTH, "height", MODEL_HEIGHT,
				"samples", MODEL_SAMPLES, "meshes", "file", path);
	char *text = doc ? json_dumps(doc, JSON_COMPACT) : NULL;
	double lo[3], hi[3];
	int ret;

	json_decref(doc);
	memset(scene, 0, sizeof(*scene));
	if (!text) {
		snprintf(err, err_size, "%s: out of memory", quote_text(path));
		return -1;
	}
	ret = loader_load_buffer(scene, text, strlen(text), path, NULL, 1, err, err_size);
	free(text);
	if (ret) {
		drop_entry_path(err);
		return -1;
	}
	scene_bounds(scene, lo, hi); /* a model holds triangles: the loader checked */
	for (int i = 0; i < 3; i++)
		scene->background[i] = 0.4 + 0.05 * i; /* a grey-blue backdrop */
	/* No camera of the file's: eye and look_at still 0. */
	int framed = memcmp(scene->camera.eye, scene->camera.look_at, sizeof(lo)) == 0;
	if (framed)
		frame_view(scene, lo, hi, (double)width / height, fov);
	const struct scene_camera *c = &scene->camera;
	if (scene->light_count > 0) {
		double centre[3];
		for (int i = 0; i < 3; i++)
			centre[i] = (lo[i] + hi[i]) / 2;
		scale_file_lights(scene, centre);
		if (report(scene,
			   "model %s: %d light%s of its own, scaled together so that the strongest "
			   "is 1 (a point light's intensity as it reaches the model's centre)",
			   quote_text(path), scene->light_count,
			   scene->light_count == 1 ? "" : "s"))
			goto out_of_memory;
	}
	if ((framed && report(scene,
			      "model %s: no camera of its own: the view framed from its bounds, "
			      "eye [%g, %g, %g], look_at [%g, %g, %g], fov %g",
			      quote_text(path), c->eye[0], c->eye[1], c->eye[2], c->look_at[0],
			      c->look_at[1], c->look_at[2], c->fov)) ||
	    (scene->light_count == 0 &&
	     (add_default_stage(scene, lo, hi) ||
	      report(scene,
		     "model %s: no light of its own: the default stage, 3 directional lights "
		     "about the view and a floor at y = %g",
		     quote_text(path), lo[1]))))
		goto out_of_memory;
	return 0;

out_of_memory:
	snprintf(err, err_size, "%s: out of memory", quote_text(path));
	scene_free(scene);
	return -1;
}
