/* Scene files (docs/SCENE.md, format versions 1 and 2).
 *
 * The loader validates everything SCENE.md asks for and fills a plain C
 * struct in double precision; the OpenCL runtime packs it into the device
 * layout of cl/rtcl_shared.h and the CPU reference renders it directly.
 */
#ifndef RTCL_SCENE_H
#define RTCL_SCENE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define SCENE_MAX_IMAGE_SIDE 32768
#define SCENE_MAX_DEPTH 64
#define SCENE_MAX_SAMPLES 65536 /* image.samples and --spp */

struct scene_material {
	double color[3];
	double ambient;	  /* ka */
	double diffuse;	  /* kd */
	double specular;  /* ks */
	double shininess; /* Blinn-Phong exponent */
	double reflect;	  /* kr */
	double transmit;  /* kt */
	double ior;
};

struct scene_sphere {
	double center[3];
	double radius;
	int material; /* index into scene.materials */
};

struct scene_plane {
	double point[3];
	double normal[3]; /* unit length (normalised on load) */
	int material;
	int has_checker;
	double checker_size;
	double checker_color[3];
};

/* A triangle of a mesh file or of the inline "triangles", placed in the
 * world. Its geometric normal is (v1 - v0) x (v2 - v0) normalised; normal[k]
 * is the unit shading normal at vertex k (the geometric normal for a flat
 * triangle). */
struct scene_triangle {
	double v[3][3];
	double normal[3][3];
	int material;
	int smooth; /* the shading normals are interpolated */
};

struct scene_light {
	double position[3];
	double color[3];
};

struct scene_camera {
	double eye[3];
	double look_at[3];
	double up[3];
	double fov; /* vertical, degrees */
};

/* A file the scene was read from. No output may replace one (output/plan.h). */
struct scene_input {
	char *path;	  /* as opened: a mesh file's path joined to the scene's folder */
	const char *kind; /* "scene file", "mesh file" */
};

struct scene {
	char *source;		    /* file name (or "name (built-in)") used in messages */
	struct scene_input *inputs; /* the scene file (none for a string) and its mesh files */
	int input_count;
	int width, height;
	int samples; /* per pixel, image.samples (1 when not given) */
	struct scene_camera camera;
	double background[3];
	double ambient[3];
	int max_depth;
	double epsilon;

	/* Named materials first, then one per inline material, then the
	 * default material if anything uses it. */
	struct scene_material *materials;
	int material_count;
	struct scene_sphere *spheres;
	int sphere_count;
	struct scene_plane *planes;
	int plane_count;
	struct scene_light *lights;
	int light_count;
	/* Version 2: the triangles of the meshes in order, then the inline ones. */
	struct scene_triangle *triangles;
	int triangle_count;
	long skipped_triangles; /* zero-area triangles of mesh files, left out */
	/* What -v says of each mesh file that keeps its materials (SCENE.md,
	 * "Materials from mesh files"): one line each, without "rtcl: ". */
	char **mesh_reports;
	int mesh_report_count;
};

/* Loads and validates a scene file. Returns 0 on success; otherwise writes
 * one message (formatted as in SCENE.md, "FILE: PATH: what is wrong" or
 * "FILE:LINE:COLUMN: what is wrong", without a trailing newline) into
 * err[err_size] and returns -1. The scene must be released with
 * scene_free() on success; on failure nothing needs releasing. */
int scene_load_file(struct scene *scene, const char *path, char *err, size_t err_size);

/* The same for a document held in memory; `name` stands for FILE in
 * messages. */
int scene_load_string(struct scene *scene, const char *json, const char *name, char *err,
		      size_t err_size);

void scene_free(struct scene *scene);

/* p relative to the camera's eye, in double: the device renders the scene
 * translated so that the eye is its origin (camera-relative rendering,
 * RENDERING.md "Coordinates on the device"), where float keeps the most
 * precision. Every world position that goes to the device goes through it. */
static inline void scene_from_eye(const struct scene *scene, const double p[3], double out[3])
{
	for (int i = 0; i < 3; i++)
		out[i] = p[i] - scene->camera.eye[i];
}

/* A 64-bit FNV-1a digest of everything in the loaded scene that its image
 * depends on: the image and camera settings and every material, sphere,
 * plane, light and triangle (the mesh files' contents, placed), field by
 * field; not the file's name. Equal scenes give equal digests on every host
 * of one byte order (--mpi ranks compare them, run/job_digest.h). */
unsigned long long scene_digest(const struct scene *scene);

/* Sets lo and hi to the world-space axis-aligned box of the scene's finite
 * objects, the spheres and triangles (planes are infinite), and returns how
 * many there are; with none, lo and hi are left as they were. */
int scene_bounds(const struct scene *scene, double lo[3], double hi[3]);

#ifdef __cplusplus
}
#endif

#endif
