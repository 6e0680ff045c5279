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

/* A material's "bsdf" (SCENE.md, "A material's bsdf"): the path
 * integrator's scattering. SCENE_BSDF_NONE, a material without one, maps
 * from the Whitted fields (RENDERING.md, "The mapped BSDF"). The same numbers
 * as cl/rtcl_shared.h's RT_BSDF_*. */
enum {
	SCENE_BSDF_NONE,
	SCENE_BSDF_DIFFUSE,
	SCENE_BSDF_CONDUCTOR,
	SCENE_BSDF_DIELECTRIC,
	SCENE_BSDF_PRINCIPLED,
};

struct scene_bsdf {
	int type;		/* SCENE_BSDF_* */
	double color[3];	/* diffuse and conductor reflectance, principled base_color */
	double roughness;	/* perceptual: alpha = roughness^2 */
	double ior;		/* dielectric and principled */
	double metallic;	/* principled */
	double transmission;	/* principled */
};

struct scene_material {
	double color[3];
	double ambient;	  /* ka */
	double diffuse;	  /* kd */
	double specular;  /* ks */
	double shininess; /* Blinn-Phong exponent */
	double reflect;	  /* kr */
	double transmit;  /* kt */
	double ior;
	int fresnel; /* SCENE_FRESNEL_*: RENDERING.md, "Fresnel" */
	/* Textures (RENDERING.md, "Textures", "Alpha cut-out"), only a mesh
	 * file's material has them. 1 + an index into scene.textures, 0 for
	 * none, so that a material set to zeros has none. */
	int texture;	     /* the base colour texture */
	int alpha_texture;   /* the cut-out's alpha texture */
	double alpha_cutoff; /* > 0: hits of alpha below it are cut out; 0: none */
	double alpha_scale;  /* the factor of the texture's alpha (glTF's b.a) */
	int metallic_roughness_texture; /* the path integrator's (1 + index, 0: none) */
	int emissive_texture;
	int normal_texture;
	/* The path integrator's (SCENE.md, "Path tracing"). */
	struct scene_bsdf bsdf;
	double emission[3]; /* radiance from the front side */
};

/* A material's "fresnel" (the same numbers as cl/rtcl_shared.h's RT_FRESNEL_*). */
enum { SCENE_FRESNEL_OFF, SCENE_FRESNEL_DIELECTRIC, SCENE_FRESNEL_CONDUCTOR };

/* Whether a material of the scene has a Fresnel term. */
static inline int scene_has_fresnel(const struct scene_material *materials, int count)
{
	for (int i = 0; i < count; i++)
		if (materials[i].fresnel != SCENE_FRESNEL_OFF)
			return 1;
	return 0;
}

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

/* A texture a mesh material uses, decoded (RENDERING.md, "Textures"):
 * width × height texels, rows top first, 4 bytes each (RGB sRGB-encoded,
 * alpha linear) or with is_float 4 floats (linear). */
enum { SCENE_WRAP_REPEAT, SCENE_WRAP_CLAMP, SCENE_WRAP_MIRROR };

struct scene_texture {
	char *name; /* as the mesh file names it */
	int mesh;   /* the index of the mesh (meshes[i]) that brought it */
	int width, height;
	int is_float;
	int is_linear; /* 8-bit RGB linear numbers (metallic-roughness), not sRGB */
	int wrap_s, wrap_t; /* SCENE_WRAP_* */
	void *texels;
	size_t bytes;
};

/* A triangle's texture coordinates at its three vertices (in the vertex
 * order of scene_triangle.v). */
struct scene_triangle_uv {
	double uv[3][2];
};

/* A point light (radius 0), a sphere light (radius > 0) or a directional
 * light (docs/SCENE.md, "Lights"). */
struct scene_light {
	double position[3]; /* a point or sphere light's centre */
	double color[3];
	double radius;	     /* a sphere light's; 0: a point light */
	int directional;     /* the light is the sun: direction and angle, no position */
	double direction[3]; /* unit: the way a directional light's light travels */
	double angle;	     /* a directional light's angular radius, degrees, 0 ... < 90 */
};

struct scene_camera {
	double eye[3];
	double look_at[3];
	double up[3];
	double fov; /* vertical, degrees */
	double aperture;       /* the lens radius; 0: a pinhole */
	double focus_distance; /* > 0: camera.focus_distance, else |look_at - eye| */
	int focus_given;       /* focus_distance was given, not taken from look_at */
};

/* The camera as the command line changes it (--eye, --look-at, --fov,
 * --aperture, --focus-distance): each value replaces the scene's where its
 * flag is set. */
struct camera_override {
	int eye_given, look_at_given, fov_given, aperture_given, focus_given;
	double eye[3], look_at[3];
	double fov, aperture, focus_distance;
};

/* A file the run reads: the scene file, its mesh files, and every file those
 * read (MTL libraries, glTF buffers and images, textures), as the mesh
 * helper reports them (scene/mesh.h). No output may replace one
 * (output/plan.h). */
