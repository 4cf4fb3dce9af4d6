/* embree-direct: Embree 3 called directly from C on the work a raylab run dumped, the independent
 * check that raylab's Embree rows time Embree at its best (README, "Embree at its best").
 *
 * Build (Debian's libembree-dev, as .ci/setup installs it):
 *     cc -O2 -o target/embree-direct tools/embree-direct.c -lembree3
 * Dump a run's work, then time Embree on it, single-threaded:
 *     raylab run experiments/quick.toml --dump-rays --threads 1
 *     target/embree-direct DIR/rays/room-s3-f0.tris DIR/rays/room-s3-f0-diffuse.rays
 *     target/embree-direct DIR/rays/room-s3-f0.tris DIR/rays/room-s3-f0-shadow.rays --occluded
 *     target/embree-direct DIR/rays/room-area-light-f0.tris DIR/rays/room-area-light-f0.points
 *
 * For a ray file it times every entry point (rtcIntersect1/4/8/16/1M, or rtcOccluded* with
 * --occluded) × intersect context (coherent, incoherent) × build quality (medium, high), without
 * RTC_SCENE_FLAG_ROBUST, on rays already in Embree's layout: only the calls are timed, as an
 * Embree user who keeps rays in Embree's structures would pay. For a soft-shadow points file
 * (`raylab run --dump-rays` writes the query's shading points and quad light) it times the loop an
 * Embree user would write for Benthin & Wald 2009's query: per shading point, its samples² ...
 * stratified jittered light samples generated in registers and one rtcOccluded16 per 16 of them,
 * generation included (raylab times its tracers' generation too), and the same calls on
 * pregenerated packets, so the generation's share shows. The soft-shadow rays go from the point's
 * ray origin to just short of the sample (t_far = 0.9999 × distance); samples behind the surface
 * are inactive lanes, as in raylab's `tracers::visibility::shadow_ray`.
 *
 * Prints one line per configuration (fastest of --repeats passes, default 5, after one warm-up
 * pass) and the best; the file formats are raylab's (`geometry::ray_file`, `experiment::run::dump`).
 */
#include <embree3/rtcore.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Embree 3's headers declare the ray structures as C++-style structs only. */
typedef struct RTCRay RTCRay;
typedef struct RTCRayHit RTCRayHit;
typedef struct RTCRayHit4 RTCRayHit4;
typedef struct RTCRayHit8 RTCRayHit8;
typedef struct RTCRayHit16 RTCRayHit16;
typedef struct RTCRay16 RTCRay16;
typedef struct RTCIntersectContext RTCIntersectContext;

typedef struct {
  float *f;       /* the records' floats */
  uint32_t word;  /* the header's second u32 */
  uint64_t count; /* records */
} Records;

static void fail(const char *what, const char *path) {
  fprintf(stderr, "embree-direct: %s: %s\n", path, what);
  exit(2);
}

/* A raylab dump file: 8-byte magic, u32 version 1, u32 word, u64 count, then f32 records of
 * `floats` each after `extra` leading floats. */
static Records read_records(const char *path, const char *magic, size_t floats, size_t extra) {
  FILE *file = fopen(path, "rb");
  if (!file) fail("cannot open", path);
  unsigned char header[24];
  if (fread(header, 1, 24, file) != 24 || memcmp(header, magic, 8) != 0) fail("not a raylab dump of this kind", path);
  Records r;
  uint32_t version;
  memcpy(&version, header + 8, 4);
  memcpy(&r.word, header + 12, 4);
  memcpy(&r.count, header + 16, 8);
  if (version != 1) fail("unknown version", path);
  size_t n = extra + r.count * floats;
  r.f = malloc(n * sizeof(float) + 1);
  if (!r.f || fread(r.f, sizeof(float), n, file) != n) fail("truncated", path);
  fclose(file);
  return r;
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + t.tv_nsec * 1e-9;
}

static RTCScene build(RTCDevice device, const Records *tris, enum RTCBuildQuality quality) {
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_NONE);
  rtcSetSceneBuildQuality(scene, quality);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geometry, quality);
  float *v = rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, tris->count * 3);
  unsigned *index = rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, tris->count);
  memcpy(v, tris->f, tris->count * 36);
  for (uint64_t i = 0; i < tris->count * 3; i++) index[i] = (unsigned)i;
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene);
  return scene;
}

