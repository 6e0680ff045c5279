// The peer's GPU traversals (TinyBVH's OpenCL kernels) over a ray file of
// rtcl-peer-compare --rays (peer_rays.cpp makes them; docs/bvh.md, "Incoherent
// rays against TinyBVH"). Built against the peer's folder, run from a folder
// that holds the peer's .cl files and peer_rays.cl (tiny_ocl loads kernels
// from the working directory):
//   g++ -O3 -march=x86-64-v3 -std=c++20 -I PEER -I/usr/include/CL peer_rays_gpu.cpp -o peer_rays_gpu -lOpenCL -lpthread
// usage: peer_rays_gpu TRIS.bin RAYS HITS [passes [variants]]
// variants: letters of a (BVH_GPU HQ), A (BVH_GPU SAH), q (BVH4_GPU HQ),
// c (CWBVH HQ), C (CWBVH SAH), as the peer's side.cpp; default aAc.
// Closest-hit files go through TinyBVH's batch_* kernels (t_max 1e30, the
// file's), any-hit files through peer_rays.cl's occluded_* kernels (each
// ray's t_max). Each variant: one untimed launch, then `passes` (default 10)
// timed by OpenCL profiling events; median and min. HITS: the first
// variant's hits in rtcl-rays's layout (float t, int32 triangle; t 0 and -1
// for none; for any-hit files t 1 when occluded and triangle -1; the
// triangle only from BVH_GPU, else -1).
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"
#define TINY_OCL_IMPLEMENTATION
#include "tiny_ocl.h"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>
using namespace tinybvh;

static double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

struct GpuRay { float O[4], D[4], rD[4], hit[4]; }; // traverse.cl's struct Ray

template <class F> static std::vector<double> timed(tinyocl::Kernel& k, unsigned n, int passes, tinyocl::Buffer& rays, const std::vector<GpuRay>& fresh, F setargs)
{
	setargs();
	std::vector<double> ms;
	for (int p = 0; p < passes + 1; p++) {
		memcpy(rays.GetHostPtr(), fresh.data(), fresh.size() * sizeof(GpuRay));
		rays.CopyToDevice();
		cl_event ev; cl_ulong a, b;
		k.Run(n, 64, 0, &ev);
		clWaitForEvents(1, &ev);
		clGetEventProfilingInfo(ev, CL_PROFILING_COMMAND_START, sizeof a, &a, 0);
		clGetEventProfilingInfo(ev, CL_PROFILING_COMMAND_END, sizeof b, &b, 0);
		if (p) ms.push_back((b - a) * 1e-6);
	}
	std::sort(ms.begin(), ms.end());
	return ms;
}

