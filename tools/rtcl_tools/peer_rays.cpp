// The rays of rtcl-peer-compare --rays, made once, and the peer's CPU traversals
// over them (docs/bvh.md, "Incoherent rays against TinyBVH"). Built against the
// peer's tiny_bvh.h:
//   g++ -O3 -march=native -std=c++20 -I PEER peer_rays.cpp -o peer_rays -lpthread
//
// peer_rays make TRIS.bin W H ex ey ez lx ly lz fov ux uy uz OUTDIR
//   writes OUTDIR/primary.rays, bounce.rays and shadow.rays (the ray file of
//   host/cmd/rays.c: "RTCLRAY1", uint32 count, uint32 flags (1: any hit), then
//   per ray origin xyz, t_max, direction xyz, 0, all float32):
//   - primary: one ray per pixel with rtcl's pinhole camera (RENDERING.md,
//     "Camera and pixels"), pixels in 8x4 tiles (a 32-wide warp a tile), rows
//     of tiles top down; t_max 1e30.
//   - bounce: for each primary ray that hits (traced here with TinyBVH's BVH),
//     in the same order, one diffuse bounce: origin p + e n, where p = o + t d,
//     n the hit triangle's geometric normal turned to face the ray and
//     e = 1e-5 times the mesh's bounding-box diagonal; direction
//     cosine-distributed about n from u1 = (hash(2i) >> 8) 2^-24 and
//     u2 = (hash(2i + 1) >> 8) 2^-24, i = y W + x the pixel, hash the
//     integer hash "lowbias32" (x ^= x >> 16; x *= 0x7feb352d; x ^= x >> 15;
//     x *= 0x846ca68b; x ^= x >> 16), r = sqrt(u1), phi = 2 pi u2, local
//     (r cos phi, r sin phi, sqrt(1 - u1)) in the frame of Duff et al. (2017)
//     about n; t_max 1e30.
//   - shadow: from the same origins to the point light L = c + D (0.3, 0.8,
//     0.5), c the box's centre and D its diagonal's length (any hit): direction
//     (L - o) / |L - o|, t_max |L - o|.
//   Everything in float32, as written here: the two sides read the same file.
//
// peer_rays trace TRIS.bin passes RAYS HITS [RAYS HITS ...]
//   traces each RAYS with TinyBVH's CPU traversals (BVH built HQ, BVH4_CPU,
//   BVH8_CPU, each built once) on every hardware thread: Intersect, or
//   IsOccluded for an any-hit file; prints each one's build and median trace
//   time of `passes` after one untimed, and writes the first's hits to HITS in
//   rtcl-rays's layout (float t, int32 triangle; t 0 and -1 for none; for an
//   any-hit file t 1 when occluded).
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>
using namespace tinybvh;

static double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

static uint32_t lowbias32(uint32_t x)
{
	x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
	return x;
}

struct FileRay { float o[3], tmax, d[3], pad; };

static bvhvec4* read_tris(const char* path, uint32_t& n)
{
	FILE* f = fopen(path, "rb");
	if (!f || fread(&n, 4, 1, f) != 1) { fprintf(stderr, "peer_rays: cannot read %s\n", path); exit(1); }
	bvhvec4* tris = (bvhvec4*)tinybvh::malloc64((size_t)n * 48);
	if (fread(tris, 16, (size_t)n * 3, f) != (size_t)n * 3) { fprintf(stderr, "peer_rays: %s is short\n", path); exit(1); }
	fclose(f);
	return tris;
}

static void write_rays(const std::string& path, const std::vector<FileRay>& rays, uint32_t flags)
{
	FILE* f = fopen(path.c_str(), "wb");
	uint32_t n = (uint32_t)rays.size();
	if (!f || fwrite("RTCLRAY1", 1, 8, f) != 8 || fwrite(&n, 4, 1, f) != 1 || fwrite(&flags, 4, 1, f) != 1 ||
		fwrite(rays.data(), sizeof(FileRay), n, f) != n || fclose(f) != 0) {
		fprintf(stderr, "peer_rays: cannot write %s\n", path.c_str()); exit(1);
	}
}

static std::vector<FileRay> read_rays(const char* path, uint32_t& flags)
{
	FILE* f = fopen(path, "rb"); char magic[8]; uint32_t n;
	if (!f || fread(magic, 1, 8, f) != 8 || memcmp(magic, "RTCLRAY1", 8) || fread(&n, 4, 1, f) != 1 || fread(&flags, 4, 1, f) != 1) {
		fprintf(stderr, "peer_rays: %s is not a ray file\n", path); exit(1);
	}
	std::vector<FileRay> rays(n);
	if (fread(rays.data(), sizeof(FileRay), n, f) != n) { fprintf(stderr, "peer_rays: %s is short\n", path); exit(1); }
	fclose(f);
	return rays;
}