/* The rays of a ray file in every layout an entry point takes, filled once, untimed. */
typedef struct {
  size_t n, stride; /* rays, floats per ray in the file */
  const float *f;
  RTCRayHit *single;
  RTCRayHit4 *p4;
  RTCRayHit8 *p8;
  RTCRayHit16 *p16;
  int *valid; /* n rounded up to 16, -1 for a ray, 0 past the end */
} Rays;

static void *aligned(size_t bytes) {
  void *p = aligned_alloc(64, (bytes + 63) / 64 * 64);
  if (!p) fail("out of memory", "embree-direct");
  return p;
}

#define SET_PACKET(P, W, i, f)                                                             \
  do {                                                                                     \
    size_t k = (i) / W, l = (i) % W;                                                       \
    P[k].ray.org_x[l] = f[0], P[k].ray.org_y[l] = f[1], P[k].ray.org_z[l] = f[2];          \
    P[k].ray.dir_x[l] = f[3], P[k].ray.dir_y[l] = f[4], P[k].ray.dir_z[l] = f[5];          \
    P[k].ray.tnear[l] = f[6], P[k].ray.tfar[l] = f[7], P[k].ray.time[l] = 0.0f;            \
    P[k].ray.mask[l] = 0xFFFFFFFF, P[k].ray.flags[l] = 0, P[k].ray.id[l] = (unsigned)(i);  \
    P[k].hit.geomID[l] = RTC_INVALID_GEOMETRY_ID;                                          \
  } while (0)

/* Resets every layout to the file's rays (tfar and the hits change when traced). */
static void reset(Rays *r) {
  for (size_t i = 0; i < r->n; i++) {
    const float *f = r->f + i * r->stride;
    RTCRayHit *s = &r->single[i];
    s->ray.org_x = f[0], s->ray.org_y = f[1], s->ray.org_z = f[2];
    s->ray.dir_x = f[3], s->ray.dir_y = f[4], s->ray.dir_z = f[5];
    s->ray.tnear = f[6], s->ray.tfar = f[7], s->ray.time = 0.0f;
    s->ray.mask = 0xFFFFFFFF, s->ray.flags = 0, s->ray.id = (unsigned)i;
    s->hit.geomID = RTC_INVALID_GEOMETRY_ID;
    SET_PACKET(r->p4, 4, i, f);
    SET_PACKET(r->p8, 8, i, f);
    SET_PACKET(r->p16, 16, i, f);
  }
}

enum { ONE, FOUR, EIGHT, SIXTEEN, STREAM };
static const char *ENTRY[] = {"1", "4", "8", "16", "1M"};

static void trace(RTCScene scene, RTCIntersectContext *ctx, Rays *r, int entry, int occluded) {
  size_t n = r->n;
  switch (entry) {
  case ONE:
    for (size_t i = 0; i < n; i++)
      occluded ? rtcOccluded1(scene, ctx, &r->single[i].ray) : rtcIntersect1(scene, ctx, &r->single[i]);
    break;
  case FOUR:
    for (size_t k = 0; k < (n + 3) / 4; k++)
      occluded ? rtcOccluded4(r->valid + 4 * k, scene, ctx, &r->p4[k].ray)
               : rtcIntersect4(r->valid + 4 * k, scene, ctx, &r->p4[k]);
    break;
  case EIGHT:
    for (size_t k = 0; k < (n + 7) / 8; k++)
      occluded ? rtcOccluded8(r->valid + 8 * k, scene, ctx, &r->p8[k].ray)
               : rtcIntersect8(r->valid + 8 * k, scene, ctx, &r->p8[k]);
    break;
  case SIXTEEN:
    for (size_t k = 0; k < (n + 15) / 16; k++)
      occluded ? rtcOccluded16(r->valid + 16 * k, scene, ctx, &r->p16[k].ray)
               : rtcIntersect16(r->valid + 16 * k, scene, ctx, &r->p16[k]);
    break;
  case STREAM:
    occluded ? rtcOccluded1M(scene, ctx, &r->single[0].ray, (unsigned)n, sizeof(RTCRayHit))
             : rtcIntersect1M(scene, ctx, r->single, (unsigned)n, sizeof(RTCRayHit));
    break;
  }
}

