// The C API (gsf/gsf.h) from C11: size queries, argument rejection (NULL, misaligned, too small, bad
// config, corrupt map blobs), and end to end on the simulator's tiny world: every query gives the C++
// API's result bit for bit, one well-constrained query is within 0.5 m / 2 deg of ground truth, and
// map load, init and localize allocate nothing; the two poses of a result are in the frames gsf.h says
// (map-local, and the map's frame with the origin added). The world comes from a C++ fixture (tiny_world_c.h).
// Set GSF_C_API_VERBOSE=1 to print every query's error.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gsf/gsf.h"
#include "tiny_world_c.h"

// A query the C++ tests localize too (test_localizer, test_threads): 0.15 m / 0.6 deg off on x86-64 with 7
// inliers, the largest margin to 0.5 m / 2 deg among the tiny world's unrefined answers.
#define GOOD_QUERY 15u

static int g_checks = 0, g_failures = 0;

static void check(int ok, const char* what, const char* file, int line) {
  ++g_checks;
  if (!ok) {
    ++g_failures;
    fprintf(stderr, "%s:%d: CHECK failed: %s\n", file, line, what);
  }
}
#define CHECK(cond) check((cond) ? 1 : 0, #cond, __FILE__, __LINE__)

static void check_status(int got, int want, const char* what, const char* file, int line) {
  ++g_checks;
  if (got != want) {
    ++g_failures;
    fprintf(stderr, "%s:%d: %s gave %s, expected %s\n", file, line, what, gsf_status_string(got),
            gsf_status_string(want));
  }
}
#define CHECK_STATUS(expr, want) check_status((expr), (want), #expr, __FILE__, __LINE__)

static size_t round_up(size_t n) { return (n + GSF_ALIGNMENT - 1) / GSF_ALIGNMENT * GSF_ALIGNMENT; }

// 16-byte aligned block (C11 aligned_alloc wants a multiple of the alignment); aborts on failure.
static void* block(size_t bytes) {
  void* p = aligned_alloc(GSF_ALIGNMENT, round_up(bytes ? bytes : 1));
  if (p == NULL) abort();
  return p;
}

// Translation (m) and rotation (deg) between two row-major 3x4 poses.
static void pose_error(const double* a, const double* b, double* metres, double* degrees) {
  double dt = 0.0, trace = 0.0;
  for (int r = 0; r < 3; ++r) {
    const double d = a[4 * r + 3] - b[4 * r + 3];
    dt += d * d;
    for (int c = 0; c < 3; ++c) trace += a[4 * r + c] * b[4 * r + c];  // trace(Ra^T Rb)
  }
  double cosine = (trace - 1.0) / 2.0;
  if (cosine > 1.0) cosine = 1.0;
  if (cosine < -1.0) cosine = -1.0;
  *metres = sqrt(dt);
  *degrees = acos(cosine) * 180.0 / 3.14159265358979323846;
}

static int same_result(const gsf_result* a, const gsf_result* b) {
  return a->status == b->status && memcmp(a->map_T_scan, b->map_T_scan, sizeof(a->map_T_scan)) == 0 &&
         memcmp(a->map_frame_T_scan, b->map_frame_T_scan, sizeof(a->map_frame_T_scan)) == 0 &&
         a->inliers == b->inliers && memcmp(&a->confidence, &b->confidence, sizeof(double)) == 0 &&
         a->confident == b->confident && memcmp(&a->score, &b->score, sizeof(double)) == 0 &&
         a->clique_size == b->clique_size && a->clique_nodes == b->clique_nodes &&
         a->query_instances == b->query_instances && a->query_triangles == b->query_triangles &&
         a->triangle_matches == b->triangle_matches && a->gsf_survivors == b->gsf_survivors &&
         a->correspondences == b->correspondences && a->field_probes == b->field_probes &&
         a->field_comparisons == b->field_comparisons && a->refined == b->refined &&
         a->budget_exhausted == b->budget_exhausted && a->capacity_truncated == b->capacity_truncated;
}

