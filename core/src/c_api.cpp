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
#include "gsf/parameters.h"
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

// gsf_config <-> LocalizerConfig, generated from the parameter list (parameters.def): every USER
// parameter is the gsf_config field group_field of its type (flags: uint32_t 0 or 1), and the struct
// holds nothing else but struct_bytes and label_set.
template <typename C, typename K>
bool from_c(C c, K* k) {
  static_assert(std::is_same<C, K>::value, "gsf_config field type differs from the parameter's");
  *k = c;
  return true;
}
inline bool from_c(uint32_t c, bool* k) {
  if (c > 1) return false;
  *k = c == 1;
  return true;
}
template <typename K, typename C>
void to_c(K k, C* c) {
  static_assert(std::is_same<C, K>::value, "gsf_config field type differs from the parameter's");
  *c = k;
}
inline void to_c(bool k, uint32_t* c) { *c = k ? 1u : 0u; }

#define GSF_PARAM(level, type, group, field, unit, bounds, lo, hi, doc) \
  GSF_C_##level(group##_##field, group.field, #group "." #field)
#define GSF_PARAM_TOP(level, type, field, unit, bounds, lo, hi, doc) GSF_C_##level(field, field, #field)
#define GSF_PARAM_CLASSES(level, type, group, field, classes, name, unit, bounds, lo, hi, doc) \
  GSF_C_CLASSES_##level  // per-class parameters are expert (no GSF_C_CLASSES_USER)
#define GSF_C_EXPERT(c_field, cpp_field, name)
#define GSF_C_CLASSES_EXPERT

#define GSF_C_USER(c_field, cpp_field, name) +sizeof(gsf_config::c_field)
constexpr size_t kUserFieldBytes = 0
#include "parameters.def"
    ;
#undef GSF_C_USER
static_assert(sizeof(gsf_config) == kUserFieldBytes + 2 * sizeof(uint32_t),
              "gsf_config holds exactly the USER parameters of parameters.def, struct_bytes and label_set");

// gsf_config -> LocalizerConfig (C++ defaults for every expert value). On failure *bad names the field.
bool to_cpp(const gsf_config* c, gsf::LocalizerConfig* out, const char** bad) {
  if (c == nullptr || c->struct_bytes != sizeof(gsf_config)) {
    *bad = c == nullptr ? "config" : "struct_bytes";
    return false;
  }
  gsf::LocalizerConfig k;
#define GSF_C_USER(c_field, cpp_field, name) \
  if (!from_c(c->c_field, &k.cpp_field)) {   \
    *bad = name;                             \
    return false;                            \
  }
#include "parameters.def"
#undef GSF_C_USER
  // Built-in tables in static storage, built on first use (read-only afterwards; init copies them).
  if (c->label_set == GSF_LABEL_SET_NUSCENES_LIDARSEG) {
    static const gsf::ClassTable nuscenes = [] {
      gsf::ClassTable t;
      gsf::nuscenes_lidarseg_class_table(&t);
      return t;
    }();
    k.classes = &nuscenes;
  } else if (c->label_set != GSF_LABEL_SET_SEMANTIC_KITTI) {
    *bad = "label_set";
    return false;
  }
  *out = k;
  return true;
}

bool to_cpp(const gsf_config* c, gsf::LocalizerConfig* out) {
  const char* bad = nullptr;
  return to_cpp(c, out, &bad);
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

// Every localizing call: a null or unusable handle (or bad arguments) gives a status and no work.
template <typename Call>
gsf::LocalizeResult run_on_localizer(gsf_localizer* localizer, bool arguments_valid, Call call) {
  gsf::LocalizeResult r;
  if (localizer == nullptr || !arguments_valid) {
    r.status = Status::InvalidArgument;
  } else if (Handle* h = live_handle(localizer)) {
    call(h->localizer, &r);
  } else {
    r.status = Status::NotInitialized;
  }
  return r;
}

// A row-major 3x4 [R | t] from the C API.
Eigen::Isometry3d pose_from_rows(const double rows[12]) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) pose.matrix()(row, col) = rows[row * 4 + col];
  return pose;
}

// The C prior as the C++ one; false for a NULL prior or a has_heading other than 0 or 1.
bool position_prior(const gsf_position_prior* prior, gsf::PositionPrior* p) {
  if (prior == nullptr || prior->has_heading > 1) return false;
  p->x = prior->x;
  p->y = prior->y;
  p->radius_m = prior->radius_m;
  p->has_heading = prior->has_heading != 0;
  p->heading_deg = prior->heading_deg;
  p->heading_tolerance_deg = prior->heading_tolerance_deg;
  return true;
}