/* A small seeded generator for the light samples (xorshift32). */
static inline float next(uint32_t *s) {
  *s ^= *s << 13, *s ^= *s >> 17, *s ^= *s << 5;
  return (*s >> 8) * (1.0f / 16777216.0f);
}

/* One packet of up to 16 soft-shadow rays of point p (position, normal, origin) towards samples
 * first..first+count of its side × side strata. */
static void soft_packet(RTCRay16 *ray, int *valid, const float *p, const float *light, int side, int first,
                        int count, uint32_t *seed) {
  for (int l = 0; l < 16; l++) {
    int s = first + l;
    valid[l] = 0;
    if (l >= count) continue;
    float u = ((s % side) + next(seed)) / side, v = ((s / side) + next(seed)) / side;
    float target[3], to[3];
    for (int a = 0; a < 3; a++) target[a] = light[a] + light[3 + a] * u + light[6 + a] * v;
    float facing = 0.0f;
    for (int a = 0; a < 3; a++) facing += (target[a] - p[a]) * p[3 + a];
    if (facing <= 0.0f) continue;
    for (int a = 0; a < 3; a++) to[a] = target[a] - p[6 + a];
    float d = sqrtf(to[0] * to[0] + to[1] * to[1] + to[2] * to[2]);
    ray->org_x[l] = p[6], ray->org_y[l] = p[7], ray->org_z[l] = p[8];
    ray->dir_x[l] = to[0] / d, ray->dir_y[l] = to[1] / d, ray->dir_z[l] = to[2] / d;
    ray->tnear[l] = 0.0f, ray->tfar[l] = d * (1.0f - 1e-4f), ray->time[l] = 0.0f;
    ray->mask[l] = 0xFFFFFFFF, ray->flags[l] = 0, ray->id[l] = (unsigned)s;
    valid[l] = -1;
  }
}

/* The soft-shadow query: generation and rtcOccluded16 per 16 samples of each point (pregenerated:
 * the packets made before the clock starts). */
static void soft_shadows(RTCScene scene, RTCIntersectContext *ctx, const Records *points, RTCRay16 *pre,
                         int *pre_valid, int pregenerated) {
  int samples = (int)points->word, side = (int)lroundf(sqrtf((float)samples));
  int packets = (samples + 15) / 16;
  const float *light = points->f;
  RTCRay16 ray __attribute__((aligned(64)));
  int valid[16] __attribute__((aligned(64)));
  uint32_t seed = 0x9E3779B9u;
  for (uint64_t i = 0; i < points->count; i++) {
    const float *p = points->f + 9 + i * 9;
    for (int k = 0; k < packets; k++) {
      size_t at = i * packets + k;
      if (pregenerated) {
        rtcOccluded16(pre_valid + 16 * at, scene, ctx, &pre[at]);
      } else {
        int first = k * 16, count = samples - first < 16 ? samples - first : 16;
        soft_packet(&ray, valid, p, light, side, first, count, &seed);
        rtcOccluded16(valid, scene, ctx, &ray);
      }
    }
  }
}

