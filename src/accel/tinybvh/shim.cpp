// raylab's C interface to tinybvh (J. Bikker, tiny_bvh.h, MIT): build one of its CPU layouts over
// a triangle soup and trace rays laid out as its own `Ray`. Compiled by build.rs against the
// header .ci/fetch-tinybvh caches; nothing of tinybvh is part of raylab's sources.
//
// Every entry point is noexcept: a C++ exception must not unwind into Rust. tinybvh reports a
// fatal error with exit(1) (BVH_FATAL_ERROR_IF); the Rust side never hands it what triggers one
// (no empty mesh, no NaN ray, no refit).

#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

using tinybvh::BVH;
using tinybvh::BVH4_CPU;
using tinybvh::BVH8_CPU;
using tinybvh::bvhvec4;
using tinybvh::Ray;

// The layout the Rust side mirrors (`accel::tinybvh::ffi::TinyRay`): checked on both sides.
static_assert(sizeof(Ray) == 128, "tinybvh::Ray is 128 bytes");
static_assert(alignof(Ray) == 64, "tinybvh::Ray is 64-byte aligned");
static_assert(offsetof(Ray, O) == 0 && offsetof(Ray, D) == 16 && offsetof(Ray, rD) == 32,
              "tinybvh::Ray: O, D, rD");
static_assert(offsetof(Ray, hit) == 44, "tinybvh::Ray: hit");
static_assert(offsetof(tinybvh::Intersection, t) == 4 && offsetof(tinybvh::Intersection, u) == 8 &&
                  offsetof(tinybvh::Intersection, v) == 12 &&
                  offsetof(tinybvh::Intersection, prim) == 16,
              "tinybvh::Intersection: inst, t, u, v, prim");
static_assert(sizeof(bvhvec4) == 16, "tinybvh::bvhvec4 is 16 bytes");

namespace {

enum Layout : uint32_t { BINARY = 2, WIDE4 = 4, WIDE8 = 8 };
enum Builder : uint32_t { SAH = 0, SBVH = 1 };

}  // namespace

// One built structure. The vertices live here because every tinybvh layout keeps a pointer to
// them (`bvhvec4slice`), never a copy.
struct raylab_tinybvh {
  std::vector<bvhvec4> vertices;
  uint32_t layout = BINARY;
  BVH binary;
  BVH4_CPU wide4;
  BVH8_CPU wide8;
};

// Sets rD as tinybvh's own Ray constructor does (tinybvh_rcp: 1/D, ±1e30 for a component within
// 1e-12 of 0), and keeps the ray clear of what tinybvh's wide layouts put in empty child slots: a
// box at (1e30, 1e30, 1e30) (BVH4_CPU/BVH8_CPU::ConvertFrom). A ray whose direction has three
// positive components and whose far end reaches that box — one along (1, 1, 1) from the origin
// with tinybvh's own far end BVH_FAR, say — "hits" the slot, and the traversal reads outside its
// nodes (a crash, found by the stability suite's watertight cube). Real geometry lies within
// 2^60 of the origin (`scale_for`), so a far end of 1e29 / max(D) cuts off nothing but that box.
// O·rD is kept finite likewise: the wide layouts' slabs are box·rD − O·rD, and ±inf there would
// make the empty slots' slabs NaN.
static inline void prepare(Ray& ray) {
  ray.rD = tinybvh::tinybvh_rcp(ray.D);
  const auto keep_finite = [](float o, float& rd) {
    const float limit = 1e37f;
    if (std::fabs(o) * std::fabs(rd) > limit) rd = std::copysign(limit / std::fabs(o), rd);
  };
  keep_finite(ray.O.x, ray.rD.x);
  keep_finite(ray.O.y, ray.rD.y);
  keep_finite(ray.O.z, ray.rD.z);
  if (ray.D.x > 0 && ray.D.y > 0 && ray.D.z > 0) {
    const float reach = 1e29f / std::fmax(ray.D.x, std::fmax(ray.D.y, ray.D.z));
    if (ray.hit.t > reach) ray.hit.t = reach;
  }
}

