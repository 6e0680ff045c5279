/* Reading a mesh file (any format the Open Asset Import Library reads: OBJ,
 * PLY, STL, glTF 2.0, ...) into one flat list of triangles, with the file's
 * own node transforms applied. Placement, normals and the checks of
 * docs/SCENE.md are the scene loader's (host/scene/scene_mesh.c).
 *
 * Assimp runs in a helper program of its own, rtcl-meshread (host/meshread/meshread.c),
 * which rtcl starts for each mesh file and which sends the mesh back through a
 * pipe (host/scene/mesh_spawn.c): Assimp 5.2 calls abort() on some malformed files
 * (found by the mesh fuzzer, test/fuzz_mesh.c), and that must end the helper,
 * never rtcl and its user's render. rtcl itself does not link Assimp. */
#ifndef RTCL_MESH_H
#define RTCL_MESH_H

#include <stddef.h>
#include <stdint.h>

/* A material of the file as the importer reads it, before rtcl's rule turns
 * it into a scene material (docs/RENDERING.md, "Materials from mesh files";
 * host/scene/mesh_material.c). Fixed-size so that it crosses the pipe as it is. */
/* Names as the importer keeps them: Assimp's aiString holds 1023 bytes
 * (issue 39: 127 cut long names, and two sharing 127 bytes became one). */
#define MESH_NAME_MAX 1024
#define MESH_NOTES_MAX 256

enum mesh_material_kind {
	MESH_MATERIAL_MISSING,		 /* the importer's stand-in for no material */
	MESH_MATERIAL_PHONG,		 /* OBJ/MTL and the other formats */
	MESH_MATERIAL_METALLIC_ROUGHNESS /* glTF 2.0 */
};

enum mesh_alpha_mode { MESH_ALPHA_OPAQUE, MESH_ALPHA_BLEND, MESH_ALPHA_MASK };

struct mesh_material {
	char name[MESH_NAME_MAX]; /* "#N" where the file gives none */
	uint32_t kind;		  /* enum mesh_material_kind */
	uint32_t illum;		  /* Phong: MTL's illumination model, 2 when not given */
	uint32_t alpha_mode;	  /* metallic-roughness: enum mesh_alpha_mode */
	uint32_t has_ior;	  /* metallic-roughness: KHR_materials_ior was given */
	uint32_t textures;	  /* base colour and opacity textures named */
	int32_t base_texture;	  /* the base colour texture (map_Kd, glTF's
				     baseColorTexture): an index into the mesh's
				     textures, or -1 */
	int32_t opacity_texture;  /* MTL's map_d: an index, or -1 */
	/* Metallic-roughness: glTF's metallicRoughnessTexture (linear: G the
	 * roughness, B the metallic factor's multiplier); any kind: the
	 * emissive texture (glTF's emissiveTexture, MTL's map_Ke). Indices, or -1. */
	int32_t metallic_roughness_texture;
	int32_t emissive_texture;
	int32_t normal_texture; /* metallic-roughness: glTF's normalTexture (linear), or -1 */
	/* Phong: Kd, Ks, Ka, Ns, d (1 - Tr), Ni. */
	double diffuse[3], specular[3], ambient[3], shininess, opacity, ior;
	/* Metallic-roughness: the base colour factor (rgba), metallic, roughness,
	 * KHR_materials_transmission's factor (0 without), alphaCutoff; ior above. */
	double base[4], metallic, roughness, transmission, alpha_cutoff;
	/* What rtcl does not understand, comma-separated: "emissive", "normal
	 * texture", an unknown property's key. */
	char not_understood[MESH_NOTES_MAX];
	/* The radiance it emits (the path integrator): glTF's emissiveFactor
	 * times KHR_materials_emissive_strength, MTL's Ke. */
	double emissive[3];
};

/* A triangle whose file gives no material index. */
#define MESH_NO_MATERIAL UINT32_MAX

/* A texture a used material names, decoded by the helper (stb_image) into
 * RGBA texels (docs/RENDERING.md, "Textures"), or why it could not be read.
 * Fixed-size but for its name, which follows the array on the pipe. */
#define MESH_TEXTURE_REASON_MAX 256
#define MESH_TEXTURE_MAX_SIDE 16384 /* texels a side */
/* The most bytes of texels one texture may take on the device (4 a texel, 16
 * for 16-bit and float images): the scene block's limit (its offsets are 32
 * bits, host/layout/scene_block.h), checked from the image's header so that
 * no image is decoded that could never render. */
