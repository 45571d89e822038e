#include "tiny_world_c.h"

#include <cstring>
#include <vector>

#include "alloc_counter.h"
#include "gsf/localizer.h"
#include "tiny_world.h"

namespace {

void to_c(const gsf::LocalizeResult& r, gsf_result* out) {
  std::memset(out, 0, sizeof(*out));
  out->status = static_cast<int>(r.status);
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) {
      out->map_T_scan[4 * row + col] = r.map_T_scan.linear()(row, col);
      out->map_frame_T_scan[4 * row + col] = r.map_frame_T_scan.linear()(row, col);
    }
    out->map_T_scan[4 * row + 3] = r.map_T_scan.translation()(row);
    out->map_frame_T_scan[4 * row + 3] = r.map_frame_T_scan.translation()(row);
  }
  out->inliers = r.inliers;
  out->confidence = r.confidence;
  out->score = r.score;
  out->clique_nodes = r.clique_nodes;
  out->clique_size = r.clique_size;
  out->query_instances = r.query_instances;
  out->query_triangles = r.query_triangles;
  out->triangle_matches = r.triangle_matches;
  out->gsf_survivors = r.gsf_survivors;
  out->correspondences = r.correspondences;
  out->field_probes = r.field_probes;
  out->field_comparisons = r.field_comparisons;
  out->refined = r.refined;
  out->budget_exhausted = r.budget_exhausted;
  out->capacity_truncated = r.capacity_truncated;
  out->confident = r.confident;
}

}  // namespace

extern "C" {

const void* gsf_test_tiny_map(size_t* bytes) {
  const gsf_test::TinyWorld& w = gsf_test::tiny_world();
  if (bytes) *bytes = w.bytes;
  return w.blob.data();
}

const void* gsf_test_tiny_map_georeferenced(const double origin[3], const char* frame, size_t* bytes) {
  static std::vector<uint64_t> blob;
  gsf::MapView view = gsf_test::tiny_world().map;
  for (int k = 0; k < 3; ++k) view.georef.origin[k] = origin[k];
  if (!gsf::set_frame_name(&view.georef, frame)) return nullptr;
  const size_t size = gsf::map_serialized_size(view);
  blob.assign(size / 8 + 2, 0);
  if (gsf::write_map(view, blob.data(), blob.size() * 8, bytes) != gsf::Status::Ok) return nullptr;
  return blob.data();
}

uint32_t gsf_test_tiny_query_count(void) { return static_cast<uint32_t>(gsf_test::tiny_world().queries.size()); }

int gsf_test_tiny_query(uint32_t k, gsf_test_query* out) {
  const gsf_test::TinyWorld& w = gsf_test::tiny_world();
  if (out == nullptr) return GSF_STATUS_INVALID_ARGUMENT;
  if (k >= w.queries.size()) return GSF_STATUS_NOT_FOUND;
  const gsf_test::QueryScan& q = w.queries[k];
  out->xyzi = q.xyzi.data();
  out->labels = q.labels.data();
  out->logits = q.logits.data();
  out->count = static_cast<uint32_t>(q.labels.size());
  out->in_zone = q.in_zone ? 1 : 0;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) out->truth[4 * row + col] = q.truth.matrix()(row, col);
  return GSF_STATUS_OK;
}

int gsf_test_cpp_localize(uint32_t k, gsf_result* out) {
  const gsf_test::TinyWorld& w = gsf_test::tiny_world();
  static std::vector<uint64_t> workspace(gsf::Localizer::required_bytes(w.config) / 8 + 2);
  static gsf::Localizer localizer;
  if (!localizer.initialized() &&
      localizer.init(w.config, w.map, workspace.data(), workspace.size() * 8) != gsf::Status::Ok)
    return GSF_STATUS_NOT_INITIALIZED;
  if (k >= w.queries.size()) return GSF_STATUS_NOT_FOUND;
  gsf::LocalizeResult r;
  localizer.localize(w.queries[k].view(), &r);
  to_c(r, out);
  return out->status;
}

uint64_t gsf_test_allocations(void) { return gsf_test::alloc_stats().allocations; }

}  // extern "C"