extern "C" {

uint32_t raylab_tinybvh_version() {
  return (TINY_BVH_VERSION_MAJOR << 16) | (TINY_BVH_VERSION_MINOR << 8) | TINY_BVH_VERSION_SUB;
}

// 1 when this object file has the SIMD kernels the wide layouts need (BVH4_CPU: SSE; BVH8_CPU:
// AVX2 + FMA), 0 when tiny_bvh.h fell back to stubs that exit(1).
uint32_t raylab_tinybvh_has_simd() {
#if defined(BVH_USEAVX2) && defined(BVH_USESSE)
  return 1;
#else
  return 0;
#endif
}

uint32_t raylab_tinybvh_ray_size() { return sizeof(Ray); }

// `triangles` holds three float4 vertices per triangle (w unused), `count` > 0 of them;
// `iterations` > 0 runs tinybvh's Optimize (reinsertion, Meister & Bittner 2018) that many
// times after the build. Null when out of memory or for an unknown layout or builder.
raylab_tinybvh* raylab_tinybvh_build(const float* triangles, uint32_t count, uint32_t layout,
                                     uint32_t builder, uint32_t iterations) noexcept {
  if (count == 0 || (layout != BINARY && layout != WIDE4 && layout != WIDE8) ||
      (builder != SAH && builder != SBVH))
    return nullptr;
  try {
    raylab_tinybvh* bvh = new raylab_tinybvh();
    bvh->layout = layout;
    bvh->vertices.resize(size_t(count) * 3);
    for (size_t i = 0; i < bvh->vertices.size(); i++)
      bvh->vertices[i] = bvhvec4(triangles[4 * i], triangles[4 * i + 1], triangles[4 * i + 2], 0);
    const bvhvec4* v = bvh->vertices.data();
    switch (layout) {
      case BINARY:
        if (builder == SBVH) bvh->binary.BuildHQ(v, count); else bvh->binary.Build(v, count);
        if (iterations > 0) bvh->binary.Optimize(iterations);
        break;
      case WIDE4:
        if (builder == SBVH) bvh->wide4.BuildHQ(v, count); else bvh->wide4.Build(v, count);
        if (iterations > 0) bvh->wide4.Optimize(iterations, false);
        break;
      case WIDE8:
        if (builder == SBVH) bvh->wide8.BuildHQ(v, count); else bvh->wide8.Build(v, count);
        if (iterations > 0) bvh->wide8.Optimize(iterations, false);
        break;
    }
    return bvh;
  } catch (...) {
    return nullptr;
  }
}

void raylab_tinybvh_free(raylab_tinybvh* bvh) noexcept { delete bvh; }

// Closest hits: each ray's O, D and hit.t (the far end) are set; rD is set here (`prepare`), and
// hit is filled where a triangle is nearer.
void raylab_tinybvh_intersect(const raylab_tinybvh* bvh, Ray* rays, size_t count) noexcept {
  for (size_t i = 0; i < count; i++) {
    Ray& ray = rays[i];
    prepare(ray);
    switch (bvh->layout) {
      case BINARY: bvh->binary.Intersect(ray); break;
      case WIDE4: bvh->wide4.Intersect(ray); break;
      case WIDE8: bvh->wide8.Intersect(ray); break;
    }
  }
}

// Occlusion: `occluded[i]` becomes whether anything lies on ray i before hit.t.
void raylab_tinybvh_occluded(const raylab_tinybvh* bvh, Ray* rays, size_t count,
                             uint8_t* occluded) noexcept {
  for (size_t i = 0; i < count; i++) {
    Ray& ray = rays[i];
    prepare(ray);
    bool any = false;
    switch (bvh->layout) {
      case BINARY: any = bvh->binary.IsOccluded(ray); break;
      case WIDE4: any = bvh->wide4.IsOccluded(ray); break;
      case WIDE8: any = bvh->wide8.IsOccluded(ray); break;
    }
    occluded[i] = any ? 1 : 0;
  }
}

// Closest hits of one 256-ray packet sharing an origin, in the order Intersect256Rays expects
// (its corner rays are 0, 51, 204 and 255). `sse` picks Intersect256RaysSSE, the same
// algorithm with SSE box tests. The binary layout only; 0 when the structure is another.
uint32_t raylab_tinybvh_intersect256(const raylab_tinybvh* bvh, Ray* packet,
                                     uint32_t sse) noexcept {
  if (bvh->layout != BINARY) return 0;
  for (size_t i = 0; i < 256; i++) prepare(packet[i]);
#ifdef BVH_USEAVX
  if (sse) {
    bvh->binary.Intersect256RaysSSE(packet);
    return 1;
  }
#endif
  bvh->binary.Intersect256Rays(packet);
  return 1;
}

}  // extern "C"