int main(int argc, char** argv)
{
	if (argc < 4) { fprintf(stderr, "usage: peer_rays_gpu TRIS.bin RAYS HITS [passes [variants]]\n"); return 2; }
	FILE* f = fopen(argv[1], "rb"); if (!f) { perror(argv[1]); return 1; }
	uint32_t ntri; if (fread(&ntri, 4, 1, f) != 1) return 1;
	bvhvec4* tris = (bvhvec4*)tinybvh::malloc64((size_t)ntri * 3 * sizeof(bvhvec4));
	if (fread(tris, 16, (size_t)ntri * 3, f) != (size_t)ntri * 3) { fprintf(stderr, "short file\n"); return 1; }
	fclose(f);
	f = fopen(argv[2], "rb"); char magic[8]; uint32_t N, flags;
	if (!f || fread(magic, 1, 8, f) != 8 || memcmp(magic, "RTCLRAY1", 8) || fread(&N, 4, 1, f) != 1 || fread(&flags, 4, 1, f) != 1) { fprintf(stderr, "%s: not a ray file\n", argv[2]); return 1; }
	std::vector<float> file((size_t)N * 8);
	if (fread(file.data(), 4, file.size(), f) != file.size()) { fprintf(stderr, "%s: short\n", argv[2]); return 1; }
	fclose(f);
	int passes = argc > 4 ? atoi(argv[4]) : 10; const char* vars = argc > 5 ? argv[5] : "aAc";
	bool any = flags & 1;
	unsigned Npad = (N + 63) / 64 * 64;
	std::vector<GpuRay> fresh(Npad);
	for (unsigned i = 0; i < Npad; i++) {
		const float* r = &file[8 * (size_t)std::min(i, N - 1)]; // padding: the last ray again (closest-hit kernels check no count)
		GpuRay& g = fresh[i];
		float d[3] = {r[4], r[5], r[6]};
		for (int k = 0; k < 3; k++) { g.O[k] = r[k]; g.D[k] = d[k]; g.rD[k] = 1.0f / d[k]; }
		g.O[3] = r[3]; g.D[3] = 0; g.rD[3] = 0; g.hit[0] = 1e30f; g.hit[1] = g.hit[2] = g.hit[3] = 0;
	}
	tinyocl::Kernel ailalaine(any ? "peer_rays.cl" : "traverse.cl", any ? "occluded_ailalaine" : "batch_ailalaine");
	tinyocl::Kernel gpu4way(any ? "peer_rays.cl" : "traverse.cl", any ? "occluded_gpu4way" : "batch_gpu4way");
	tinyocl::Kernel cwbvh_k(any ? "peer_rays.cl" : "traverse.cl", any ? "occluded_cwbvh" : "batch_cwbvh");
	tinyocl::Buffer rays(Npad * 64);
	GpuRay* host = (GpuRay*)rays.GetHostPtr();
	printf("triangles %u, %u %s rays, %d timed passes (median, min)\n", ntri, N, any ? "any-hit" : "closest-hit", passes);
	std::vector<float> out; bool written = false;
	auto report = [&](const char* name, double build, std::vector<double> ms, bool with_prim) {
		rays.CopyFromDevice();
		unsigned c = 0;
		for (unsigned j = 0; j < N; j++) c += any ? host[j].hit[0] > 0.5f : host[j].hit[0] < file[8 * (size_t)j + 3];
		printf("%-28s build %8.1f ms  trace median %.4f ms  min %.4f ms  -> %.0f Mrays/s\n   hits %u\n", name, build, ms[ms.size() / 2], ms[0], N / (ms[ms.size() / 2] * 1e-3) * 1e-6, c);
		if (written) return;
		out.resize((size_t)N * 2);
		for (unsigned j = 0; j < N; j++) {
			bool h = any ? host[j].hit[0] > 0.5f : host[j].hit[0] < file[8 * (size_t)j + 3];
			int32_t prim = h && !any && with_prim ? (int32_t)*(uint32_t*)&host[j].hit[3] : -1;
			out[2 * j] = h ? (any ? 1.0f : host[j].hit[0]) : 0.0f;
			memcpy(&out[2 * j + 1], &prim, 4);
		}
		written = true;
	};
	for (const char* v = vars; *v; v++) {
		if (*v == 'a' || *v == 'A') {
			double t0 = now(); BVH_GPU b; if (*v == 'a') b.BuildHQ(tris, ntri); else b.Build(tris, ntri); double bt = (now() - t0) * 1e3;
			tinyocl::Buffer nodes(b.usedNodes * sizeof(BVH_GPU::BVHNode), b.bvhNode), idx(b.idxCount * 4, b.bvh.primIdx), tri(ntri * 3 * 16, tris);
			nodes.CopyToDevice(); idx.CopyToDevice(); tri.CopyToDevice();
			auto ms = timed(ailalaine, Npad, passes, rays, fresh, [&] { if (any) ailalaine.SetArguments(&nodes, &idx, &tri, &rays, N); else ailalaine.SetArguments(&nodes, &idx, &tri, &rays); });
			report(*v == 'a' ? "BVH_GPU (Aila-Laine, HQ)" : "BVH_GPU (Aila-Laine, SAH)", bt, ms, true);
		} else if (*v == 'q') {
			double t0 = now(); BVH4_GPU b; b.BuildHQ(tris, ntri); double bt = (now() - t0) * 1e3;
			tinyocl::Buffer nodes(b.usedBlocks * sizeof(bvhvec4), b.bvh4Data); nodes.CopyToDevice();
			auto ms = timed(gpu4way, Npad, passes, rays, fresh, [&] { if (any) gpu4way.SetArguments(&nodes, &rays, N); else gpu4way.SetArguments(&nodes, &rays); });
			report("BVH4_GPU (HQ)", bt, ms, false);
		} else if (*v == 'c' || *v == 'C') {
			double t0 = now(); BVH8_CWBVH b; if (*v == 'c') b.BuildHQ(tris, ntri); else b.Build(tris, ntri); double bt = (now() - t0) * 1e3;
#ifdef CWBVH_COMPRESSED_TRIS
			tinyocl::Buffer tb(b.idxCount * 4 * sizeof(bvhvec4), b.bvh8Tris);
#else
			tinyocl::Buffer tb(b.idxCount * 3 * sizeof(bvhvec4), b.bvh8Tris);
#endif
			tinyocl::Buffer nodes(b.usedBlocks * sizeof(bvhvec4), b.bvh8Data); nodes.CopyToDevice(); tb.CopyToDevice();
			auto ms = timed(cwbvh_k, Npad, passes, rays, fresh, [&] { if (any) cwbvh_k.SetArguments(&nodes, &tb, &rays, N); else cwbvh_k.SetArguments(&nodes, &tb, &rays); });
			report(*v == 'c' ? "BVH8_CWBVH (HQ)" : "BVH8_CWBVH (SAH)", bt, ms, false);
		} else {
			fprintf(stderr, "peer_rays_gpu: variant '%c' is none of aAqcC\n", *v); return 2;
		}
	}
	f = fopen(argv[3], "wb");
	if (!f || fwrite(out.data(), 4, out.size(), f) != out.size() || fclose(f) != 0) { fprintf(stderr, "peer_rays_gpu: cannot write %s\n", argv[3]); return 1; }
	return 0;
}