template <class F> static void parallel(size_t n, F body)
{
	unsigned T = std::max(1u, std::thread::hardware_concurrency());
	std::atomic<size_t> next(0); std::vector<std::thread> th;
	for (unsigned i = 0; i < T; i++) th.emplace_back([&] { size_t b; while ((b = next.fetch_add(1024)) < n) for (size_t j = b; j < std::min(n, b + 1024); j++) body(j); });
	for (auto& t : th) t.join();
}

static int make(int argc, char** argv)
{
	if (argc != 16) { fprintf(stderr, "usage: peer_rays make TRIS.bin W H ex ey ez lx ly lz fov ux uy uz OUTDIR\n"); return 2; }
	uint32_t n; bvhvec4* tris = read_tris(argv[2], n);
	int W = atoi(argv[3]), H = atoi(argv[4]);
	bvhvec3 eye(atof(argv[5]), atof(argv[6]), atof(argv[7])), at(atof(argv[8]), atof(argv[9]), atof(argv[10]));
	float fov = (float)atof(argv[11]);
	bvhvec3 up(atof(argv[12]), atof(argv[13]), atof(argv[14]));
	std::string out = argv[15];
	bvhvec3 fw = tinybvh_normalize(at - eye), r = tinybvh_normalize(tinybvh_cross(fw, up)), u = tinybvh_cross(r, fw);
	float h = tanf(fov * 3.14159265358979f / 360.f), a = (float)W / H;
	bvhvec3 lo(1e30f), hi(-1e30f);
	for (size_t i = 0; i < (size_t)n * 3; i++) { lo = tinybvh_min(lo, bvhvec3(tris[i])); hi = tinybvh_max(hi, bvhvec3(tris[i])); }
	float diagonal = tinybvh_length(hi - lo);
	bvhvec3 light = (lo + hi) * 0.5f + diagonal * bvhvec3(0.3f, 0.8f, 0.5f);
	float lift = 1e-5f * diagonal;

	std::vector<FileRay> primary; std::vector<uint32_t> pixel;
	for (int ty = 0; ty < (H + 3) / 4; ty++) for (int tx = 0; tx < (W + 7) / 8; tx++)
		for (int y = ty * 4; y < ty * 4 + 4; y++) for (int x = tx * 8; x < tx * 8 + 8; x++) {
			if (x >= W || y >= H) continue;
			bvhvec3 d = tinybvh_normalize(fw + ((2 * (x + 0.5f) / W - 1) * a * h) * r + ((1 - 2 * (y + 0.5f) / H) * h) * u);
			primary.push_back({{eye.x, eye.y, eye.z}, 1e30f, {d.x, d.y, d.z}, 0});
			pixel.push_back((uint32_t)y * W + x);
		}
	BVH bvh; bvh.Build(tris, n);
	std::vector<Ray> hits(primary.size());
	parallel(primary.size(), [&](size_t i) {
		const FileRay& p = primary[i];
		hits[i] = Ray(bvhvec3(p.o[0], p.o[1], p.o[2]), bvhvec3(p.d[0], p.d[1], p.d[2]));
		bvh.Intersect(hits[i]);
	});
	std::vector<FileRay> bounce, shadow;
	for (size_t i = 0; i < primary.size(); i++) {
		const Ray& ray = hits[i];
		if (!(ray.hit.t < 1e29f)) continue;
		uint32_t prim = ray.hit.prim;
		bvhvec3 v0(tris[prim * 3]), v1(tris[prim * 3 + 1]), v2(tris[prim * 3 + 2]);
		bvhvec3 nrm = tinybvh_normalize(tinybvh_cross(v1 - v0, v2 - v0));
		if (tinybvh_dot(nrm, ray.D) > 0) nrm = nrm * -1.0f;
		bvhvec3 o = ray.O + ray.hit.t * ray.D + lift * nrm;
		// Duff et al., "Building an Orthonormal Basis, Revisited" (2017).
		float sign = copysignf(1.0f, nrm.z), aa = -1.0f / (sign + nrm.z), b = nrm.x * nrm.y * aa;
		bvhvec3 t1(1.0f + sign * nrm.x * nrm.x * aa, sign * b, -sign * nrm.x), t2(b, sign + nrm.y * nrm.y * aa, -nrm.y);
		float u1 = (lowbias32(2 * pixel[i]) >> 8) * (1.0f / 16777216.0f);
		float u2 = (lowbias32(2 * pixel[i] + 1) >> 8) * (1.0f / 16777216.0f);
		float rad = sqrtf(u1), phi = 6.28318530717959f * u2;
		bvhvec3 d = tinybvh_normalize(rad * cosf(phi) * t1 + rad * sinf(phi) * t2 + sqrtf(std::max(0.0f, 1.0f - u1)) * nrm);
		bounce.push_back({{o.x, o.y, o.z}, 1e30f, {d.x, d.y, d.z}, 0});
		bvhvec3 toward = light - o; float dist = tinybvh_length(toward); bvhvec3 ld = toward * (1.0f / dist);
		shadow.push_back({{o.x, o.y, o.z}, dist, {ld.x, ld.y, ld.z}, 0});
	}
	write_rays(out + "/primary.rays", primary, 0);
	write_rays(out + "/bounce.rays", bounce, 0);
	write_rays(out + "/shadow.rays", shadow, 1);
	printf("triangles %u, rays: primary %zu, bounce %zu, shadow %zu; light %g %g %g\n", n, primary.size(), bounce.size(), shadow.size(), light.x, light.y, light.z);
	return 0;
}

