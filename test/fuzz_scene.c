/* libFuzzer target for the scene loader, its validation and the packing into
 * the device layout (host/scene/scene.c, host/layout/scene_block.c).
 *
 * Each input is loaded as a NUL-terminated document: it must be accepted or
 * refused with one message, never crash, leak, hang or hit undefined
 * behaviour. An accepted scene is also packed, as render.c would pack it,
 * and the device layout must hold only usable numbers (scene_block_check.h).
 *
 *   make fuzz FUZZ_SECONDS=600    # build/fuzz/fuzz_scene, seeded from scenes/,
 *                                 # test/bad_scenes/ and the committed corpus
 * Findings go to test/fuzz_regressions/, small interesting inputs to
 * test/fuzz_corpus/; test_fuzz_regressions.c replays both in `make test`.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "layout/scene_block.h"
#include "scene_block_check.h"
#include "scene/mesh.h"
#include "scene/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	char *json = malloc(size + 1);
	char err[512];
	struct scene scene;

	if (!json)
		return 0;
	memcpy(json, data, size);
	json[size] = '\0';

	if (scene_load_string(&scene, json, "fuzz.json", err, sizeof(err)) == 0) {
		size_t bytes;
		struct bvh bvh;
		struct mesh_block mesh;
		if (bvh_build_scene(&scene, BVH_TRIANGLE_COST, &bvh) ||
		    mesh_block_build(&scene, &mesh))
			abort();
		/* As a GPU packs it (binary nodes), then as a CPU (four-wide). */
		for (int wide = 0; wide < 2; wide++) {
			if (wide && bvh_widen(&bvh))
				abort();
			void *packed = scene_block_pack(&scene, &mesh, &bvh, scene.width,
							scene.height, scene.max_depth, &bytes);
			if (!packed || scene_block_problem(packed))
				abort();
			free(packed);
		}
		bvh_free(&bvh);
		mesh_block_free(&mesh);
		scene_free(&scene);
	} else if (strlen(err) == 0 || strchr(err, '\n') || scene.source || scene.materials ||
		   scene.spheres || scene.planes || scene.lights) {
		/* The contract (scene.h): on failure one line of message, and
		 * nothing left to release. */
		abort();
	} else if (mesh_importer_failures() > 0) {
		/* The helper's sanitizers caught something (host/scene/mesh.h). */
		fprintf(stderr, "%s\n", err);
		abort();
	}
	free(json);
	return 0;
}
