// tinybvh-direct: tinybvh called directly from C++ on the work a raylab run dumped, the independent
// check that raylab's tinybvh rows time tinybvh at its speed (issue 45, item 5), as
// tools/embree-direct.c checks the Embree rows.
//
// Build against the header .ci/fetch-tinybvh caches, with the flags build.rs gives raylab's shim:
//     g++ -std=c++20 -O3 -march=native -I ~/.cache/raylab/tinybvh/include \
//         -o target/tinybvh-direct tools/tinybvh-direct.cpp
// Dump a run's work, then time tinybvh on it, single-threaded:
//     raylab run experiments/quick.toml --dump-rays --threads 1
//     target/tinybvh-direct DIR/rays/room-s3-f0.tris DIR/rays/room-s3-f0-diffuse.rays [--sbvh]
//         [--optimize N] [--occluded] [--repeats N]
// and compare with `raylab bench --tracer tinybvh-8 --rays DIR/rays/room-s3-f0-diffuse.rays …`
// (same builder and optimize parameters).
//
// It builds tinybvh's BVH8_CPU as tinybvh's own speedtest does (Build or BuildHQ, then Optimize
// if asked; BVH8_CPU builds its binary tree and converts it), sets every ray up with tinybvh's
// Ray constructor, untimed, and times BVH8_CPU::Intersect (or IsOccluded) over the rays: the
// fastest of --repeats passes (default 5) after one warm-up pass, in ms and Mrays/s. raylab's
// shim also computes each ray's reciprocal direction inside its timed call (`prepare`), so it
// does a little more per ray than this loop.
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace {

[[noreturn]] void fail(const char* what, const char* path) {
  std::fprintf(stderr, "tinybvh-direct: %s: %s\n", path, what);
  std::exit(2);
}

// A raylab dump file (`geometry::ray_file`, `experiment::run::dump`): 8-byte magic, u32 version
// 1, u32 word, u64 count, then `floats` f32 per record.
std::vector<float> read_records(const char* path, const char* magic, size_t floats, uint32_t* word) {
  std::FILE* file = std::fopen(path, "rb");
  if (!file) fail("cannot open", path);
  unsigned char header[24];
  if (std::fread(header, 1, 24, file) != 24 || std::memcmp(header, magic, 8) != 0)
    fail("not a raylab dump of this kind", path);
  uint32_t version;
  uint64_t count;
  std::memcpy(&version, header + 8, 4);
  std::memcpy(word, header + 12, 4);
  std::memcpy(&count, header + 16, 8);
  if (version != 1) fail("unknown version", path);
  // Rays with times carry a ninth float.
  if (floats == 8 && *word != 0) floats = 9;
  std::vector<float> f(count * floats);
  if (std::fread(f.data(), sizeof(float), f.size(), file) != f.size()) fail("truncated", path);
  std::fclose(file);
  return f;
}

double now() {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
  const char *tris_path = nullptr, *rays_path = nullptr;
  bool occluded = false, sbvh = false;
  int repeats = 5, optimize = 0;
  for (int i = 1; i < argc; i++) {
    if (!std::strcmp(argv[i], "--occluded")) occluded = true;
    else if (!std::strcmp(argv[i], "--sbvh")) sbvh = true;
    else if (!std::strcmp(argv[i], "--repeats") && i + 1 < argc) repeats = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--optimize") && i + 1 < argc) optimize = std::atoi(argv[++i]);
    else if (!tris_path) tris_path = argv[i];
    else if (!rays_path) rays_path = argv[i];
    else fail("unexpected argument", argv[i]);
  }
  if (!tris_path || !rays_path || repeats < 1 || optimize < 0) {
    std::fprintf(stderr,
                 "usage: tinybvh-direct SCENE.tris RAYS.rays [--sbvh] [--optimize N] [--occluded] "
                 "[--repeats N]\n");
    return 2;
  }
  uint32_t word;
  std::vector<float> tris = read_records(tris_path, "RAYLABTR", 9, &word);
  std::vector<float> file = read_records(rays_path, "RAYLABRY", 8, &word);
  size_t stride = word ? 9 : 8, n = file.size() / stride, count = tris.size() / 9;
  if (count == 0) fail("no triangles", tris_path);

  std::vector<tinybvh::bvhvec4> vertices(count * 3);
  for (size_t i = 0; i < count * 3; i++)
    vertices[i] = tinybvh::bvhvec4(tris[i * 3], tris[i * 3 + 1], tris[i * 3 + 2], 0);
  tinybvh::BVH8_CPU bvh;
  double start = now();
  if (sbvh) bvh.BuildHQ(vertices.data(), (uint32_t)count);
  else bvh.Build(vertices.data(), (uint32_t)count);
  if (optimize > 0) bvh.Optimize(optimize, false);
  double build = now() - start;

  // Set up untimed, as raylab stages a baseline's rays before each timed pass.
  std::vector<tinybvh::Ray> fresh(n), rays(n);
  for (size_t i = 0; i < n; i++) {
    // tinybvh's rays start at their origin: one with tmin > 0 starts at origin + tmin·dir, as
    // raylab hands it over (`tracers::tinybvh`). The far end stays short of the box tinybvh puts
    // in empty child slots (1e30), as raylab's shim keeps it.
    const float* f = &file[i * stride];
    const float tmin = f[6] > 0 ? f[6] : 0, far = std::fmin(f[7] - tmin, 1e29f);
    const tinybvh::bvhvec3 o(f[0], f[1], f[2]), d(f[3], f[4], f[5]);
    fresh[i] = tinybvh::Ray(o + d * tmin, d, far);
  }
  double best = 1e30;
  size_t met = 0;
  for (int pass = 0; pass <= repeats; pass++) {
    rays = fresh;
    met = 0;
    double t0 = now();
    if (occluded) {
      for (size_t i = 0; i < n; i++) met += bvh.IsOccluded(rays[i]) ? 1 : 0;
    } else {
      for (size_t i = 0; i < n; i++) bvh.Intersect(rays[i]);
    }
    double t = now() - t0;
    if (pass > 0 && t < best) best = t;  // pass 0 warms up
  }
  // The triangles hit, summed as a check that the hits are the ones raylab's tinybvh rows find.
  uint64_t prims = 0;
  if (!occluded)
    for (size_t i = 0; i < n; i++)
      if (rays[i].hit.t < fresh[i].hit.t) met++, prims += rays[i].hit.prim;
  std::printf("tinybvh BVH8_CPU %s%s: %zu triangles, %zu rays, build %.3f s: min %.3f ms, %.2f Mrays/s, %zu %s",
              sbvh ? "sbvh" : "sah", optimize ? " + optimize" : "", count, n, build, best * 1e3,
              n / best * 1e-6, met, occluded ? "occluded" : "hit");
  if (!occluded) std::printf(", triangle ids summing to %llu", (unsigned long long)prims);
  std::printf("\n");
  return 0;
}