static int trace(int argc, char** argv)
{
	if (argc < 6 || argc % 2) { fprintf(stderr, "usage: peer_rays trace TRIS.bin passes RAYS HITS [RAYS HITS ...]\n"); return 2; }
	uint32_t n; bvhvec4* tris = read_tris(argv[2], n);
	int passes = atoi(argv[3]);
	struct Set { const char *rays, *hits; uint32_t flags; std::vector<FileRay> file; std::vector<float> out; };
	std::vector<Set> sets((argc - 4) / 2);
	for (size_t s = 0; s < sets.size(); s++) {
		sets[s].rays = argv[4 + 2 * s]; sets[s].hits = argv[5 + 2 * s];
		sets[s].file = read_rays(sets[s].rays, sets[s].flags);
	}
	unsigned T = std::max(1u, std::thread::hardware_concurrency());
	printf("triangles %u, %u threads, %d timed passes (median, min)\n", n, T, passes);
	auto bench = [&](const char* name, auto& bvh, double build) {
		for (Set& set : sets) {
			const std::vector<FileRay>& file = set.file;
			bool any = set.flags & 1;
			std::vector<Ray> rays(file.size()); std::vector<uint8_t> occluded(file.size());
			std::vector<double> ts;
			for (int p = 0; p < passes + 1; p++) {
				for (size_t i = 0; i < file.size(); i++) {
					const FileRay& f = file[i];
					rays[i] = Ray(bvhvec3(f.o[0], f.o[1], f.o[2]), bvhvec3(f.d[0], f.d[1], f.d[2]), f.tmax);
				}
				double t0 = now();
				if (any) parallel(rays.size(), [&](size_t j) { occluded[j] = bvh.IsOccluded(rays[j]); });
				else parallel(rays.size(), [&](size_t j) { bvh.Intersect(rays[j]); });
				if (p) ts.push_back(now() - t0);
			}
			std::sort(ts.begin(), ts.end());
			size_t hit = 0;
			for (size_t i = 0; i < rays.size(); i++) hit += any ? occluded[i] : rays[i].hit.t < file[i].tmax;
			double median = ts[ts.size() / 2];
			printf("%s: %zu %s rays\n%-12s build %8.1f ms  trace median %9.3f ms  min %9.3f ms -> %7.2f Mrays/s, hits %zu\n", set.rays, rays.size(), any ? "any-hit" : "closest-hit", name, build, median * 1e3, ts[0] * 1e3, rays.size() / median * 1e-6, hit);
			if (!set.out.empty()) continue;
			set.out.resize(rays.size() * 2);
			for (size_t i = 0; i < rays.size(); i++) {
				bool h = any ? occluded[i] : rays[i].hit.t < file[i].tmax;
				int32_t prim = h && !any ? (int32_t)rays[i].hit.prim : -1;
				set.out[2 * i] = h ? (any ? 1.0f : rays[i].hit.t) : 0.0f;
				memcpy(&set.out[2 * i + 1], &prim, 4);
			}
		}
	};
	{ double t0 = now(); BVH b; b.BuildHQ(tris, n); bench("BVH (HQ)", b, (now() - t0) * 1e3); }
	{ double t0 = now(); BVH4_CPU b; b.BuildHQ(tris, n); bench("BVH4_CPU", b, (now() - t0) * 1e3); }
	{ double t0 = now(); BVH8_CPU b; b.BuildHQ(tris, n); bench("BVH8_CPU", b, (now() - t0) * 1e3); }
	for (Set& set : sets) {
		FILE* f = fopen(set.hits, "wb");
		if (!f || fwrite(set.out.data(), 4, set.out.size(), f) != set.out.size() || fclose(f) != 0) { fprintf(stderr, "peer_rays: cannot write %s\n", set.hits); return 1; }
	}
	return 0;
}

int main(int argc, char** argv)
{
	if (argc > 1 && !strcmp(argv[1], "make")) return make(argc, argv);
	if (argc > 1 && !strcmp(argv[1], "trace")) return trace(argc, argv);
	fprintf(stderr, "usage: peer_rays make TRIS.bin W H ex ey ez lx ly lz fov ux uy uz OUTDIR\n"
		"       peer_rays trace TRIS.bin passes RAYS HITS [RAYS HITS ...]\n");
	return 2;
}
