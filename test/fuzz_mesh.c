/* libFuzzer target for mesh files (issue 11): malformed OBJ and PLY inputs
 * through the scene loader, the import helper (Assimp in a process of its
 * own, built with the same sanitizers as build/fuzz/rtcl-meshread), the
 * placement and the device packing (host/scene/scene_mesh.c, host/scene/mesh_spawn.c,
 * host/meshread/meshread_assimp.c, host/layout/mesh_block.c, host/layout/scene_block.c).
 *
 * Each input is a mesh file: PLY when it starts with "ply", glTF when it
 * starts with "{", else OBJ (Assimp picks its reader by the extension). The
 * folder holds material libraries an OBJ may name (material_files), so
 * that materials and the textures they name are fuzzed too (issue 27). It is written to a private folder and
 * placed by a scene that names it. The scene must be accepted or refused
 * with one message (a crash inside Assimp is the file's fault and refuses
 * it), never crash, leak, hang or hit undefined behaviour in rtcl's code;
 * an accepted scene is packed with its BVH, as a render would, and the
 * device layout must hold only usable numbers (scene_block_check.h).
 *
 *   make fuzz-mesh FUZZ_SECONDS=600   # build/fuzz/fuzz_mesh, seeded from
 *                                     # test/meshes/ and the regressions,
 *                                     # with test/fuzz_mesh.dict (PLY counts,
 *                                     # referenced files, flat triangles)
 * Findings go to test/fuzz_mesh_regressions/ (replayed by `make test`). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "layout/scene_block.h"
#include "scene_block_check.h"
#include "scene/mesh.h"
#include "scene/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Material libraries in the fuzzer's folder (test/fuzz_mesh.dict: "mtllib
 * m.mtl"): well-formed, malformed numbers, textures outside the folder, a
 * FIFO and a device as textures. */
static const char *const material_files[][2] = {
	{"m.mtl", "newmtl m\nKd 0.9 0.1 0.1\nKs 0.5 0.5 0.5\nNs 40\nd 0.5\nNi 1.4\nillum 7\n"
		  "map_Kd t.png\nmap_d t.png\n"},
	{"bad.mtl", "newmtl m\nKd 1e400 -1 nan\nNs -1e400\nd -3\nNi 0\nillum 99\nKa inf\n"},
	{"outside.mtl", "newmtl m\nmap_Kd ../../../../etc/passwd\nmap_d /dev/zero\nbump fifo\n"
			"map_Ks missing.png\n"},
};

/* The folder for the input's file, made once per process, with FIFOs that
 * an input may name as its material library or buffer (test/fuzz_mesh.dict:
 * "mtllib fifo.mtl"): one hung the import for good (issue 24 finding 4);
 * and the material libraries above. */
static const char *fuzz_dir(void)
{
	static const char *const fifos[] = {"fifo.mtl", "fifo.bin", "fifo"};
	static char dir[] = "/tmp/rtcl-fuzz-mesh-XXXXXX";
	static int made;

	if (!made) {
		char path[128];

		if (!mkdtemp(dir))
			abort();
		for (size_t i = 0; i < sizeof(fifos) / sizeof(fifos[0]); i++) {
			snprintf(path, sizeof(path), "%s/%s", dir, fifos[i]);
			if (mkfifo(path, 0600) != 0)
				abort();
		}
		for (size_t i = 0; i < sizeof(material_files) / sizeof(material_files[0]); i++) {
			FILE *f;
			snprintf(path, sizeof(path), "%s/%s", dir, material_files[i][0]);
			f = fopen(path, "w");
			if (!f || fputs(material_files[i][1], f) < 0 || fclose(f) != 0)
				abort();
		}
	}
	made = 1;
	return dir;
}

static void write_input(const char *path, const uint8_t *data, size_t size)
{
	FILE *f = fopen(path, "wb");

	if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0)
		abort();
}

/* Packs an accepted scene as a render would; aborts unless the layout holds
 * only usable numbers. */
static void pack_and_check(const struct scene *scene)
{
	struct bvh bvh;
	struct mesh_block mesh;
	size_t bytes;

	if (bvh_build_scene(scene, BVH_TRIANGLE_COST, &bvh) || mesh_block_build(scene, &mesh))
		abort();
	/* As a GPU packs it (binary nodes), then as a CPU (four-wide). */
	for (int wide = 0; wide < 2; wide++) {
		if (wide && bvh_widen(&bvh))
			abort();
		void *packed = scene_block_pack(scene, &mesh, &bvh, 4, 4, 2, &bytes);
		if (!packed || scene_block_problem(packed))
			abort();
		free(packed);
	}
	mesh_block_free(&mesh);
	bvh_free(&bvh);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	char path[64], json[256], err[512];
	struct scene scene;
	int ply = size >= 3 && memcmp(data, "ply", 3) == 0, gltf = size >= 1 && data[0] == '{';

	/* Below libFuzzer's -timeout: an import that slow is refused, as rtcl
	 * refuses one past --mesh-time-limit. */
	mesh_set_limits(&(struct mesh_limits){.seconds = 5, .memory_mib = 0});
	snprintf(path, sizeof(path), "%s/mesh.%s", fuzz_dir(),
		 ply ? "ply" : gltf ? "gltf" : "obj");
	write_input(path, data, size);
	snprintf(json, sizeof(json),
		 "{\"format\": \"rtcl-scene\", \"version\": 2,"
		 " \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0]},"
		 " \"meshes\": [{\"file\": \"%s\"}]}",
		 path);
	if (scene_load_string(&scene, json, "fuzz.json", err, sizeof(err)) == 0) {
		pack_and_check(&scene);
		scene_free(&scene);
	} else if (strlen(err) == 0 || strchr(err, '\n')) {
		/* The contract (scene.h): on failure, one line of message. */
		abort();
	} else if (mesh_importer_failures() > 0) {
		/* Not the file's fault: the helper's sanitizers caught something
		 * in rtcl's import code, or it did not run (host/scene/mesh.h). */
		fprintf(stderr, "%s\n", err);
		abort();
	}
	unlink(path);
	return 0;
}