static void test_status_strings(void) {
  CHECK(strcmp(gsf_status_string(GSF_STATUS_OK), "Ok") == 0);
  CHECK(strcmp(gsf_status_string(GSF_STATUS_BUFFER_TOO_SMALL), "BufferTooSmall") == 0);
  CHECK(strcmp(gsf_status_string(GSF_STATUS_UNSUPPORTED), "Unsupported") == 0);
  CHECK(strcmp(gsf_status_string(-1), "Unknown") == 0);
  CHECK(strcmp(gsf_status_string(GSF_STATUS_UNSUPPORTED + 1), "Unknown") == 0);
  CHECK(strcmp(gsf_status_string(256), "Unknown") == 0);  // would alias Ok as a uint8_t
}

static void test_sizes(void) {
  gsf_config cfg;
  gsf_config_default(&cfg);
  gsf_config_default(NULL);  // no-op
  CHECK(cfg.struct_bytes == sizeof(gsf_config));
  CHECK(cfg.verify_enabled == 1 && cfg.refine_enabled == 0);
  CHECK(cfg.max_scan_points > 0 && cfg.gsf_tau > 0.0f);
  const size_t storage = gsf_localizer_storage_bytes();
  CHECK(storage > 0 && storage % GSF_ALIGNMENT == 0);
  const size_t ws = gsf_workspace_bytes(&cfg);
  CHECK(ws > 1000000);  // megabytes for the default capacities (docs/memory.md)
  CHECK(gsf_workspace_bytes(NULL) == 0);
  gsf_config bad = cfg;
  bad.match_max_correspondences = 1;  // below the clique's minimum
  CHECK(gsf_workspace_bytes(&bad) == 0);
  bad = cfg;
  bad.struct_bytes = 0;  // not from gsf_config_default
  CHECK(gsf_workspace_bytes(&bad) == 0);
  gsf_config big = cfg;
  big.match_max_correspondences *= 4;
  CHECK(gsf_workspace_bytes(&big) > ws);  // capacities drive the workspace
  gsf_config refine = cfg;
  refine.refine_enabled = 1;
  // The refiner is bound for tracking's ICP either way (LocalizerConfig::track.refine, on by default).
  CHECK(gsf_workspace_bytes(&refine) == ws);
  CHECK(cfg.confidence_min_probability > 0.5f && cfg.confidence_min_probability < 1.0f);  // the decision rule
  bad = cfg;
  bad.confidence_min_probability = 1.5f;  // not a probability
  CHECK(gsf_workspace_bytes(&bad) == 0);
  CHECK(strcmp(gsf_config_check(&bad), "confidence.min_probability") == 0);  // which value, by name
  CHECK(gsf_config_check(&cfg) == NULL);
}

