// Test fixture: the simulator's tiny world (mapping + query drive), its map built in memory, and the
// query scans with synthetic logits. Made once per test process: read from the file ctest's test_worlds
// fixture wrote (GSF_TEST_WORLDS, tests/CMakeLists.txt) when there is one, else built in process. The
// dozen executables that share these worlds read them instead of each building them again (about 2 s
// each in a release build, 15 s under qemu); test_world_cache.cpp checks the file equals the build.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "gsf/config.h"
#include "gsf/map_format.h"
#include "gsf/port/logit_synthesis.h"
#include "gsf/port/nuscenes.h"
#include "mapping/map_builder.h"
#include "sim/simulation.h"
#include "world_cache.h"

namespace gsf_test {

struct QueryScan {
  std::vector<float> xyzi;
  std::vector<uint32_t> labels;
  std::vector<float> logits;
  Eigen::Isometry3d truth;
  bool in_zone = false;
  gsf::ScanView view() const {
    gsf::ScanView v;
    v.points = xyzi.data();
    v.labels = labels.data();
    v.logits = logits.data();
    v.logit_dim = gsf::kNumClasses;
    v.count = static_cast<uint32_t>(labels.size());
    return v;
  }
};

struct TinyWorld {
  gsf::ClassTable classes;  // the label set of the scans (config.classes points here, or is nullptr)
  gsf::LocalizerConfig config;
  std::vector<uint64_t> blob;
  size_t bytes = 0;
  gsf::MapView map;
  std::vector<QueryScan> queries;
  gsf::mapping::MapBuildStats build_stats;
};

// classes == nullptr: SemanticKITTI labels; else the scan is relabelled as nuScenes-lidarseg would
// label it (gsf::port::kitti_to_nuscenes) and `classes` must be the nuScenes-lidarseg table.
inline void make_scan(const gsf::sim::Raycaster& rc, const gsf::sim::SimConfig& sc, const Eigen::Isometry3d& pose,
                      uint64_t seed, uint64_t scan_id, QueryScan* out, const gsf::ClassTable* classes = nullptr) {
  gsf::sim::SimScan s;
  rc.scan(pose, sc.lidar, seed, &s);
  out->xyzi = s.xyzi;
  out->labels = s.labels;
  if (classes)
    for (uint32_t& l : out->labels) l = gsf::port::kitti_to_nuscenes(l);
  out->logits.assign(s.labels.size() * gsf::kNumClasses, 0.0f);
  gsf::port::LogitModel model;
  gsf::port::synthesize_logits(model, scan_id, out->labels.data(), s.size(), out->logits.data(), out->labels.data(),
                               classes);
  out->truth = pose;
}

// The world's config and label set; everything else of a TinyWorld is built or read.
inline TinyWorld* new_world(const gsf::ClassTable* nuscenes_table) {
  auto* t = new TinyWorld();
  t->config.max_scan_points = 262144;
  if (nuscenes_table) {
    t->classes = *nuscenes_table;
    t->config.classes = &t->classes;
  }
  return t;
}

// Simulates `sc`, builds its map in memory and the query scans (map and query logits drawn
// independently, as `gsf evaluate` does).
// nuscenes_table != nullptr: the scans are labelled as nuScenes-lidarseg would label them, and this
// table (of lidarseg ids) is the label set of map and queries.
inline TinyWorld* build_sim_world(const gsf::sim::SimConfig& sc, const gsf::ClassTable* nuscenes_table = nullptr) {
  {
    TinyWorld* t = new_world(nuscenes_table);
    const gsf::ClassTable* classes = t->config.classes;
    const gsf::sim::World world = gsf::sim::generate_world(sc.world);
    const gsf::sim::World later = gsf::sim::apply_time_gap(world, sc.time_gap);
    const gsf::sim::Raycaster map_rc(world), query_rc(later);
    const gsf::sim::Drive md = gsf::sim::mapping_drive(world, sc);
    const gsf::sim::Drive qd = gsf::sim::query_drive(world, sc);
    // The simulator's world frame is already local: an explicit zero origin keeps the fixture's map
    // local, so the map's frame and the map-local frame coincide (test_localizer compares poses in
    // either with the simulator's truth). The default origin
    // (first pose, rounded) is tested in test_map_builder.cpp and by the CLI's shifted-world test.
    gsf::mapping::MapBuildConfig build_config;
    build_config.stages = t->config;
    build_config.origin_given = true;
    build_config.road_length_m = world.road_length();
    gsf::mapping::MapBuilder builder(build_config);
    for (uint32_t f = 0; f < md.poses.size(); ++f) {
      QueryScan s;
      make_scan(map_rc, sc, md.poses[f], gsf::sim::scan_seed(sc.world.seed, 0, f), 1000000u + f, &s, classes);
      builder.add_scan(s.view(), md.poses[f]);
    }
    builder.build(&t->blob, &t->bytes, &t->build_stats);
    gsf::load_map(t->blob.data(), t->bytes, &t->map);
    for (uint32_t f = 0; f < qd.poses.size(); ++f) {
      QueryScan s;
      make_scan(query_rc, sc, qd.poses[f], gsf::sim::scan_seed(sc.world.seed, 1, f), 2000000u + f, &s, classes);
      s.in_zone = qd.in_zone[f];
      t->queries.push_back(std::move(s));
    }
    return t;
  }
}

// Writes everything of `w` that is built (map, build stats, query scans) to `path`, through a
// temporary file renamed into place, so a reader never sees a partial file.
inline bool save_world(const TinyWorld& w, const std::string& path) {
  const std::string tmp = path + ".tmp";
  FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) return false;
  world_cache::Writer out(f);
  out.bytes(world_cache::kMagic, sizeof(world_cache::kMagic));
  out.pod(static_cast<uint64_t>(w.bytes));
  out.array(w.blob);
  out.pod(w.build_stats);
  out.pod(static_cast<uint64_t>(w.queries.size()));
  for (const QueryScan& q : w.queries) {
    out.array(q.xyzi);
    out.array(q.labels);
    out.array(q.logits);
    out.bytes(q.truth.matrix().data(), 16 * sizeof(double));
    out.pod(static_cast<uint8_t>(q.in_zone));
  }
  out.bytes(world_cache::kMagic, sizeof(world_cache::kMagic));
  const bool ok = std::fclose(f) == 0 && out.ok();
  return ok && std::rename(tmp.c_str(), path.c_str()) == 0;
}

