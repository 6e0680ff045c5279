/* The stages form's host rules (host/render/stages.c; docs/wavefront.md,
 * "The pool's default"). */
#include <criterion/criterion.h>

#include "device/device.h"
#include "render/stages.h"

#define GIB (1ULL << 30)

static struct device device_of(int is_gpu, int units, unsigned long long memory)
{
	struct device d = {0};

	d.is_gpu = is_gpu;
	d.compute_units = (cl_uint)units;
	d.global_mem_size = memory;
	d.max_alloc_size = memory / 4; /* NVIDIA's and PoCL's fraction */
	return d;
}

Test(stages, the_default_pool_is_4m_paths_on_a_gpu_with_room)
{
	struct device h100 = device_of(1, 132, 80 * GIB);

	cr_assert_eq(stages_default_paths(&h100, 1ULL << 40), 1u << 22);
	/* never more than the render's paths */
	cr_assert_eq(stages_default_paths(&h100, 1000), 1000u);
}

Test(stages, the_default_pool_on_a_cpu_is_32k_paths_a_compute_unit)
{
	struct device cpu = device_of(0, 2, 24 * GIB);

	cr_assert_eq(stages_default_paths(&cpu, 1ULL << 40), 65536u);
	struct device big = device_of(0, 256, 512 * GIB);
	cr_assert_eq(stages_default_paths(&big, 1ULL << 40), 1u << 22, "capped as a GPU's");
}

Test(stages, the_default_pool_halves_to_fit_an_eighth_of_the_memory)
{
	/* 2 GiB: an eighth is 256 MiB, 196 bytes a path: 2^20 paths (196 MiB). */
	struct device small = device_of(1, 16, 2 * GIB);

	cr_assert_eq(stages_default_paths(&small, 1ULL << 40), 1u << 20);
	/* the state buffer within the largest allocation even where an eighth
	   of the memory would hold it */
	small.max_alloc_size = 64ULL << 20; /* 2^18 paths of 160 bytes: 40 MiB */
	cr_assert_eq(stages_default_paths(&small, 1ULL << 40), 1u << 18);
	/* and never below 2^14, which --paths-in-flight can still lower */
	struct device tiny = device_of(1, 1, 16ULL << 20);
	cr_assert_eq(stages_default_paths(&tiny, 1ULL << 40), 1u << 14);
}