static void test_map_load(const void* blob, size_t bytes) {
  gsf_map map;
  gsf_map_info info;
  unsigned char* copy = block(bytes + GSF_ALIGNMENT);
  memcpy(copy, blob, bytes);
  CHECK_STATUS(gsf_map_load(copy, bytes, &map), GSF_STATUS_OK);
  CHECK_STATUS(gsf_map_get_info(&map, &info), GSF_STATUS_OK);
  CHECK(info.instances > 50 && info.triangles > 500 && info.total_bytes == bytes && info.road_length_m > 500.0f);
  CHECK_STATUS(gsf_map_get_info(NULL, &info), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_map_get_info(&map, NULL), GSF_STATUS_INVALID_ARGUMENT);

  CHECK_STATUS(gsf_map_load(NULL, bytes, &map), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_map_get_info(&map, &info), GSF_STATUS_INVALID_ARGUMENT);  // a failed load is unusable
  CHECK_STATUS(gsf_map_load(copy, bytes, NULL), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_map_load(copy, 0, &map), GSF_STATUS_TRUNCATED);
  CHECK_STATUS(gsf_map_load(copy, bytes - 1, &map), GSF_STATUS_TRUNCATED);
  CHECK_STATUS(gsf_map_load(copy, bytes + 8, &map), GSF_STATUS_CORRUPT_DATA);  // trailing bytes

  unsigned char* shifted = block(bytes + GSF_ALIGNMENT);  // the same bytes, 8-byte aligned only
  memcpy(shifted + 8, blob, bytes);
  CHECK_STATUS(gsf_map_load(shifted + 8, bytes, &map), GSF_STATUS_INVALID_ARGUMENT);
  free(shifted);

  copy[0] ^= 0xFF;  // magic
  CHECK_STATUS(gsf_map_load(copy, bytes, &map), GSF_STATUS_CORRUPT_DATA);
  memcpy(copy, blob, bytes);
  copy[8] ^= 0x02;  // version (checked before the header CRC)
  CHECK_STATUS(gsf_map_load(copy, bytes, &map), GSF_STATUS_VERSION_MISMATCH);
  memcpy(copy, blob, bytes);
  copy[100] ^= 0x10;  // inside the header's build parameters: header CRC
  CHECK_STATUS(gsf_map_load(copy, bytes, &map), GSF_STATUS_CORRUPT_DATA);
  memcpy(copy, blob, bytes);
  copy[bytes / 2] ^= 0x01;  // one bit in a section: that section's CRC
  CHECK_STATUS(gsf_map_load(copy, bytes, &map), GSF_STATUS_CORRUPT_DATA);
  memcpy(copy, blob, bytes);
  copy[bytes - 20] ^= 0x80;
  CHECK_STATUS(gsf_map_load(copy, bytes, &map), GSF_STATUS_CORRUPT_DATA);
  free(copy);
}

// Localizes query k against `blob` (copied into aligned memory) with the default config.
static int localize_with(const void* blob, size_t bytes, uint32_t k, gsf_map_info* info, gsf_result* out) {
  gsf_config cfg;
  gsf_config_default(&cfg);
  const size_t sb = gsf_localizer_storage_bytes(), wb = gsf_workspace_bytes(&cfg);
  void* storage = block(sb);
  void* ws = block(wb);
  void* copy = block(bytes);
  memcpy(copy, blob, bytes);
  gsf_map map;
  gsf_localizer* loc = NULL;
  gsf_test_query q;
  int s = gsf_map_load(copy, bytes, &map);
  if (s == GSF_STATUS_OK) s = gsf_map_get_info(&map, info);
  if (s == GSF_STATUS_OK) s = gsf_localizer_init(storage, sb, &cfg, &map, ws, wb, &loc);
  if (s == GSF_STATUS_OK) s = gsf_test_tiny_query(k, &q);
  if (s == GSF_STATUS_OK) s = gsf_localize(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, out);
  free(copy);
  free(ws);
  free(storage);
  return s;
}

