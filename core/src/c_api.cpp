// C API (gsf/gsf.h) over the C++ facade. Only placement new into caller storage; no heap, no exceptions.
#include "gsf/gsf.h"

#include "gsf/class_table.h"

#include <cstddef>
#include <cstring>
#include <new>
#include <type_traits>

#include "gsf/config.h"
#include "gsf/localizer.h"
#include "gsf/map_format.h"
#include "gsf/semantic_classes.h"
#include "gsf/status.h"

namespace {

using gsf::Status;

#define GSF_SAME_STATUS(c, s) static_assert((c) == static_cast<int>(Status::s), "gsf.h status " #s)
GSF_SAME_STATUS(GSF_STATUS_OK, Ok);
GSF_SAME_STATUS(GSF_STATUS_INVALID_ARGUMENT, InvalidArgument);
GSF_SAME_STATUS(GSF_STATUS_INVALID_INPUT, InvalidInput);
GSF_SAME_STATUS(GSF_STATUS_CAPACITY_EXCEEDED, CapacityExceeded);
GSF_SAME_STATUS(GSF_STATUS_BUFFER_TOO_SMALL, BufferTooSmall);
GSF_SAME_STATUS(GSF_STATUS_NOT_INITIALIZED, NotInitialized);
GSF_SAME_STATUS(GSF_STATUS_CORRUPT_DATA, CorruptData);
GSF_SAME_STATUS(GSF_STATUS_VERSION_MISMATCH, VersionMismatch);
GSF_SAME_STATUS(GSF_STATUS_CONFIG_MISMATCH, ConfigMismatch);
GSF_SAME_STATUS(GSF_STATUS_TRUNCATED, Truncated);
GSF_SAME_STATUS(GSF_STATUS_IO_ERROR, IoError);
GSF_SAME_STATUS(GSF_STATUS_NOT_FOUND, NotFound);
GSF_SAME_STATUS(GSF_STATUS_BUDGET_EXHAUSTED, BudgetExhausted);
GSF_SAME_STATUS(GSF_STATUS_NO_SOLUTION, NoSolution);
GSF_SAME_STATUS(GSF_STATUS_UNSUPPORTED, Unsupported);
#undef GSF_SAME_STATUS
static_assert(GSF_NUM_CLASSES == gsf::kNumClasses, "gsf.h GSF_NUM_CLASSES");
static_assert(GSF_MAP_FRAME_NAME_BYTES == gsf::kMapFrameNameBytes, "gsf.h GSF_MAP_FRAME_NAME_BYTES");

// Tags mark storage that holds a live object (a loaded map, an initialised localizer), so a gsf_map that
// was never loaded or a handle whose re-init failed is refused instead of read.
constexpr uint64_t kMapTag = 0x5650414d30465347ull;   // "GSF0MAPV"
constexpr uint64_t kHandleTag = 0x434f4c30465347ull;  // "GSF0LOC"

struct MapSlot {
  uint64_t tag;
  gsf::MapView view;
};
static_assert(sizeof(MapSlot) <= sizeof(gsf_map), "gsf_map too small for a MapView: grow gsf_map::opaque");
static_assert(alignof(MapSlot) <= alignof(gsf_map), "gsf_map under-aligned");
static_assert(offsetof(MapSlot, tag) == 0, "tag first");
static_assert(std::is_trivially_destructible<MapSlot>::value, "gsf_map has no teardown");

struct Handle {
  uint64_t tag;
  gsf::Localizer localizer;
};
static_assert(alignof(Handle) <= GSF_ALIGNMENT, "storage alignment");
static_assert(std::is_trivially_destructible<Handle>::value, "the C API has no teardown call");

constexpr size_t kHandleBytes = (sizeof(Handle) + GSF_ALIGNMENT - 1) / GSF_ALIGNMENT * GSF_ALIGNMENT;

bool aligned(const void* p) { return reinterpret_cast<uintptr_t>(p) % GSF_ALIGNMENT == 0; }

// Both live at the start of their (tagged) storage; std::launder because they were placement-new'ed.
uint64_t tag_at(const void* p) {
  uint64_t tag;
  std::memcpy(&tag, p, sizeof(tag));
  return tag;
}
const MapSlot* loaded_map(const gsf_map* m) {
  if (m == nullptr || tag_at(m->opaque) != kMapTag) return nullptr;
  return std::launder(reinterpret_cast<const MapSlot*>(m->opaque));
}
Handle* live_handle(gsf_localizer* h) {
  if (h == nullptr || !aligned(h) || tag_at(h) != kHandleTag) return nullptr;
  return std::launder(reinterpret_cast<Handle*>(h));
}

bool flag(uint32_t v, bool* out) {
  if (v > 1) return false;
  *out = v == 1;
  return true;
}

// gsf_config -> LocalizerConfig (C++ defaults for every value the C struct does not carry).
bool to_cpp(const gsf_config* c, gsf::LocalizerConfig* out) {
  if (c == nullptr || c->struct_bytes != sizeof(gsf_config)) return false;
  gsf::LocalizerConfig k;
  k.max_scan_points = c->max_scan_points;
  k.voxel.min_range = c->voxel_min_range;
  k.voxel.max_range = c->voxel_max_range;
  k.voxel.max_voxels = c->voxel_max_voxels;
  k.cluster.max_instances = c->cluster_max_instances;
  if (!flag(c->match_use_gsf, &k.match.use_gsf)) return false;
  k.gsf.tau = c->gsf_tau;
  k.match.min_similarity = c->match_min_similarity;
  k.gsf.observed_variance = c->gsf_observed_variance;
  k.gsf.normalize_mass = c->gsf_normalize_mass;
  k.gsf.covariance_weight = c->gsf_covariance_weight;
  k.gsf.yaw_bins = c->gsf_yaw_bins;
  k.match.max_correspondences = c->match_max_correspondences;
  k.match.max_matches_per_triangle = c->match_max_matches_per_triangle;
  k.triangle.relative_side_tolerance = c->triangle_relative_side_tolerance;
  k.hypotheses.consistency_eps = c->hypotheses_consistency_eps;
  k.hypotheses.first_budget = c->hypotheses_first_budget;
  k.hypotheses.next_budget = c->hypotheses_next_budget;
  k.hypotheses.tls_threshold = c->hypotheses_tls_threshold;
  k.hypotheses.min_inliers = c->hypotheses_min_inliers;
  k.hypotheses.max_hypotheses = c->hypotheses_max_hypotheses;
  if (!flag(c->verify_enabled, &k.verify.enabled)) return false;
  k.triangle.max_triangles = c->triangle_max_triangles;
  if (!flag(c->refine_enabled, &k.refine.enabled)) return false;
  k.confidence.min_probability = c->confidence_min_probability;
  k.voxel.voxel_size = c->voxel_size;
  k.field.length_scale = c->field_length_scale;
  k.field.radius = c->field_radius;
  k.field.grid_spacing = c->field_grid_spacing;
  k.field.noise_variance = c->field_noise_variance;
  k.field.inducing_points = c->field_inducing_points;
  k.field.grid_nx = c->field_grid_nx;
  k.field.grid_ny = c->field_grid_ny;
  k.triangle.neighbours = c->triangle_neighbours;
  // Built-in tables in static storage, built on first use (read-only afterwards; init copies them).
  if (c->label_set == GSF_LABEL_SET_NUSCENES_LIDARSEG) {
    static const gsf::ClassTable nuscenes = [] {
      gsf::ClassTable t;
      gsf::nuscenes_lidarseg_class_table(&t);
      return t;
    }();
    k.classes = &nuscenes;
  } else if (c->label_set != GSF_LABEL_SET_SEMANTIC_KITTI) {
    return false;
  }
  *out = k;
  return true;
}

void fill(const gsf::LocalizeResult& r, gsf_result* out) {
  std::memset(out, 0, sizeof(*out));
  out->status = static_cast<int>(r.status);
  const Eigen::Matrix4d& m = r.map_T_scan.matrix();
  const Eigen::Matrix4d& f = r.map_frame_T_scan.matrix();
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) {
      out->map_T_scan[row * 4 + col] = m(row, col);
      out->map_frame_T_scan[row * 4 + col] = f(row, col);
    }
  out->inliers = r.inliers;
  out->clique_size = r.clique_size;
  out->score = r.score;
  out->confidence = r.confidence;
  out->confident = r.confident ? 1u : 0u;
  out->query_instances = r.query_instances;
  out->query_triangles = r.query_triangles;
  out->triangle_matches = r.triangle_matches;
  out->gsf_survivors = r.gsf_survivors;
  out->correspondences = r.correspondences;
  out->field_probes = r.field_probes;
  out->field_comparisons = r.field_comparisons;
  out->clique_nodes = r.clique_nodes;
  out->refined = r.refined ? 1 : 0;
  out->budget_exhausted = r.budget_exhausted ? 1 : 0;
  out->capacity_truncated = r.capacity_truncated ? 1 : 0;
}