#define MESH_TEXTURE_MAX_BYTES ((uint64_t)UINT32_MAX - 15)
/* The most bytes of an image file or embedded image (stb_image takes an int). */
#define MESH_TEXTURE_MAX_FILE_BYTES ((uint64_t)INT32_MAX)

enum mesh_texels {
	MESH_TEXELS_8,	  /* 4 bytes: RGB sRGB-encoded, alpha linear */
	MESH_TEXELS_FLOAT /* 4 floats, linear (16-bit and float images) */
};

/* Which channel a texture's alpha comes from, as its role asks: a base colour
 * texture's alpha is its alpha channel (1 without); an opacity texture's
 * (map_d) is its alpha channel, or its first where it has none. */
enum mesh_texture_role {
	MESH_TEXTURE_COLOR,   /* RGB sRGB-encoded, alpha its own */
	MESH_TEXTURE_OPACITY, /* the alpha, from the first channel without one */
	MESH_TEXTURE_DATA     /* RGBA linear numbers (metallic-roughness) */
};

enum mesh_wrap { MESH_WRAP_REPEAT, MESH_WRAP_CLAMP, MESH_WRAP_MIRROR };

struct mesh_texture {
	char *name; /* as the file names it, whole ("*0": embedded); malloc'd */
	char reason[MESH_TEXTURE_REASON_MAX]; /* "" when read, else why not */
	uint32_t role;			      /* enum mesh_texture_role */
	uint32_t format;		      /* enum mesh_texels */
	uint32_t width, height;
	uint32_t wrap_s, wrap_t; /* enum mesh_wrap */
	uint64_t offset, bytes;	 /* its texels in mesh_data.texels */
};

/* A camera of the file (docs/SCENE.md, "The camera from a mesh file"), in
 * the file's world space: its node's transform and those of the node's
 * parents applied. Fixed-size so that it crosses the pipe as it is. */
enum mesh_camera_kind {
	MESH_CAMERA_PERSPECTIVE,
	MESH_CAMERA_ORTHOGRAPHIC,
	MESH_CAMERA_NOT_GLTF /* a camera of another format: not read */
};

struct mesh_camera {
	char name[MESH_NAME_MAX]; /* its node's name: Assimp names a camera by its node */
	uint32_t kind;		  /* enum mesh_camera_kind */
	uint32_t pad;
	double position[3], direction[3], up[3]; /* direction and up not unit */
	double fov;				 /* vertical, degrees */
	double aspect;				 /* the file's aspect ratio; 0: not given */
};

/* A file the helper read besides the mesh file itself: rtcl counts each
 * among the run's inputs, which no output may replace (output/plan.h). */
enum mesh_file_kind {
	MESH_FILE_TEXTURE, /* an image a material names */
	MESH_FILE_LIBRARY, /* an OBJ file's MTL library */
	MESH_FILE_BUFFER,  /* a glTF buffer */
	MESH_FILE_OTHER	   /* another file the mesh file names */
};

struct mesh_file {
	char *path;    /* as the helper opened it (relative to rtcl's folder
			  unless absolute); malloc'd */
	uint32_t kind; /* enum mesh_file_kind */
};

/* A light of the file (glTF 2.0's KHR_lights_punctual, or another
 * format's), in the file's world space: its node's transform and those of
 * the node's parents applied (glTF: at the node's origin, shining down its
 * -z). Only a model rendered alone uses them (docs/SCENE.md, "A model file
 * alone"). Fixed-size so that it crosses the pipe as it is. */
enum mesh_light_kind {
	MESH_LIGHT_POINT,
	MESH_LIGHT_DIRECTIONAL,
	MESH_LIGHT_SPOT,
	MESH_LIGHT_OTHER /* an area or ambient light: not read */
};

struct mesh_light {
	char name[MESH_NAME_MAX]; /* its node's name */
	uint32_t kind;		  /* enum mesh_light_kind */
	uint32_t pad;
	double position[3], direction[3]; /* direction not unit */
	double color[3];		  /* the file's colour times its intensity */
};

