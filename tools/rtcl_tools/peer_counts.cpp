// What TinyBVH's GPU layout does for rtcl's primary rays, counted on the host
// (issue 26 step 1): traversal iterations (interior nodes and leaves) and
// triangle tests per ray of BVH_GPU, TinyBVH's fastest OpenCL kernel's layout,
// built as the peer's `side` builds it (HQ: SBVH; SAH: binned), through
// BVH_GPU::Intersect, the host twin of that kernel's traversal. rtcl-peer-compare
// --counts builds this against the peer's tiny_bvh.h (g++ -I PEER) and sets it
// beside rtcl's own counts (--stats node_visits, leaf_visits, primitive_tests).
//
//   peer_counts TRIS.bin W H ex ey ez lx ly lz fov [ux uy uz]
//
// TRIS.bin: uint32 count, then count x 3 float4 vertices (the peer's ply2bin.py).
// Rays: one per pixel through its centre, rtcl's pinhole camera
// (docs/RENDERING.md, "Camera and pixels"), in float as rtcl's kernels make them.
// Prints one line per build: "<build>: iterations per ray X, triangle tests per
// ray Y, hits N, nodes M, build ms B".
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>

using tinybvh::bvhvec3;
using tinybvh::bvhvec4;

namespace {

struct camera {
	bvhvec3 eye, forward, right, up;
	float half_width, half_height;
	int width, height;
};

bvhvec3 normalized(bvhvec3 v)
{
	float length = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
	return bvhvec3(v.x / length, v.y / length, v.z / length);
}

bvhvec3 cross(bvhvec3 a, bvhvec3 b)
{
	return bvhvec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

camera make_camera(char **argv, int argc)
{
	camera c;
	c.width = std::atoi(argv[2]);
	c.height = std::atoi(argv[3]);
	c.eye = bvhvec3(std::atof(argv[4]), std::atof(argv[5]), std::atof(argv[6]));
	bvhvec3 look(std::atof(argv[7]), std::atof(argv[8]), std::atof(argv[9]));
	bvhvec3 up = argc > 13 ? bvhvec3(std::atof(argv[11]), std::atof(argv[12]),
					 std::atof(argv[13]))
			       : bvhvec3(0, 1, 0);
	float h = std::tan(std::atof(argv[10]) * 3.14159265358979 / 360.0);
	c.forward = normalized(bvhvec3(look.x - c.eye.x, look.y - c.eye.y, look.z - c.eye.z));
	c.right = normalized(cross(c.forward, up));
	c.up = cross(c.right, c.forward);
	c.half_height = h;
	c.half_width = h * (float)c.width / (float)c.height;
	return c;
}

tinybvh::Ray primary_ray(const camera &c, int x, int y)
{
	float sx = (2.0f * ((float)x + 0.5f) / (float)c.width - 1.0f) * c.half_width;
	float sy = (1.0f - 2.0f * ((float)y + 0.5f) / (float)c.height) * c.half_height;
	bvhvec3 d(c.forward.x + sx * c.right.x + sy * c.up.x,
		  c.forward.y + sx * c.right.y + sy * c.up.y,
		  c.forward.z + sx * c.right.z + sy * c.up.z);
	return tinybvh::Ray(c.eye, d);
}

// Returns Intersect's cost summed over every pixel's ray, on every hardware
// thread (rows interleaved); *hits: the rays that hit a triangle.
double total_cost(tinybvh::BVH_GPU &bvh, const camera &c, long long *hits)
{
	unsigned threads = std::max(1u, std::thread::hardware_concurrency());
	std::vector<double> cost(threads, 0.0);
	std::vector<long long> hit(threads, 0);
	std::vector<std::thread> pool;
	for (unsigned t = 0; t < threads; t++)
		pool.emplace_back([&, t] {
			for (int y = (int)t; y < c.height; y += (int)threads)
				for (int x = 0; x < c.width; x++) {
					tinybvh::Ray ray = primary_ray(c, x, y);
					cost[t] += bvh.Intersect(ray);
					hit[t] += ray.hit.t < BVH_FAR;
				}
		});
	for (auto &thread : pool)
		thread.join();
	double all = 0;
	*hits = 0;
	for (unsigned t = 0; t < threads; t++)
		all += cost[t], *hits += hit[t];
	return all;
}

void report(const char *name, tinybvh::BVH_GPU &bvh, double build_ms, const camera &c)
{
	double rays = (double)c.width * c.height;
	long long hits = 0;
	// Intersect's cost is c_trav a loop iteration and c_int a triangle test.
	bvh.c_trav = 1, bvh.c_int = 0;
	double iterations = total_cost(bvh, c, &hits);
	bvh.c_trav = 0, bvh.c_int = 1;
	double tests = total_cost(bvh, c, &hits);
	std::printf("%s: iterations per ray %.4f, triangle tests per ray %.4f, hits %lld, "
		    "nodes %u, build ms %.0f\n",
		    name, iterations / rays, tests / rays, hits, bvh.usedNodes, build_ms);
	std::fflush(stdout);
}

} // namespace

int main(int argc, char **argv)
{
	if (argc != 11 && argc != 14) {
		std::fprintf(stderr, "usage: peer_counts TRIS.bin W H ex ey ez lx ly lz fov "
				     "[ux uy uz]\n");
		return 2;
	}
	FILE *file = std::fopen(argv[1], "rb");
	uint32_t count = 0;
	if (!file || std::fread(&count, 4, 1, file) != 1 || count == 0) {
		std::fprintf(stderr, "peer_counts: %s: cannot read a triangle count\n", argv[1]);
		return 1;
	}
	std::vector<bvhvec4> tris((size_t)count * 3);
	if (std::fread(tris.data(), 16, tris.size(), file) != tris.size()) {
		std::fprintf(stderr, "peer_counts: %s: fewer than %u triangles\n", argv[1], count);
		return 1;
	}
	std::fclose(file);
	camera c = make_camera(argv, argc);
	if (c.width < 1 || c.height < 1) {
		std::fprintf(stderr, "peer_counts: the image size must be positive\n");
		return 2;
	}
	std::printf("triangles %u, rays %d\n", count, c.width * c.height);
	using clock = std::chrono::steady_clock;
	{
		auto start = clock::now();
		tinybvh::BVH_GPU bvh;
		bvh.BuildHQ(tris.data(), count);
		double ms = std::chrono::duration<double, std::milli>(clock::now() - start).count();
		report("BVH_GPU HQ", bvh, ms, c);
	}
	{
		auto start = clock::now();
		tinybvh::BVH_GPU bvh;
		bvh.Build(tris.data(), count);
		double ms = std::chrono::duration<double, std::milli>(clock::now() - start).count();
		report("BVH_GPU SAH", bvh, ms, c);
	}
	return 0;
}
