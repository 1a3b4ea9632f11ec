// Embree's traversal statistics on the anchors' rays: builds the MEDIUM scene of a mesh (as
// ../shared/anchors/embree_bench.c does), traces one ray file once on one thread with
// rtcIntersect1 (closest) or rtcOccluded1 (any hit), and prints nodes, leaves and Triangle4
// blocks a ray. Needs an Embree built with EMBREE_STAT_COUNTERS=ON (scripts/embree-stats.sh) for
// the counters; linked to any Embree 3 it traces the same rays (for callgrind, see
// docs/performance.md). EVERY (default 1) traces every EVERY-th ray only.
// usage: embree_stats MESH.obj RAYS.rays closest|any [EVERY]
#include <embree3/rtcore.h>
#include "common.h"

int main(int argc, char** argv) {
  if (argc != 4 && argc != 5) {
    fprintf(stderr, "usage: embree_stats MESH.obj RAYS.rays closest|any [EVERY]\n"); return 2;
  }
  uint64_t every = argc == 5 ? strtoull(argv[4], NULL, 10) : 1;
  if (every == 0) { fprintf(stderr, "EVERY must be at least 1\n"); return 2; }
  Mesh m = load_obj(argv[1]);
  uint64_t n; RayRec* r = read_rays(argv[2], &n);
  int any = strcmp(argv[3], "any") == 0;
  RTCDevice dev = rtcNewDevice("threads=1");
  RTCScene s = rtcNewScene(dev);
  rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_MEDIUM);
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_MEDIUM);
  float* vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, m.nv);
  memcpy(vb, m.v, m.nv * 12);
  uint32_t* ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, m.nt);
  memcpy(ib, m.idx, m.nt * 12);
  rtcCommitGeometry(g); rtcAttachGeometry(s, g); rtcReleaseGeometry(g); rtcCommitScene(s);
  struct RTCIntersectContext ctx; rtcInitIntersectContext(&ctx);
  uint64_t hits = 0;
  uint64_t traced = 0;
  for (uint64_t i = 0; i < n; i += every, traced++) {
    RayRec* q = &r[i]; struct RTCRayHit rh;
    rh.ray.org_x = q->ox; rh.ray.org_y = q->oy; rh.ray.org_z = q->oz; rh.ray.tnear = q->tmin;
    rh.ray.dir_x = q->dx; rh.ray.dir_y = q->dy; rh.ray.dir_z = q->dz; rh.ray.tfar = q->tmax;
    rh.ray.mask = -1; rh.ray.flags = 0; rh.ray.time = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID; rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    if (any) { rtcOccluded1(s, &ctx, &rh.ray); hits += rh.ray.tfar < 0; }
    else { rtcIntersect1(s, &ctx, &rh); hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID; }
  }
  // Embree prints its counters (per ray under "--- PER RAY ---"-like headings) when the
  // library unloads, after this line.
  printf("rays %lu hits %lu\n", (unsigned long)traced, (unsigned long)hits);
  fflush(stdout);
  rtcReleaseScene(s); rtcReleaseDevice(dev);
  return 0;
}