gsf_window_info window_info(const gsf::LocalizeResult& r) {
  gsf_window_info w{};
  w.sequence_index = r.sequence_index;
  w.combined = r.window_combined ? 1u : 0u;
  w.checked = r.window_checked ? 1u : 0u;
  w.contradicted = r.window_contradicted ? 1u : 0u;
  w.scans = r.window_scans;
  for (uint32_t k = 0; k < GSF_MAX_WINDOW_SCANS; ++k) w.ids[k] = r.window_ids[k];
  w.single_confidence = r.single_confidence;
  return w;
}

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
#define GSF_C_USER(c_field, cpp_field, name) to_c(k.cpp_field, &c->c_field);
#include "parameters.def"
#undef GSF_C_USER
  c->label_set = GSF_LABEL_SET_SEMANTIC_KITTI;
}

const char* gsf_config_check(const gsf_config* c) noexcept {
  gsf::LocalizerConfig k;
  const char* bad = nullptr;
  if (!to_cpp(c, &k, &bad)) return bad;
  const gsf::ConfigCheck check = gsf::check_config(k);
  return check.status == Status::Ok ? nullptr : check.param->name;
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
  const gsf::ScanView scan = scan_view(xyz_stride, stride, count, labels, logits, logit_dim);
  const gsf::LocalizeResult r =
      run_on_localizer(localizer, true, [&](gsf::Localizer& l, gsf::LocalizeResult* res) { l.localize(scan, res); });
  if (out != nullptr) fill(r, out);
  return code(r.status);
}

// ---- Vehicle modes: a position prior, tracking and several scans. ----
static_assert(GSF_MAX_WINDOW_SCANS == gsf::kMaxWindowScans, "gsf_window_info.ids holds every combined scan");

int gsf_localize_with_prior(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
                            const uint32_t* labels, const float* logits, uint32_t logit_dim,
                            const gsf_position_prior* prior, gsf_result* out) noexcept {
  gsf::PositionPrior p;
  const bool valid = position_prior(prior, &p);
  const gsf::ScanView scan = scan_view(xyz_stride, stride, count, labels, logits, logit_dim);
  const gsf::LocalizeResult r = run_on_localizer(
      localizer, valid, [&](gsf::Localizer& l, gsf::LocalizeResult* res) { l.localize(scan, p, res); });
  if (out != nullptr) fill(r, out);
  return code(r.status);
}

int gsf_track(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
              const uint32_t* labels, const float* logits, uint32_t logit_dim,
              const double predicted_map_frame_T_scan[12], gsf_result* out) noexcept {
  const gsf::ScanView scan = scan_view(xyz_stride, stride, count, labels, logits, logit_dim);
  const gsf::LocalizeResult r = run_on_localizer(localizer, predicted_map_frame_T_scan != nullptr,
                                                 [&](gsf::Localizer& l, gsf::LocalizeResult* res) {
                                                   l.track(scan, pose_from_rows(predicted_map_frame_T_scan), res);
                                                 });
  if (out != nullptr) fill(r, out);
  return code(r.status);
}

int gsf_localize_sequence(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
                          const uint32_t* labels, const float* logits, uint32_t logit_dim,
                          const double previous_T_scan[12], gsf_result* out, gsf_window_info* window) noexcept {
  const gsf::ScanView scan = scan_view(xyz_stride, stride, count, labels, logits, logit_dim);
  const gsf::LocalizeResult r = run_on_localizer(localizer, true, [&](gsf::Localizer& l, gsf::LocalizeResult* res) {
    if (previous_T_scan == nullptr) l.reset_sequence();  // the first scan of a sequence
    const Eigen::Isometry3d odometry =
        previous_T_scan == nullptr ? Eigen::Isometry3d::Identity() : pose_from_rows(previous_T_scan);
    l.localize_sequence(scan, odometry, res);
  });
  if (out != nullptr) fill(r, out);
  if (window != nullptr) *window = window_info(r);
  return code(r.status);
}

int gsf_localize_next(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
                      const uint32_t* labels, const float* logits, uint32_t logit_dim, const double previous_T_scan[12],
                      const gsf_position_prior* gnss, gsf_result* out, gsf_drive_info* info) noexcept {
  gsf::PositionPrior p;
  const bool valid = gnss == nullptr || position_prior(gnss, &p);
  const gsf::ScanView scan = scan_view(xyz_stride, stride, count, labels, logits, logit_dim);
  const gsf::LocalizeResult r = run_on_localizer(localizer, valid, [&](gsf::Localizer& l, gsf::LocalizeResult* res) {
    if (previous_T_scan == nullptr) l.reset_drive();  // the first scan of a drive
    const Eigen::Isometry3d odometry =
        previous_T_scan == nullptr ? Eigen::Isometry3d::Identity() : pose_from_rows(previous_T_scan);
    l.localize_next(scan, odometry, gnss != nullptr ? &p : nullptr, res);
  });
  if (out != nullptr) fill(r, out);
  if (info != nullptr) {
    *info = gsf_drive_info{};
    info->tracked = r.tracked ? 1u : 0u;
    info->track_lost = r.track_lost ? 1u : 0u;
    info->prior_used = r.prior_used ? 1u : 0u;
    info->window = window_info(r);
  }
  return code(r.status);
}

}  // extern "C"