// Which frame each pose is in: the tiny map (origin 0, "local") and the same map georeferenced at a
// UTM-size origin give the same map-local pose bit for bit; map_frame_T_scan is it plus the origin, and
// only map_frame_T_scan matches the truth posed in the map's frame.
static void test_pose_frames(const void* blob, size_t bytes) {
  const double origin[3] = {512345.0, 5412343.0, 2.0};
  size_t geo_bytes = 0;
  const void* geo = gsf_test_tiny_map_georeferenced(origin, "utm-32N", &geo_bytes);
  CHECK(geo != NULL && geo_bytes == bytes);
  if (geo == NULL) return;
  gsf_map_info local_info, geo_info;
  gsf_result local, utm;
  CHECK_STATUS(localize_with(blob, bytes, GOOD_QUERY, &local_info, &local), GSF_STATUS_OK);
  CHECK(local_info.origin[0] == 0.0 && local_info.origin[1] == 0.0 && local_info.origin[2] == 0.0);
  CHECK(strcmp(local_info.frame, "local") == 0);
  CHECK(memcmp(local.map_T_scan, local.map_frame_T_scan, sizeof(local.map_T_scan)) == 0);  // origin 0
  CHECK_STATUS(localize_with(geo, geo_bytes, GOOD_QUERY, &geo_info, &utm), GSF_STATUS_OK);
  CHECK(geo_info.origin[0] == origin[0] && geo_info.origin[1] == origin[1] && geo_info.origin[2] == origin[2]);
  CHECK(strcmp(geo_info.frame, "utm-32N") == 0);
  CHECK(memcmp(local.map_T_scan, utm.map_T_scan, sizeof(local.map_T_scan)) == 0);  // map-local: unchanged
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) CHECK(utm.map_frame_T_scan[4 * r + c] == utm.map_T_scan[4 * r + c]);
    CHECK(utm.map_frame_T_scan[4 * r + 3] == utm.map_T_scan[4 * r + 3] + origin[r]);  // added in double
  }
  gsf_test_query q;
  CHECK_STATUS(gsf_test_tiny_query(GOOD_QUERY, &q), GSF_STATUS_OK);
  double truth_utm[12];
  memcpy(truth_utm, q.truth, sizeof(truth_utm));
  for (int r = 0; r < 3; ++r) truth_utm[4 * r + 3] += origin[r];
  double m, deg;
  pose_error(utm.map_frame_T_scan, truth_utm, &m, &deg);
  CHECK(m < 0.5 && deg < 2.0);
  pose_error(utm.map_T_scan, truth_utm, &m, &deg);
  CHECK(m > 5.0e6);  // the map-local pose is not in the map's frame
}