int code(Status s) { return static_cast<int>(s); }

}  // namespace

extern "C" {

const char* gsf_status_string(int status) noexcept {
  if (status < GSF_STATUS_OK || status > GSF_STATUS_UNSUPPORTED) return "Unknown";
  return gsf::to_string(static_cast<Status>(status));
}

void gsf_config_default(gsf_config* c) noexcept {
  if (c == nullptr) return;
  const gsf::LocalizerConfig k;
  std::memset(c, 0, sizeof(*c));
  c->struct_bytes = sizeof(gsf_config);
  c->max_scan_points = k.max_scan_points;
  c->voxel_min_range = k.voxel.min_range;
  c->voxel_max_range = k.voxel.max_range;
  c->voxel_max_voxels = k.voxel.max_voxels;
  c->cluster_max_instances = k.cluster.max_instances;
  c->match_use_gsf = k.match.use_gsf ? 1 : 0;
  c->gsf_tau = k.gsf.tau;
  c->match_min_similarity = k.match.min_similarity;
  c->gsf_observed_variance = k.gsf.observed_variance;
  c->gsf_normalize_mass = k.gsf.normalize_mass;
  c->gsf_covariance_weight = k.gsf.covariance_weight;
  c->gsf_yaw_bins = k.gsf.yaw_bins;
  c->match_max_correspondences = k.match.max_correspondences;
  c->match_max_matches_per_triangle = k.match.max_matches_per_triangle;
  c->triangle_relative_side_tolerance = k.triangle.relative_side_tolerance;
  c->hypotheses_consistency_eps = k.hypotheses.consistency_eps;
  c->hypotheses_first_budget = k.hypotheses.first_budget;
  c->hypotheses_next_budget = k.hypotheses.next_budget;
  c->hypotheses_tls_threshold = k.hypotheses.tls_threshold;
  c->hypotheses_min_inliers = k.hypotheses.min_inliers;
  c->hypotheses_max_hypotheses = k.hypotheses.max_hypotheses;
  c->verify_enabled = k.verify.enabled ? 1 : 0;
  c->triangle_max_triangles = k.triangle.max_triangles;
  c->refine_enabled = k.refine.enabled ? 1 : 0;
  c->confidence_min_probability = k.confidence.min_probability;
  c->voxel_size = k.voxel.voxel_size;
  c->field_length_scale = k.field.length_scale;
  c->field_radius = k.field.radius;
  c->field_grid_spacing = k.field.grid_spacing;
  c->field_noise_variance = k.field.noise_variance;
  c->field_inducing_points = k.field.inducing_points;
  c->field_grid_nx = k.field.grid_nx;
  c->field_grid_ny = k.field.grid_ny;
  c->label_set = GSF_LABEL_SET_SEMANTIC_KITTI;
  c->triangle_neighbours = k.triangle.neighbours;
}

int gsf_map_load(const void* blob, size_t bytes, gsf_map* out) noexcept {
  if (out == nullptr) return code(Status::InvalidArgument);
  std::memset(out, 0, sizeof(*out));  // untagged until the blob validated
  MapSlot* slot = new (out->opaque) MapSlot{0, gsf::MapView()};
  const Status s = gsf::load_map(blob, bytes, &slot->view);
  if (s == Status::Ok) slot->tag = kMapTag;
  return code(s);
}

int gsf_map_get_info(const gsf_map* map, gsf_map_info* out) noexcept {
  if (out == nullptr) return code(Status::InvalidArgument);
  std::memset(out, 0, sizeof(*out));
  const MapSlot* slot = loaded_map(map);
  if (slot == nullptr) return code(Status::InvalidArgument);
  out->instances = slot->view.counts.instances;
  out->triangles = slot->view.counts.triangles;
  out->refine_points = slot->view.counts.refine_points;
  out->road_length_m = slot->view.counts.road_length_m;
  out->total_bytes = slot->view.total_bytes;
  for (int k = 0; k < 3; ++k) out->origin[k] = slot->view.georef.origin[k];
  std::memcpy(out->frame, slot->view.georef.frame, sizeof(out->frame));
  return code(Status::Ok);
}

size_t gsf_localizer_storage_bytes(void) noexcept { return kHandleBytes; }

size_t gsf_workspace_bytes(const gsf_config* config) noexcept {
  gsf::LocalizerConfig k;
  if (!to_cpp(config, &k)) return 0;
  return gsf::Localizer::required_bytes(k);
}

int gsf_localizer_init(void* storage, size_t storage_bytes, const gsf_config* config, const gsf_map* map,
                       void* workspace, size_t workspace_bytes, gsf_localizer** out) noexcept {
  if (out == nullptr) return code(Status::InvalidArgument);
  *out = nullptr;
  if (storage == nullptr || !aligned(storage)) return code(Status::InvalidArgument);
  if (storage_bytes < kHandleBytes) return code(Status::BufferTooSmall);
  // From here on the storage holds an untagged (unusable) handle until init succeeds.
  Handle* h = new (storage) Handle{0, gsf::Localizer()};
  gsf::LocalizerConfig k;
  if (!to_cpp(config, &k)) return code(Status::InvalidArgument);
  const MapSlot* slot = loaded_map(map);
  if (slot == nullptr) return code(Status::InvalidArgument);
  if (workspace == nullptr || !aligned(workspace)) return code(Status::InvalidArgument);
  const Status s = h->localizer.init(k, slot->view, workspace, workspace_bytes);
  if (s != Status::Ok) return code(s);
  h->tag = kHandleTag;
  *out = reinterpret_cast<gsf_localizer*>(h);
  return code(Status::Ok);
}

int gsf_localize(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
                 const uint32_t* labels, const float* logits, uint32_t logit_dim, gsf_result* out) noexcept {
  gsf::LocalizeResult r;
  if (localizer == nullptr) {
    r.status = Status::InvalidArgument;
  } else if (Handle* h = live_handle(localizer)) {
    gsf::ScanView scan;
    scan.points = xyz_stride;
    scan.stride = stride;
    scan.count = count;
    scan.labels = labels;
    scan.logits = logits;
    scan.logit_dim = logit_dim;
    h->localizer.localize(scan, &r);
  } else {
    r.status = Status::NotInitialized;
  }
  if (out != nullptr) fill(r, out);
  return code(r.status);
}

}  // extern "C"

