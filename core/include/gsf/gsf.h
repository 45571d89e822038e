// The C API of libgsf (C11; usable from C++, where every function is noexcept). It wraps the C++ facade
// (gsf/localizer.h) with the same rules: the caller provides all memory, nothing is allocated, nothing
// throws, every fallible call returns a status code (one of GSF_STATUS_*, the values of gsf::Status).
//
//   gsf_config cfg;       gsf_config_default(&cfg);            // then tune fields
//   gsf_map map;          gsf_map_load(blob, blob_bytes, &map); // validates, then zero copy
//   storage:   gsf_localizer_storage_bytes() bytes, 16-byte aligned (the handle lives here)
//   workspace: gsf_workspace_bytes(&cfg) bytes, 16-byte aligned (all per-scan memory)
//   gsf_localizer* loc;   gsf_localizer_init(storage, ..., &cfg, &map, workspace, ..., &loc);
//   gsf_result r;         gsf_localize(loc, xyz, 4, n, labels, NULL, 0, &r);
//
// Lifetimes: the map blob, the gsf_map, the storage and the workspace must stay valid and unchanged
// while the localizer is used. There is no teardown call: drop or reuse the memory. Threads: a loaded
// gsf_map may be shared read-only by any number of localizers on any threads; one localizer (and its
// workspace) must be used by one thread at a time.
//
// Linking: libgsf is C++. CMake consumers (find_package(gsf), gsf::gsf) get the C++ runtime linked
// automatically; otherwise link with the C++ compiler driver (or add -lstdc++ -lm).
#pragma once

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
#define GSF_NOEXCEPT noexcept
extern "C" {
#else
#define GSF_NOEXCEPT
#endif

// Status codes: the values of gsf::Status (gsf/status.h), checked at compile time in c_api.cpp.
enum {
  GSF_STATUS_OK = 0,
  GSF_STATUS_INVALID_ARGUMENT = 1,  // NULL pointer, misaligned buffer, value out of range
  GSF_STATUS_INVALID_INPUT = 2,     // scan data unusable (NaN/Inf, empty after gating, ...)
  GSF_STATUS_CAPACITY_EXCEEDED = 3,
  GSF_STATUS_BUFFER_TOO_SMALL = 4,  // storage or workspace smaller than its *_bytes() query
  GSF_STATUS_NOT_INITIALIZED = 5,   // localizer whose last init failed
  GSF_STATUS_CORRUPT_DATA = 6,      // map blob failed a size, range or CRC check
  GSF_STATUS_VERSION_MISMATCH = 7,
  GSF_STATUS_CONFIG_MISMATCH = 8,  // map built with values the config disagrees with
  GSF_STATUS_TRUNCATED = 9,        // map blob shorter than its header says
  GSF_STATUS_IO_ERROR = 10,
  GSF_STATUS_NOT_FOUND = 11,
  GSF_STATUS_BUDGET_EXHAUSTED = 12,
  GSF_STATUS_NO_SOLUTION = 13,  // no pose (too few instances or inliers)
  GSF_STATUS_UNSUPPORTED = 14
};

// Alignment required of the map blob, the localizer storage and the workspace.
#define GSF_ALIGNMENT 16
// Logit dimension (SemanticKITTI's learning classes, gsf::kNumClasses).
#define GSF_NUM_CLASSES 19

// Name of a status code ("Ok", "InvalidArgument", ...); "Unknown" for other values. Never NULL.
const char* gsf_status_string(int status) GSF_NOEXCEPT;

// The user-facing parameters of gsf::LocalizerConfig (docs/parameters.md, "User-facing"); the expert ones
// keep their C++ defaults. Names are the parameters' with '.' -> '_' (gsf_tau is gsf.tau); the ranges
// and units are in docs/parameters.md. Flags are 0 or 1. c_api.cpp maps each from the parameter list
// (core/src/parameters.def) and checks at compile time that this struct holds exactly those.
typedef struct gsf_config {
  uint32_t struct_bytes;  // sizeof(gsf_config); set by gsf_config_default (catches stale layouts)
  // Capacities: the workspace (gsf_workspace_bytes) and the worst-case work grow with them.
  uint32_t max_scan_points;            // larger scans: GSF_STATUS_CAPACITY_EXCEEDED
  uint64_t hypotheses_first_budget;    // branch-and-bound nodes of the first clique search
  uint32_t voxel_max_voxels;           // voxels of a scan's layer
  uint32_t cluster_max_instances;      // instances of a scan
  uint32_t triangle_max_triangles;     // query triangles of a scan
  uint32_t match_max_correspondences;  // vertices of the consistency graph
  uint32_t hypotheses_max_hypotheses;  // pose hypotheses per query
  // Query side: may differ from the values the map was built with.
  float voxel_min_range, voxel_max_range;  // m
  float gsf_tau, match_min_similarity;     // field similarity exp(-W2 / tau); the gate on it
  float hypotheses_consistency_eps;        // m
  float hypotheses_tls_threshold;          // m
  uint32_t verify_enabled;                 // whole-scan verification (needs the map's semantic layer)
  uint32_t refine_enabled;                 // uses the map's refinement layer (if any); grows the workspace
  // The decision rule: gsf_result.confident = confidence >= this (0..1; default 0.9, docs/confidence.md).
  float confidence_min_probability;
  // Map side: must equal the values the map was built with (else GSF_STATUS_CONFIG_MISMATCH at init).
  float voxel_voxel_size;  // m
  float field_radius, field_length_scale, field_noise_variance, field_grid_spacing;
  uint32_t field_inducing_points, field_grid_nx, field_grid_ny;
  uint32_t triangle_neighbours;
  // Label set of the scans' label ids (built-in class tables, gsf/class_table.h); the map records it, so
  // it must be the one the map was built with. Geometric poles / trunks come with nuScenes-lidarseg.
  uint32_t label_set;  // GSF_LABEL_SET_*
} gsf_config;

enum {
  GSF_LABEL_SET_SEMANTIC_KITTI = 0,    // SemanticKITTI ids (low 16 bits of the label word)
  GSF_LABEL_SET_NUSCENES_LIDARSEG = 1  // nuScenes-lidarseg classes 0..31
};

// Fills the defaults (the evaluated settings, gsf::LocalizerConfig{}). No-op on NULL.
void gsf_config_default(gsf_config* config) GSF_NOEXCEPT;
// NULL when `config` is valid; else the name of its first value that is out of range or breaks a rule
// with another: a parameter's name as in docs/parameters.md ("hypotheses.tls_threshold" for
// hypotheses_tls_threshold), "struct_bytes", "label_set", or "config" for NULL. Static storage.
const char* gsf_config_check(const gsf_config* config) GSF_NOEXCEPT;

// A validated, zero-copy view of a map blob. Caller storage; fill it with gsf_map_load only.
typedef struct gsf_map {
  uint64_t opaque[48];
} gsf_map;

// Map coordinates are float32 in a map-local frame relative to `origin`; `frame` names the frame the
// origin (and gsf_result.map_frame_T_scan) is given in - the frame of the mapping poses, e.g. "utm-32N".
#define GSF_MAP_FRAME_NAME_BYTES 32
typedef struct gsf_map_info {
  uint32_t instances, triangles, refine_points;
  float road_length_m;
  uint64_t total_bytes;
  double origin[3];                      // m, in `frame`: where the map-local (0, 0, 0) is
  char frame[GSF_MAP_FRAME_NAME_BYTES];  // NUL-terminated printable ASCII, e.g. "local", "utm-32N"
} gsf_map_info;

// Validates `blob` (16-byte aligned, exactly `bytes` long) completely and points `out` into it. Never
// reads outside the blob. On failure `out` is left unusable (gsf_localizer_init rejects it).
int gsf_map_load(const void* blob, size_t bytes, gsf_map* out) GSF_NOEXCEPT;
int gsf_map_get_info(const gsf_map* map, gsf_map_info* out) GSF_NOEXCEPT;

// Opaque localizer handle; it lives inside the caller's storage.
typedef struct gsf_localizer gsf_localizer;

// Bytes of handle storage (a multiple of GSF_ALIGNMENT; the storage itself must be 16-byte aligned).
size_t gsf_localizer_storage_bytes(void) GSF_NOEXCEPT;
// Workspace bytes gsf_localizer_init needs for this config (independent of the map); 0 if the config is
// NULL or invalid.
size_t gsf_workspace_bytes(const gsf_config* config) GSF_NOEXCEPT;

// Builds a localizer in `storage` over `map`, carving all per-scan memory from `workspace`. Rejects a NULL
// or misaligned storage/workspace (GSF_STATUS_INVALID_ARGUMENT), a too small one (BUFFER_TOO_SMALL), an
// invalid config (INVALID_ARGUMENT), a map not loaded by gsf_map_load (INVALID_ARGUMENT) or one built for
// other map-side values (CONFIG_MISMATCH). On success *out is the handle (inside storage), else NULL;
// a failure after the storage itself was accepted leaves a localizer previously built in it answering
// GSF_STATUS_NOT_INITIALIZED.
int gsf_localizer_init(void* storage, size_t storage_bytes, const gsf_config* config, const gsf_map* map,
                       void* workspace, size_t workspace_bytes, gsf_localizer** out) GSF_NOEXCEPT;

typedef struct gsf_result {
  int status;        // also the return value of gsf_localize
  uint32_t inliers;  // correspondences agreeing with the pose
  // The pose, row-major 3x4 [R | t] (p = R p_scan + t), in two frames with the same R:
  double map_T_scan[12];        // map-local frame: t relative to the map origin (gsf_map_info.origin)
  double map_frame_T_scan[12];  // the map's frame (gsf_map_info.frame): t = map-local t + origin, in double
  double confidence;            // calibrated probability that the pose is right (t < 5 m, r < 10 deg);
                                // at most 0.5 when under a third of the scan lands on the mapped area
  double score;                 // sum of inlier weights
  uint64_t clique_nodes;
  uint32_t clique_size, query_instances, query_triangles, triangle_matches, gsf_survivors, correspondences;
  uint32_t field_probes, field_comparisons;
  uint32_t refined, budget_exhausted, capacity_truncated;  // 0 or 1
  uint32_t confident;  // 0 or 1: confidence >= the config's min probability; act on the pose only when 1
} gsf_result;

// One-shot global localization of one scan in the sensor frame. Point i is xyz_stride[i * stride + 0..2]
// (stride >= 3 floats, e.g. 4 for x, y, z, intensity records); labels[i] is its SemanticKITTI label
// word (required); logits is optional (NULL, or count x logit_dim with logit_dim = GSF_NUM_CLASSES, in the
// dense class order of gsf/semantic_classes.h). Reads the scan only during the call. Always fills *out
// when out != NULL.
int gsf_localize(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
                 const uint32_t* labels, const float* logits, uint32_t logit_dim, gsf_result* out) GSF_NOEXCEPT;

// ---- Vehicle modes (docs/vehicle-modes.md): a position prior at start-up, tracking after the fix. ----

// Where the vehicle roughly is (e.g. a GNSS fix), in the map's frame (gsf_map_info.frame).
typedef struct gsf_position_prior {
  double x, y;                  // m: centre of the disc in the map's frame
  float radius_m;               // m, > 0: the sensor lies within this of (x, y)
  uint32_t has_heading;         // 0 or 1
  float heading_deg;            // yaw of the scan's x axis from the map's x axis, counter-clockwise
  float heading_tolerance_deg;  // [0, 180]
} gsf_position_prior;

// gsf_localize with a position prior: only map triangles near the prior are matched and only poses inside
// it are answers. GSF_STATUS_INVALID_ARGUMENT for a NULL or invalid prior (non-finite, radius <= 0,
// tolerance outside [0, 180]); GSF_STATUS_NO_SOLUTION when nothing inside the prior fits. A wrong prior
// gives a wrong pose at low confidence (confident = 0) or none, with one known exception: a disc that
// holds a turned copy of a repetitive scene and no pose near the truth (2 of 2,044 suite queries with the
// prior 50 m off, none 100 m off; docs/vehicle-modes.md). Give the heading (a GNSS course) when known:
// it rules those out. An answer that is not confident is also localized without the prior, and when that
// is confident at the same pose its result is returned: a prior answers at least what one-shot would.
int gsf_localize_with_prior(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
                            const uint32_t* labels, const float* logits, uint32_t logit_dim,
                            const gsf_position_prior* prior, gsf_result* out) GSF_NOEXCEPT;

// Tracking: the pose of the scan near a predicted pose (row-major 3x4 [R | t] in the map's frame, as
// gsf_result.map_frame_T_scan: e.g. the last pose times odometry), without the global search; bounded
// work. out->confident = 0 is a loss: localize the next scan with gsf_localize(_with_prior) again. Only
// confidence, confident, refined and the poses of *out are filled (the search's counts are 0).
// GSF_STATUS_INVALID_ARGUMENT for a NULL or non-finite prediction; GSF_STATUS_UNSUPPORTED for a map
// without a semantic layer.
int gsf_track(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
              const uint32_t* labels, const float* logits, uint32_t logit_dim,
              const double predicted_map_frame_T_scan[12], gsf_result* out) GSF_NOEXCEPT;

// ---- Several scans tied by odometry (docs/vehicle-modes.md) ----

#define GSF_MAX_WINDOW_SCANS 4
// Which scans made a gsf_localize_sequence answer.
typedef struct gsf_window_info {
  uint32_t sequence_index;             // this scan's number in the sequence (from 0)
  uint32_t combined;                   // 1: the answer is the window's (this scan alone was not confident)
  uint32_t checked, contradicted;      // a thin-margin confident answer checked by the window; put elsewhere
  uint32_t scans;                      // scans whose evidence made the answer (1: this one alone)
  uint32_t ids[GSF_MAX_WINDOW_SCANS];  // their sequence numbers, newest (this scan) first
  double single_confidence;            // this scan's own one-shot confidence
} gsf_window_info;

// gsf_localize, and when the scan alone is not confident, its pose from the last N scans of the sequence
// together (N: the config's window.scans, 3 by default; an expert parameter of the C++ config): each
// scan's candidate poses are moved to this one through the odometry and scored on all the scans'
// verification samples. previous_T_scan: this scan's pose in the previous scan's frame (odometry,
// row-major 3x4 [R | t]); NULL starts a new sequence (the first scan, or after a gap). window: optional.
// Every call enters its scan into the window. GSF_STATUS_INVALID_ARGUMENT for a non-finite odometry
// (the sequence restarts).
int gsf_localize_sequence(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
                          const uint32_t* labels, const float* logits, uint32_t logit_dim,
                          const double previous_T_scan[12], gsf_result* out, gsf_window_info* window) GSF_NOEXCEPT;

// ---- The vehicle loop (docs/vehicle-modes.md, "The loop") in one call per scan ----

// How gsf_localize_next found the scan's pose.
typedef struct gsf_drive_info {
  uint32_t tracked;     // 1: tracked from the last confident pose times the odometry
  uint32_t track_lost;  // 1: tracking was tried and lost; the pose is from localizing the same scan again
  uint32_t prior_used;  // 1: ... with the GNSS prior (else from the window of the last scans)
  gsf_window_info window;
} gsf_drive_info;

// One scan of a drive: while the last scan's pose was confident, tracking from it times the odometry;
// at start-up and when tracking is lost, the same scan localized from scratch, with `gnss` as a position
// prior when given (NULL: none), else with the window of the last scans localized from scratch, tied by
// the odometry (gsf_localize_sequence). previous_T_scan: this scan's pose in the previous scan's frame (row-major 3x4
// [R | t]); NULL starts a new drive (the first scan, or after a gap). info: optional. Act on the pose only when
// out->confident = 1. GSF_STATUS_INVALID_ARGUMENT for a non-finite odometry or an invalid prior (the drive
// restarts on a bad odometry).
int gsf_localize_next(gsf_localizer* localizer, const float* xyz_stride, uint32_t stride, uint32_t count,
                      const uint32_t* labels, const float* logits, uint32_t logit_dim, const double previous_T_scan[12],
                      const gsf_position_prior* gnss, gsf_result* out, gsf_drive_info* info) GSF_NOEXCEPT;

#ifdef __cplusplus
}  // extern "C"
#endif