static void test_init_rejects(const gsf_map* map) {
  gsf_config cfg;
  gsf_config_default(&cfg);
  const size_t sb = gsf_localizer_storage_bytes(), wb = gsf_workspace_bytes(&cfg);
  unsigned char* storage = block(sb + GSF_ALIGNMENT);
  unsigned char* ws = block(wb + GSF_ALIGNMENT);
  gsf_localizer* loc = (gsf_localizer*)&loc;  // must be reset to NULL on every failure

  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, map, ws, wb, NULL), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localizer_init(NULL, sb, &cfg, map, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  CHECK(loc == NULL);
  CHECK_STATUS(gsf_localizer_init(storage + 8, sb, &cfg, map, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localizer_init(storage + 1, sb, &cfg, map, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localizer_init(storage, sb - 1, &cfg, map, ws, wb, &loc), GSF_STATUS_BUFFER_TOO_SMALL);
  CHECK_STATUS(gsf_localizer_init(storage, 0, &cfg, map, ws, wb, &loc), GSF_STATUS_BUFFER_TOO_SMALL);
  CHECK_STATUS(gsf_localizer_init(storage, sb, NULL, map, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, NULL, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, map, NULL, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, map, ws + 8, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, map, ws + 4, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, map, ws, wb - 1, &loc), GSF_STATUS_BUFFER_TOO_SMALL);
  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, map, ws, 0, &loc), GSF_STATUS_BUFFER_TOO_SMALL);
  CHECK(loc == NULL);

  gsf_map never_loaded;
  memset(&never_loaded, 0, sizeof(never_loaded));
  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, &never_loaded, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  gsf_map failed;
  memset(ws, 0, 4096);
  CHECK_STATUS(gsf_map_load(ws, 4096, &failed), GSF_STATUS_CORRUPT_DATA);  // not a map
  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, &failed, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);

  gsf_config bad = cfg;
  bad.struct_bytes = sizeof(gsf_config) - 4;
  CHECK_STATUS(gsf_localizer_init(storage, sb, &bad, map, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  bad = cfg;
  bad.refine_enabled = 2;  // flags are 0 or 1
  CHECK_STATUS(gsf_localizer_init(storage, sb, &bad, map, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  bad = cfg;
  bad.match_max_correspondences = 1;
  CHECK_STATUS(gsf_localizer_init(storage, sb, &bad, map, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  bad = cfg;
  bad.field_length_scale *= 2.0f;  // the map was built with the default
  CHECK_STATUS(gsf_localizer_init(storage, sb, &bad, map, ws, wb, &loc), GSF_STATUS_CONFIG_MISMATCH);
  bad = cfg;
  bad.label_set = 2;  // no such built-in label set
  CHECK_STATUS(gsf_localizer_init(storage, sb, &bad, map, ws, wb, &loc), GSF_STATUS_INVALID_ARGUMENT);
  CHECK(gsf_workspace_bytes(&bad) == 0);
  bad = cfg;
  bad.label_set = GSF_LABEL_SET_NUSCENES_LIDARSEG;  // the map was built with SemanticKITTI's
  CHECK(gsf_workspace_bytes(&bad) > wb);            // the geometric-pole stage
  {
    unsigned char* big = block(gsf_workspace_bytes(&bad));
    CHECK_STATUS(gsf_localizer_init(storage, sb, &bad, map, big, gsf_workspace_bytes(&bad), &loc),
                 GSF_STATUS_CONFIG_MISMATCH);
    free(big);
  }
  CHECK(loc == NULL);

  // A working handle stops working once a re-init of its storage fails.
  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, map, ws, wb, &loc), GSF_STATUS_OK);
  CHECK(loc != NULL);
  gsf_localizer* const first = loc;
  gsf_test_query q;
  gsf_result r;
  CHECK_STATUS(gsf_test_tiny_query(GOOD_QUERY, &q), GSF_STATUS_OK);
  CHECK_STATUS(gsf_localize(first, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, &r), GSF_STATUS_OK);
  CHECK_STATUS(gsf_localizer_init(storage, sb, &bad, map, ws, wb, &loc), GSF_STATUS_CONFIG_MISMATCH);
  CHECK(loc == NULL);
  CHECK_STATUS(gsf_localize(first, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, &r),
               GSF_STATUS_NOT_INITIALIZED);
  CHECK(r.status == GSF_STATUS_NOT_INITIALIZED && r.inliers == 0);
  free(ws);
  free(storage);
}

static void test_localize_rejects(gsf_localizer* loc) {
  gsf_test_query q;
  gsf_result r;
  CHECK_STATUS(gsf_test_tiny_query(GOOD_QUERY, &q), GSF_STATUS_OK);
  const uint32_t D = GSF_NUM_CLASSES;
  memset(&r, 0xAB, sizeof(r));
  CHECK_STATUS(gsf_localize(NULL, q.xyzi, 4, q.count, q.labels, q.logits, D, &r), GSF_STATUS_INVALID_ARGUMENT);
  CHECK(r.status == GSF_STATUS_INVALID_ARGUMENT && r.inliers == 0 && r.map_T_scan[0] == 1.0 && r.confident == 0 &&
        r.confidence == 0.0);
  CHECK_STATUS(gsf_localize(loc, NULL, 4, q.count, q.labels, q.logits, D, &r), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localize(loc, q.xyzi, 4, q.count, NULL, q.logits, D, &r), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localize(loc, q.xyzi, 2, q.count, q.labels, q.logits, D, &r), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localize(loc, q.xyzi, 4, q.count, q.labels, q.logits, 7, &r), GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localize(loc, q.xyzi, 4, 0, q.labels, q.logits, D, &r), GSF_STATUS_INVALID_INPUT);
  CHECK_STATUS(gsf_localize(loc, q.xyzi, 4, 300000, q.labels, q.logits, D, &r), GSF_STATUS_CAPACITY_EXCEEDED);
  // A result pointer is optional; the status still comes back.
  CHECK_STATUS(gsf_localize(loc, q.xyzi, 4, q.count, q.labels, q.logits, D, NULL), GSF_STATUS_OK);
  // Without logits (labels only) it still localizes.
  CHECK_STATUS(gsf_localize(loc, q.xyzi, 4, q.count, q.labels, NULL, 0, &r), GSF_STATUS_OK);
  // xyz in a stride-3 array: the same pose as the stride-4 records.
  float* xyz = block(sizeof(float) * 3 * q.count);
  for (uint32_t i = 0; i < q.count; ++i) memcpy(xyz + 3 * i, q.xyzi + 4 * i, 3 * sizeof(float));
  gsf_result r3, r4;
  CHECK_STATUS(gsf_localize(loc, xyz, 3, q.count, q.labels, q.logits, D, &r3), GSF_STATUS_OK);
  CHECK_STATUS(gsf_localize(loc, q.xyzi, 4, q.count, q.labels, q.logits, D, &r4), GSF_STATUS_OK);
  CHECK(same_result(&r3, &r4));
  free(xyz);
}

static void test_end_to_end(const void* blob, size_t bytes) {
  gsf_config cfg;
  gsf_config_default(&cfg);
  const size_t sb = gsf_localizer_storage_bytes(), wb = gsf_workspace_bytes(&cfg);
  void* storage = block(sb);
  void* ws = block(wb);
  void* map_blob = block(bytes);
  memcpy(map_blob, blob, bytes);
  gsf_map map;
  gsf_localizer* loc = NULL;
  const uint32_t n = gsf_test_tiny_query_count();
  gsf_test_query* queries = block(sizeof(gsf_test_query) * n);
  gsf_result* mine = block(sizeof(gsf_result) * n);
  gsf_result* cpp = block(sizeof(gsf_result) * n);
  for (uint32_t k = 0; k < n; ++k) CHECK_STATUS(gsf_test_tiny_query(k, &queries[k]), GSF_STATUS_OK);
  for (uint32_t k = 0; k < n; ++k) gsf_test_cpp_localize(k, &cpp[k]);

  // Negative control: the counter sees this program's own malloc (aligned_alloc is wrapped too).
  const uint64_t control = gsf_test_allocations();
  free(block(64));
  CHECK(gsf_test_allocations() == control + 1);

  // Load, init and every localize call: no heap (the map is used in place, memory is the caller's).
  const uint64_t before = gsf_test_allocations();
  const int load = gsf_map_load(map_blob, bytes, &map);
  const int init = gsf_localizer_init(storage, sb, &cfg, &map, ws, wb, &loc);
  for (uint32_t k = 0; k < n && init == GSF_STATUS_OK; ++k) {
    const gsf_test_query* q = &queries[k];
    gsf_localize(loc, q->xyzi, 4, q->count, q->labels, q->logits, GSF_NUM_CLASSES, &mine[k]);
  }
  const uint64_t allocations = gsf_test_allocations() - before;
  CHECK_STATUS(load, GSF_STATUS_OK);
  CHECK_STATUS(init, GSF_STATUS_OK);
  CHECK(allocations == 0);
  CHECK(n >= 20);

  const int verbose = getenv("GSF_C_API_VERBOSE") != NULL;
  uint32_t same = 0, ok = 0;
  for (uint32_t k = 0; k < n; ++k) {
    double m, deg;
    pose_error(mine[k].map_T_scan, queries[k].truth, &m, &deg);
    same += (uint32_t)same_result(&mine[k], &cpp[k]);
    ok += (uint32_t)(mine[k].status == GSF_STATUS_OK && m < 5.0 && deg < 10.0);
    if (verbose)
      printf("query %2u %-12s inliers %3u confidence %.3f error %8.3f m %7.3f deg%s\n", k,
             gsf_status_string(mine[k].status), mine[k].inliers, mine[k].confidence, m, deg,
             queries[k].in_zone ? " (zone)" : "");
  }
  CHECK(same == n);         // the C API is the C++ API, bit for bit
  CHECK(ok * 10 >= n * 6);  // test_localizer's success bar

  double m, deg;
  pose_error(mine[GOOD_QUERY].map_T_scan, queries[GOOD_QUERY].truth, &m, &deg);
  CHECK_STATUS(mine[GOOD_QUERY].status, GSF_STATUS_OK);
  CHECK(m < 0.5 && deg < 2.0);
  CHECK(mine[GOOD_QUERY].inliers >= 5);

  test_localize_rejects(loc);
  free(cpp);
  free(mine);
  free(queries);
  free(map_blob);
  free(ws);
  free(storage);
}

// The vehicle modes through the C API: a prior around the truth gives the right pose, bad priors and
// predictions are refused, tracking from 1 m off returns the pose within 0.3 m / 1 deg, confident, and
// from 30 m off a loss (not confident); a sequence reports its scans; none of it allocates.
static void test_vehicle_modes(const void* blob, size_t bytes) {
  gsf_config cfg;
  gsf_config_default(&cfg);
  const size_t sb = gsf_localizer_storage_bytes(), wb = gsf_workspace_bytes(&cfg);
  void* storage = block(sb);
  void* ws = block(wb);
  void* copy = block(bytes);
  memcpy(copy, blob, bytes);
  gsf_map map;
  gsf_localizer* loc = NULL;
  gsf_test_query q;
  CHECK_STATUS(gsf_map_load(copy, bytes, &map), GSF_STATUS_OK);
  CHECK_STATUS(gsf_localizer_init(storage, sb, &cfg, &map, ws, wb, &loc), GSF_STATUS_OK);
  CHECK_STATUS(gsf_test_tiny_query(GOOD_QUERY, &q), GSF_STATUS_OK);
  gsf_position_prior prior = {q.truth[3] + 8.0, q.truth[7] - 6.0, 20.0f, 0, 0.0f, 180.0f};
  gsf_result r;
  double m, deg, predicted[12];
  const uint64_t before = gsf_test_allocations();
  CHECK_STATUS(gsf_localize_with_prior(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, &prior, &r),
               GSF_STATUS_OK);
  pose_error(r.map_frame_T_scan, q.truth, &m, &deg);
  CHECK(m < 0.5 && deg < 2.0);
  prior.radius_m = -1.0f;
  CHECK_STATUS(gsf_localize_with_prior(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, &prior, &r),
               GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_localize_with_prior(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, NULL, &r),
               GSF_STATUS_INVALID_ARGUMENT);
  memcpy(predicted, q.truth, sizeof(predicted));
  predicted[3] += 0.8;
  predicted[7] -= 0.6;
  CHECK_STATUS(gsf_track(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, predicted, &r), GSF_STATUS_OK);
  pose_error(r.map_frame_T_scan, q.truth, &m, &deg);
  CHECK(m < 0.3 && deg < 1.0);
  CHECK(r.confident == 1);
  predicted[3] += 30.0;
  CHECK_STATUS(gsf_track(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, predicted, &r), GSF_STATUS_OK);
  CHECK(r.confident == 0);
  predicted[3] = NAN;
  CHECK_STATUS(gsf_track(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, predicted, &r),
               GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_track(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, NULL, &r),
               GSF_STATUS_INVALID_ARGUMENT);
  CHECK_STATUS(gsf_track(NULL, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, predicted, &r),
               GSF_STATUS_INVALID_ARGUMENT);
  // Several scans: a sequence of the same scan (odometry: standing still); the first call starts it.
  {
    const double still[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    gsf_window_info info;
    gsf_result alone;
    CHECK_STATUS(gsf_localize(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, &alone), GSF_STATUS_OK);
    CHECK_STATUS(gsf_localize_sequence(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, NULL, &r, &info),
                 GSF_STATUS_OK);
    CHECK(info.sequence_index == 0 && info.scans == 1 && info.ids[0] == 0 && info.combined == 0);
    CHECK(info.single_confidence == alone.confidence);
    CHECK(r.confidence >= alone.confidence || info.contradicted == 1);
    CHECK_STATUS(gsf_localize_sequence(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, still, &r, &info),
                 GSF_STATUS_OK);
    CHECK(info.sequence_index == 1);
    CHECK(info.scans >= 1 && info.ids[0] == 1);
    pose_error(r.map_frame_T_scan, q.truth, &m, &deg);
    CHECK(m < 5.0 && deg < 10.0);
    CHECK_STATUS(gsf_localize_sequence(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, still, &r, NULL),
                 GSF_STATUS_OK);
    double bad[12];
    memcpy(bad, still, sizeof(bad));
    bad[3] = NAN;
    CHECK_STATUS(gsf_localize_sequence(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, bad, &r, &info),
                 GSF_STATUS_INVALID_ARGUMENT);
    CHECK_STATUS(gsf_localize_sequence(NULL, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, still, &r, &info),
                 GSF_STATUS_INVALID_ARGUMENT);
  }
  {
    // The vehicle loop: a start-up (NULL odometry), then the same scan again without motion: tracked.
    const double still[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    gsf_drive_info drive;
    CHECK_STATUS(
        gsf_localize_next(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, NULL, NULL, &r, &drive),
        GSF_STATUS_OK);
    CHECK(drive.tracked == 0 && drive.track_lost == 0 && drive.prior_used == 0 && drive.window.sequence_index == 0);
    CHECK(r.confident == 1);
    CHECK_STATUS(
        gsf_localize_next(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, still, NULL, &r, &drive),
        GSF_STATUS_OK);
    CHECK(drive.tracked == 1 && drive.track_lost == 0);
    pose_error(r.map_frame_T_scan, q.truth, &m, &deg);
    CHECK(m < 5.0 && deg < 10.0);
    // A start-up with a GNSS prior at the truth.
    gsf_position_prior gnss;
    memset(&gnss, 0, sizeof(gnss));
    gnss.x = q.truth[3];
    gnss.y = q.truth[7];
    gnss.radius_m = 20.0f;
    CHECK_STATUS(gsf_localize_next(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, NULL, &gnss, &r, NULL),
                 GSF_STATUS_OK);
    CHECK_STATUS(
        gsf_localize_next(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, NULL, &gnss, &r, &drive),
        GSF_STATUS_OK);
    CHECK(drive.prior_used == 1 && drive.tracked == 0);
    // Bad input: a NaN odometry, an invalid prior, no localizer.
    double bad[12];
    memcpy(bad, still, sizeof(bad));
    bad[3] = NAN;
    CHECK_STATUS(gsf_localize_next(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, bad, NULL, &r, &drive),
                 GSF_STATUS_INVALID_ARGUMENT);
    gnss.has_heading = 7;
    CHECK_STATUS(gsf_localize_next(loc, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, NULL, &gnss, &r, NULL),
                 GSF_STATUS_INVALID_ARGUMENT);
    CHECK_STATUS(gsf_localize_next(NULL, q.xyzi, 4, q.count, q.labels, q.logits, GSF_NUM_CLASSES, NULL, NULL, &r, NULL),
                 GSF_STATUS_INVALID_ARGUMENT);
  }
  CHECK(gsf_test_allocations() == before);
  free(copy);
  free(ws);
  free(storage);
}

int main(void) {
  size_t bytes = 0;
  const void* blob = gsf_test_tiny_map(&bytes);
  test_status_strings();
  test_sizes();
  test_map_load(blob, bytes);
  {
    gsf_map map;
    void* copy = block(bytes);
    memcpy(copy, blob, bytes);
    CHECK_STATUS(gsf_map_load(copy, bytes, &map), GSF_STATUS_OK);
    test_init_rejects(&map);
    free(copy);
  }
  test_end_to_end(blob, bytes);
  test_pose_frames(blob, bytes);
  test_vehicle_modes(blob, bytes);
  printf("test_c_api: %d checks, %d failed\n", g_checks, g_failures);
  return g_failures == 0 ? 0 : 1;
}