struct mesh_data {
	double *positions;	      /* 3 per vertex */
	double *normals;	      /* 3 per vertex, or NULL where the file has none */
	size_t *indices;	      /* 3 per triangle, into the vertices */
	uint32_t *triangle_materials; /* 1 per triangle, into materials, or MESH_NO_MATERIAL */
	struct mesh_material *materials;
	size_t vertex_count, triangle_count, material_count;
	double *uvs; /* 2 per vertex (the first set of texture coordinates), or
			NULL where no used material has a texture */
	struct mesh_texture *textures; /* texture_count of them */
	unsigned char *texels;	       /* every read texture's texels */
	size_t texture_count, texel_bytes;
	struct mesh_camera *cameras; /* the cameras that a node of the file places */
	size_t camera_count;
	struct mesh_file *files; /* every other file the import read */
	size_t file_count;
	struct mesh_light *lights; /* the lights that a node of the file places */
	size_t light_count;
};

/* What mesh_import returns besides 0. */
enum {
	MESH_REFUSED = -1,	  /* the file's fault: unreadable, malformed, or the
				     importer died on it */
	MESH_IMPORTER_FAILED = -2 /* rtcl's: the helper is missing, could not start,
				     failed a sanitizer check or answered nonsense */
};

/* Reads `path` through the helper program. Returns 0 (triangle_count may be
 * 0: points and lines are left out), or MESH_REFUSED / MESH_IMPORTER_FAILED
 * with why in reason[reason_size]. */
int mesh_import(const char *path, struct mesh_data *out, char *reason, size_t reason_size);

/* How many mesh_import calls of this process returned MESH_IMPORTER_FAILED:
 * the fuzzers and the regression test check that none did, whatever the
 * message (which quotes the scene's words). */
unsigned long mesh_importer_failures(void);

/* The most vertices of a polygon in a mesh file (OBJ, PLY), which the
 * importer triangulates in time that grows with their square. */
#define MESH_MAX_POLYGON_VERTICES 4096

/* The helper's side: Assimp in this process. Returns 0, or -1 with the
 * importer's words in reason. (host/meshread/meshread_assimp.c, linked into rtcl-meshread only.) */
int mesh_import_here(const char *path, struct mesh_data *out, char *reason, size_t reason_size);

/* The helper's answer on fd: the mesh (mesh != NULL) or the reason it was
 * refused. Returns 0, or -1 when the pipe broke. */
int mesh_send(int fd, const struct mesh_data *mesh, const char *reason);

void mesh_data_free(struct mesh_data *mesh);

/* The limits on each import (docs/SCENE.md, "Limits of a mesh import"):
 * the helper is killed when it has not answered after `seconds`, and runs
 * with an address space of `memory_mib` MiB. 0: no limit. */
struct mesh_limits {
	unsigned long seconds;
	unsigned long memory_mib;
};
#define MESH_TIME_LIMIT_DEFAULT 60 /* seconds */
/* The memory limit's default: half the machine's physical memory. */
#define MESH_MEMORY_LIMIT_DEFAULT_SHARE 2
#define MESH_TIME_LIMIT_MAX 604800	 /* a week */
#define MESH_MEMORY_LIMIT_MAX 1073741824 /* MiB: a pebibyte */
#define MESH_TIME_LIMIT_ENV "RTCL_MESH_TIME_LIMIT"
#define MESH_MEMORY_LIMIT_ENV "RTCL_MESH_MEMORY_LIMIT"

/* The limits of later mesh_import calls, instead of the defaults. */
void mesh_set_limits(const struct mesh_limits *limits);

/* The limits in force (the defaults worked out, where not set). */
struct mesh_limits mesh_get_limits(void);

/* What an import that ran out of its memory is refused with (%lu: the
 * limit in MiB). */
#define MESH_MEMORY_MESSAGE                                                                        \
	"the import needed more memory than its limit of %lu MiB (--mesh-memory-limit "            \
	"or " MESH_MEMORY_LIMIT_ENV ")"

/* What the helper prints on stderr when it crashes near its memory limit. */
#define MESH_MEMORY_NOTE "rtcl-meshread: crashed near its memory limit"

/* The environment variable that names the helper program, overriding where
 * rtcl looks for it (host/base/libdir.h). */
#define MESH_HELPER_ENV "RTCL_MESHREAD"
#define MESH_HELPER_NAME "rtcl-meshread"

#endif