// Reads what save_world wrote into `t` (made by new_world with the same label set) and loads its map;
// false for a missing, short or corrupted file.
inline bool load_world(const std::string& path, TinyWorld* t) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  world_cache::Reader in(f);
  char magic[sizeof(world_cache::kMagic)] = {};
  uint64_t bytes = 0, queries = 0;
  in.bytes(magic, sizeof(magic));
  in.pod(&bytes);
  in.array(&t->blob);
  in.pod(&t->build_stats);
  in.pod(&queries);
  for (uint64_t i = 0; in.ok() && i < queries && i < 100000; ++i) {
    QueryScan q;
    uint8_t in_zone = 0;
    in.array(&q.xyzi);
    in.array(&q.labels);
    in.array(&q.logits);
    in.bytes(q.truth.matrix().data(), 16 * sizeof(double));
    in.pod(&in_zone);
    q.in_zone = in_zone != 0;
    t->queries.push_back(std::move(q));
  }
  char end[sizeof(world_cache::kMagic)] = {};
  in.bytes(end, sizeof(end));
  std::fclose(f);
  t->bytes = static_cast<size_t>(bytes);
  const auto magic_ok = [](const char* m) {
    return std::memcmp(m, world_cache::kMagic, sizeof(world_cache::kMagic)) == 0;
  };
  return in.ok() && magic_ok(magic) && magic_ok(end) && t->queries.size() == queries &&
         t->bytes <= t->blob.size() * sizeof(uint64_t) &&
         gsf::load_map(t->blob.data(), t->bytes, &t->map) == gsf::Status::Ok;
}

// The world named `name` from the test_worlds fixture's directory (GSF_TEST_WORLDS) when it is set and
// its file reads back whole; else `build()`.
template <class Build>
TinyWorld* cached_or_built(const char* name, const gsf::ClassTable* nuscenes_table, Build build) {
  if (const char* dir = std::getenv("GSF_TEST_WORLDS")) {
    TinyWorld* t = new_world(nuscenes_table);
    if (load_world(std::string(dir) + "/" + name + ".world", t)) return t;
    delete t;
    std::fprintf(stderr, "tiny_world.h: %s/%s.world does not read back; building the world in process\n", dir, name);
  }
  return build();
}

inline const gsf::ClassTable& nuscenes_table() {
  static const gsf::ClassTable table = [] {
    gsf::ClassTable t;
    gsf::nuscenes_lidarseg_class_table(&t);
    return t;
  }();
  return table;
}

inline const TinyWorld& tiny_world() {
  static TinyWorld* w = cached_or_built("tiny", nullptr, [] { return build_sim_world(gsf::sim::SimConfig::tiny()); });
  return *w;
}

// The tiny world labelled as nuScenes-lidarseg would label it (no pole, trunk, sign or fence class),
// with the built-in nuScenes-lidarseg label set: poles and trunks come from geometry.
inline const TinyWorld& tiny_nuscenes_world() {
  static TinyWorld* w = cached_or_built("tiny_nuscenes", &nuscenes_table(),
                                        [] { return build_sim_world(gsf::sim::SimConfig::tiny(), &nuscenes_table()); });
  return *w;
}

// The tiny-lattice preset: a small city and a 2-D lattice car park of identical columns.
inline const TinyWorld& tiny_lattice_world() {
  static TinyWorld* w =
      cached_or_built("tiny_lattice", nullptr, [] { return build_sim_world(gsf::sim::SimConfig::tiny_lattice()); });
  return *w;
}

inline bool pose_ok(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth) {
  const Eigen::Isometry3d d = est.inverse() * truth;
  return d.translation().norm() < 5.0 && Eigen::AngleAxisd(d.rotation()).angle() < 10.0 * M_PI / 180.0;
}

}  // namespace gsf_test
