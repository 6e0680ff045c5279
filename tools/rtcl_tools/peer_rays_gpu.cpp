// The peer's GPU traversals (TinyBVH's OpenCL kernels) over a ray file of
// rtcl-peer-compare --rays (peer_rays.cpp makes them; docs/bvh.md, "Incoherent
// rays against TinyBVH"). Built against the peer's folder, run from a folder
// that holds the peer's .cl files and peer_rays.cl (tiny_ocl loads kernels
// from the working directory):
//   g++ -O3 -march=x86-64-v3 -std=c++20 -I PEER -I/usr/include/CL peer_rays_gpu.cpp -o peer_rays_gpu -lOpenCL -lpthread
// usage: peer_rays_gpu TRIS.bin passes variants RAYS HITS [RAYS HITS ...]
// variants: letters of a (BVH_GPU HQ), A (BVH_GPU SAH), q (BVH4_GPU HQ),
// c (CWBVH HQ), C (CWBVH SAH), as the peer's side.cpp. Each layout is built
// once and traces every ray file.
// Closest-hit files go through TinyBVH's batch_* kernels (t_max 1e30, the
// file's), any-hit files through peer_rays.cl's occluded_* kernels (each
// ray's t_max). Each variant and file: one untimed launch, then `passes`
// timed by OpenCL profiling events; median and min (the rays copied afresh
// before each). HITS: the first
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

struct RayFile { const char* rays; const char* hits; uint32_t N, flags; std::vector<float> file; std::vector<GpuRay> fresh; std::vector<float> out; bool written = false; };