int main(int argc, char **argv) {
  const char *tris_path = NULL, *work_path = NULL;
  int occluded = 0, repeats = 5;
  for (int i = 1; i < argc; i++) {
    if (!strcmp(argv[i], "--occluded")) occluded = 1;
    else if (!strcmp(argv[i], "--repeats") && i + 1 < argc) repeats = atoi(argv[++i]);
    else if (!tris_path) tris_path = argv[i];
    else if (!work_path) work_path = argv[i];
    else fail("unexpected argument", argv[i]);
  }
  if (!tris_path || !work_path || repeats < 1) {
    fprintf(stderr, "usage: embree-direct SCENE.tris (RAYS.rays [--occluded] | POINTS.points) [--repeats N]\n");
    return 2;
  }
  Records tris = read_records(tris_path, "RAYLABTR", 9, 0);
  size_t length = strlen(work_path);
  int soft = length > 7 && !strcmp(work_path + length - 7, ".points");
  Records work = soft ? read_records(work_path, "RAYLABSP", 9, 9)
                      : read_records(work_path, "RAYLABRY", 8, 0);
  if (!soft && work.word != 0) {
    /* Rays with times: 9 floats each. */
    free(work.f);
    work = read_records(work_path, "RAYLABRY", 9, 0);
  }
  int samples = (int)work.word, side = (int)lroundf(sqrtf((float)samples));
  if (soft && (samples < 1 || side * side != samples)) fail("samples per point is not a perfect square", work_path);

  RTCDevice device = rtcNewDevice(NULL);
  Rays rays = {0};
  RTCRay16 *pre = NULL;
  int *pre_valid = NULL;
  size_t traced;
  if (soft) {
    size_t packets = work.count * (size_t)((samples + 15) / 16);
    pre = aligned(packets * sizeof(RTCRay16));
    pre_valid = aligned(packets * 16 * sizeof(int));
    traced = work.count * (size_t)samples;
  } else {
    rays.n = work.count, rays.stride = work.word ? 9 : 8, rays.f = work.f;
    size_t padded = (rays.n + 15) / 16 * 16;
    rays.single = aligned(rays.n * sizeof(RTCRayHit));
    rays.p4 = aligned(padded / 4 * sizeof(RTCRayHit4));
    rays.p8 = aligned(padded / 8 * sizeof(RTCRayHit8));
    rays.p16 = aligned(padded / 16 * sizeof(RTCRayHit16));
    rays.valid = aligned(padded * sizeof(int));
    for (size_t i = 0; i < padded; i++) rays.valid[i] = i < rays.n ? -1 : 0;
    traced = rays.n;
  }
  printf("%s: %llu triangles; %s: %zu %s\n", tris_path, (unsigned long long)tris.count, work_path, traced,
         soft ? "soft-shadow rays" : (occluded ? "rays, occlusion" : "rays, closest hit"));

  const enum RTCBuildQuality qualities[] = {RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_HIGH};
  const char *quality_names[] = {"medium", "high"};
  const enum RTCIntersectContextFlags contexts[] = {RTC_INTERSECT_CONTEXT_FLAG_COHERENT,
                                                    RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT};
  const char *context_names[] = {"coherent", "incoherent"};
  double best = INFINITY;
  char best_name[128] = "";
  for (int q = 0; q < 2; q++) {
    RTCScene scene = build(device, &tris, qualities[q]);
    for (int c = 0; c < 2; c++) {
      RTCIntersectContext ctx;
      rtcInitIntersectContext(&ctx);
      ctx.flags = contexts[c];
      int entries = soft ? 2 : 5; /* soft: generated in the loop, pregenerated */
      for (int e = 0; e < entries; e++) {
        double fastest = INFINITY;
        for (int pass = 0; pass <= repeats; pass++) {
          if (soft && e == 1) {
            uint32_t seed = 0x9E3779B9u;
            int packets = (samples + 15) / 16;
            for (uint64_t i = 0; i < work.count; i++)
              for (int k = 0; k < packets; k++) {
                int first = k * 16, count = samples - first < 16 ? samples - first : 16;
                size_t at = i * packets + k;
                soft_packet(&pre[at], pre_valid + 16 * at, work.f + 9 + i * 9, work.f, side, first, count, &seed);
              }
          } else if (!soft) {
            reset(&rays);
          }
          double start = now();
          if (soft) soft_shadows(scene, &ctx, &work, pre, pre_valid, e == 1);
          else trace(scene, &ctx, &rays, e, occluded);
          double seconds = now() - start;
          if (pass > 0 && seconds < fastest) fastest = seconds; /* pass 0 warms up */
        }
        char name[128];
        if (soft) snprintf(name, sizeof name, "rtcOccluded16 per point, %s, %s %s", e ? "pregenerated" : "generated in the loop", context_names[c], quality_names[q]);
        else snprintf(name, sizeof name, "rtc%s%s %s %s", occluded ? "Occluded" : "Intersect", ENTRY[e], context_names[c], quality_names[q]);
        printf("  %-64s %10.3f ms %8.3f Mrays/s\n", name, fastest * 1e3, traced / fastest / 1e6);
        if (!(soft && e == 1) && fastest < best) best = fastest, snprintf(best_name, sizeof best_name, "%s", name);
      }
    }
    rtcReleaseScene(scene);
  }
  printf("best: %s: %.3f ms, %.3f Mrays/s\n", best_name, best * 1e3, traced / best / 1e6);
  rtcReleaseDevice(device);
  return 0;
}