struct scene_input {
	char *path;	  /* as opened: a mesh file's path joined to the scene's folder */
	const char *kind; /* "scene file", "mesh file", "texture", "glTF buffer", ... */
};

/* "integrator" (SCENE.md): the same numbers as --integrator's. */
enum { SCENE_INTEGRATOR_WHITTED, SCENE_INTEGRATOR_PATH };

/* "environment" (SCENE.md, "environment"): an equirectangular map. */
struct scene_environment {
	char *file; /* as the scene names it, joined to the scene's folder; NULL: none */
	double scale;
	double rotate; /* degrees about +y */
	int width, height;
	float *rgb; /* the map's radiance (scale not applied), rows from the top */
};

struct scene {
	char *source;		    /* file name (or "name (built-in)") used in messages */
	struct scene_input *inputs; /* the scene file (none for a string), its mesh files, theirs */
	int input_count;
	int width, height;
	int samples; /* per pixel, image.samples (1 when not given) */
	struct scene_camera camera;
	double background[3];
	double ambient[3];
	int ambient_given; /* under the path integrator it is warned about */
	int max_depth;
	double epsilon;
	int integrator; /* SCENE_INTEGRATOR_*: the scene's, or --integrator's */
	struct scene_environment environment;

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
	/* Textures: the ones the materials use, and each triangle's texture
	 * coordinates (NULL when no material has a texture or a cut-out). */
	struct scene_texture *textures;
	int texture_count;
	struct scene_triangle_uv *triangle_uvs;
	/* What -v says of each mesh file that keeps its materials (SCENE.md,
	 * "Materials from mesh files"): one line each, without "rtcl: ". */
	char **mesh_reports;
	int mesh_report_count;
	/* Warnings to print whatever -v says (a texture left out under
	 * "missing_textures": "warn"): one line each, without "rtcl: warning: ". */
	char **warnings;
	int warning_count;
};

/* Whether a light of the scene is sampled (RENDERING.md, "Light samples"):
 * a sphere light of radius > 0 or a directional light. */
static inline int scene_has_area_lights(const struct scene *scene)
{
	for (int i = 0; i < scene->light_count; i++)
		if (scene->lights[i].radius > 0 || scene->lights[i].directional)
			return 1;
	return 0;
}

/* Whether material m emits (path integrator). */
static inline int scene_material_emits(const struct scene_material *m)
{
	return m->emission[0] > 0 || m->emission[1] > 0 || m->emission[2] > 0;
}

/* Whether a material of the scene has a texture or a cut-out: the device
 * then gets texture coordinates and textures (RTCL_TEXTURES). */
static inline int scene_has_textures(const struct scene *scene)
{
	for (int i = 0; i < scene->material_count; i++)
		if (scene->materials[i].texture || scene->materials[i].alpha_texture ||
		    scene->materials[i].alpha_cutoff > 0 ||
		    (scene->integrator == SCENE_INTEGRATOR_PATH &&
		     (scene->materials[i].metallic_roughness_texture ||
		      scene->materials[i].emissive_texture || scene->materials[i].normal_texture)))
			return 1;
	return 0;
}

/* The device bytes of the scene's texels (each texture's, 16-byte aligned). */
static inline size_t scene_texture_bytes(const struct scene *scene)
{
	size_t bytes = 0;

	for (int i = 0; i < scene->texture_count; i++)
		bytes += (scene->textures[i].bytes + 15) / 16 * 16;
	return bytes;
}

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

/* A model file rendered alone (docs/SCENE.md, "A model file alone";
 * scene_model.c): the image size and vertical field of view the command
 * line gives, 0 for the defaults, which the framed view is made for. */
struct model_view {
	int width, height;
	double fov;
};

/* Whether path names a model file (a mesh file the importer reads) rather
 * than an rtcl scene: not named .json, and .gltf or .glb, or not a JSON
 * object, or a glTF document (one with an "asset"). */
int scene_is_model_file(const char *path);

/* Loads the model file at path as a scene: its own materials, textures and
 * camera; where it has no camera, a view framed from its bounds; where it
 * has no light, the default stage. Returns 0, or -1 with one message in err
 * and nothing held. */
int scene_load_model(struct scene *scene, const char *path, const struct model_view *view,
		     char *err, size_t err_size);

/* What a scene file's message adds when the file is a model: "; PATH is a
 * model file ...: render it alone with ...", or "" (into out). */
const char *scene_model_hint(const char *path, char *out, size_t size);

/* Applies the command line's camera to a loaded scene, and checks the
 * camera again as the loader does (the eye and look_at must differ, up not
 * parallel to them). Returns 0, or -1 with one message naming the options
 * in err. */
int scene_override_camera(struct scene *scene, const struct camera_override *o, char *err,
			  size_t err_size);

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