int main(int argc, char** argv)
{
	if (argc < 6 || (argc - 4) % 2) { fprintf(stderr, "usage: peer_rays_gpu TRIS.bin passes variants RAYS HITS [RAYS HITS ...]\n"); return 2; }
	FILE* f = fopen(argv[1], "rb"); if (!f) { perror(argv[1]); return 1; }
	uint32_t ntri; if (fread(&ntri, 4, 1, f) != 1) return 1;
	bvhvec4* tris = (bvhvec4*)tinybvh::malloc64((size_t)ntri * 3 * sizeof(bvhvec4));
	if (fread(tris, 16, (size_t)ntri * 3, f) != (size_t)ntri * 3) { fprintf(stderr, "short file\n"); return 1; }
	fclose(f);
	int passes = atoi(argv[2]); const char* vars = argv[3];
	std::vector<RayFile> sets((argc - 4) / 2);
	unsigned most = 64;
	for (size_t s = 0; s < sets.size(); s++) {
		RayFile& rf = sets[s]; rf.rays = argv[4 + 2 * s]; rf.hits = argv[5 + 2 * s];
		f = fopen(rf.rays, "rb"); char magic[8];
		if (!f || fread(magic, 1, 8, f) != 8 || memcmp(magic, "RTCLRAY1", 8) || fread(&rf.N, 4, 1, f) != 1 || fread(&rf.flags, 4, 1, f) != 1 || rf.N == 0) { fprintf(stderr, "%s: not a ray file\n", rf.rays); return 1; }
		rf.file.resize((size_t)rf.N * 8);
		if (fread(rf.file.data(), 4, rf.file.size(), f) != rf.file.size()) { fprintf(stderr, "%s: short\n", rf.rays); return 1; }
		fclose(f);
		unsigned Npad = (rf.N + 63) / 64 * 64; most = std::max(most, Npad);
		rf.fresh.resize(Npad);
		for (unsigned i = 0; i < Npad; i++) {
			const float* r = &rf.file[8 * (size_t)std::min(i, rf.N - 1)]; // padding: the last ray again (the batch kernels check no count)
			GpuRay& g = rf.fresh[i];
			for (int k = 0; k < 3; k++) { g.O[k] = r[k]; g.D[k] = r[4 + k]; g.rD[k] = 1.0f / r[4 + k]; }
			g.O[3] = r[3]; g.D[3] = 0; g.rD[3] = 0; g.hit[0] = 1e30f; g.hit[1] = g.hit[2] = g.hit[3] = 0;
		}
	}
	tinyocl::Kernel ailalaine("traverse.cl", "batch_ailalaine"), ailalaine_any("peer_rays.cl", "occluded_ailalaine");
	tinyocl::Kernel gpu4way("traverse.cl", "batch_gpu4way"), gpu4way_any("peer_rays.cl", "occluded_gpu4way");
	tinyocl::Kernel cwbvh_k("traverse.cl", "batch_cwbvh"), cwbvh_any("peer_rays.cl", "occluded_cwbvh");
	tinyocl::Buffer rays(most * 64);
	GpuRay* host = (GpuRay*)rays.GetHostPtr();
	printf("triangles %u, %d timed passes (median, min)\n", ntri, passes);
	// Traces every ray file with kernel k (closest) or k_any (any hit), args setting its arguments.
	auto trace_all = [&](const char* name, double build, bool with_prim, tinyocl::Kernel& k, tinyocl::Kernel& k_any, auto args) {
		for (RayFile& rf : sets) {
			bool any = rf.flags & 1;
			unsigned Npad = (unsigned)rf.fresh.size();
			auto ms = timed(any ? k_any : k, Npad, passes, rays, rf.fresh, [&] { args(any ? k_any : k, any, rf.N); });
			rays.CopyFromDevice();
			unsigned c = 0;
			for (unsigned j = 0; j < rf.N; j++) c += any ? host[j].hit[0] > 0.5f : host[j].hit[0] < rf.file[8 * (size_t)j + 3];
			printf("%s: %u %s rays\n%-28s build %8.1f ms  trace median %.4f ms  min %.4f ms  -> %.0f Mrays/s, hits %u\n", rf.rays, rf.N, any ? "any-hit" : "closest-hit", name, build, ms[ms.size() / 2], ms[0], rf.N / (ms[ms.size() / 2] * 1e-3) * 1e-6, c);
			if (rf.written) continue;
			rf.out.resize((size_t)rf.N * 2);
			for (unsigned j = 0; j < rf.N; j++) {
				bool h = any ? host[j].hit[0] > 0.5f : host[j].hit[0] < rf.file[8 * (size_t)j + 3];
				int32_t prim = h && !any && with_prim ? (int32_t)*(uint32_t*)&host[j].hit[3] : -1;
				rf.out[2 * j] = h ? (any ? 1.0f : host[j].hit[0]) : 0.0f;
				memcpy(&rf.out[2 * j + 1], &prim, 4);
			}
			rf.written = true;
		}
	};
	for (const char* v = vars; *v; v++) {
		if (*v == 'a' || *v == 'A') {
			double t0 = now(); BVH_GPU b; if (*v == 'a') b.BuildHQ(tris, ntri); else b.Build(tris, ntri); double bt = (now() - t0) * 1e3;
			tinyocl::Buffer nodes(b.usedNodes * sizeof(BVH_GPU::BVHNode), b.bvhNode), idx(b.idxCount * 4, b.bvh.primIdx), tri(ntri * 3 * 16, tris);
			nodes.CopyToDevice(); idx.CopyToDevice(); tri.CopyToDevice();
			trace_all(*v == 'a' ? "BVH_GPU (Aila-Laine, HQ)" : "BVH_GPU (Aila-Laine, SAH)", bt, true, ailalaine, ailalaine_any,
				[&](tinyocl::Kernel& k, bool any, uint32_t n) { if (any) k.SetArguments(&nodes, &idx, &tri, &rays, n); else k.SetArguments(&nodes, &idx, &tri, &rays); });
		} else if (*v == 'q') {
			double t0 = now(); BVH4_GPU b; b.BuildHQ(tris, ntri); double bt = (now() - t0) * 1e3;
			tinyocl::Buffer nodes(b.usedBlocks * sizeof(bvhvec4), b.bvh4Data); nodes.CopyToDevice();
			trace_all("BVH4_GPU (HQ)", bt, false, gpu4way, gpu4way_any,
				[&](tinyocl::Kernel& k, bool any, uint32_t n) { if (any) k.SetArguments(&nodes, &rays, n); else k.SetArguments(&nodes, &rays); });
		} else if (*v == 'c' || *v == 'C') {
			double t0 = now(); BVH8_CWBVH b; if (*v == 'c') b.BuildHQ(tris, ntri); else b.Build(tris, ntri); double bt = (now() - t0) * 1e3;
#ifdef CWBVH_COMPRESSED_TRIS
			tinyocl::Buffer tb(b.idxCount * 4 * sizeof(bvhvec4), b.bvh8Tris);
#else
			tinyocl::Buffer tb(b.idxCount * 3 * sizeof(bvhvec4), b.bvh8Tris);
#endif
			tinyocl::Buffer nodes(b.usedBlocks * sizeof(bvhvec4), b.bvh8Data); nodes.CopyToDevice(); tb.CopyToDevice();
			trace_all(*v == 'c' ? "BVH8_CWBVH (HQ)" : "BVH8_CWBVH (SAH)", bt, false, cwbvh_k, cwbvh_any,
				[&](tinyocl::Kernel& k, bool any, uint32_t n) { if (any) k.SetArguments(&nodes, &tb, &rays, n); else k.SetArguments(&nodes, &tb, &rays); });
		} else {
			fprintf(stderr, "peer_rays_gpu: variant '%c' is none of aAqcC\n", *v); return 2;
		}
	}
	for (RayFile& rf : sets) {
		f = fopen(rf.hits, "wb");
		if (!f || fwrite(rf.out.data(), 4, rf.out.size(), f) != rf.out.size() || fclose(f) != 0) { fprintf(stderr, "peer_rays_gpu: cannot write %s\n", rf.hits); return 1; }
	}
	return 0;
}