// ---- Vehicle modes: a position prior and tracking. ----
namespace {

gsf::ScanView scan_view(const float* xyz_stride, uint32_t stride, uint32_t count, const uint32_t* labels,
                        const float* logits, uint32_t logit_dim) {
  gsf::ScanView scan;
  scan.points = xyz_stride;
  scan.stride = stride;
  scan.count = count;
  scan.labels = labels;
  scan.logits = logits;
  scan.logit_dim = logit_dim;
  return scan;
}

}  // namespace

extern "C" {

int gsf_localize_with_prior(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
                            const uint32_t* labels, const float* logits, uint32_t logit_dim,
                            const gsf_position_prior* prior, gsf_result* out) noexcept {
  gsf::LocalizeResult r;
  if (localizer == nullptr || prior == nullptr || prior->has_heading > 1) {
    r.status = Status::InvalidArgument;
  } else if (Handle* h = live_handle(localizer)) {
    gsf::PositionPrior p;
    p.x = prior->x;
    p.y = prior->y;
    p.radius_m = prior->radius_m;
    p.has_heading = prior->has_heading != 0;
    p.heading_deg = prior->heading_deg;
    p.heading_tolerance_deg = prior->heading_tolerance_deg;
    h->localizer.localize(scan_view(xyz_stride, stride, count, labels, logits, logit_dim), p, &r);
  } else {
    r.status = Status::NotInitialized;
  }
  if (out != nullptr) fill(r, out);
  return code(r.status);
}

int gsf_track(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
              const uint32_t* labels, const float* logits, uint32_t logit_dim,
              const double predicted_map_frame_T_scan[12], gsf_result* out) noexcept {
  gsf::LocalizeResult r;
  if (localizer == nullptr || predicted_map_frame_T_scan == nullptr) {
    r.status = Status::InvalidArgument;
  } else if (Handle* h = live_handle(localizer)) {
    Eigen::Isometry3d predicted = Eigen::Isometry3d::Identity();
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 4; ++col) predicted.matrix()(row, col) = predicted_map_frame_T_scan[row * 4 + col];
    h->localizer.track(scan_view(xyz_stride, stride, count, labels, logits, logit_dim), predicted, &r);
  } else {
    r.status = Status::NotInitialized;
  }
  if (out != nullptr) fill(r, out);
  return code(r.status);
}

}  // extern "C"
