#include "pipeline.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "gsf/port/class_table_file.h"
#include "gsf/port/nuscenes.h"

namespace gsf::cli {

LocalizerConfig default_config() {
  LocalizerConfig c;
  c.max_scan_points = kMaxScanPoints;
  return c;
}

std::string number_text(double x) {
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

std::string value_text(const ParamInfo& p, double v) {
  if (p.type != ParamType::F32) return number_text(v);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.7g", v);  // the float's shortest decimal (0.06, not 0.0599999987)
  return buf;
}

std::string range_text(const ParamInfo& p) {
  if (p.type == ParamType::Bool) return "0 or 1";
  std::string r = (p.lo_open ? "(" : "[") + number_text(p.lo) + ", " + number_text(p.hi) +
                  (p.hi_open || std::isinf(p.hi) ? ")" : "]");
  if (p.type != ParamType::F32) r = "a whole number in " + r;
  return r;
}

std::string describe(const ConfigCheck& check, const LocalizerConfig& config) {
  if (check.status == Status::Ok || check.param == nullptr) return "ok";
  const std::string value =
      check.param->name + std::string(" = ") + value_text(*check.param, get_parameter(config, *check.param));
  if (check.rule) return value + ": " + check.param->name + " " + check.rule;
  return value + ": outside " + range_text(*check.param);
}

// `--set name=value`: the names, types and ranges are the parameter list's (gsf/parameters.h).
bool apply_override(LocalizerConfig* c, const std::string& a, std::string* error) {
  const auto eq = a.find('=');
  if (eq == std::string::npos) {
    *error = "override '" + a + "' is not name=value";
    return false;
  }
  const std::string k = a.substr(0, eq), v = a.substr(eq + 1);
  const ParamInfo* p = find_parameter(k.c_str());
  if (p == nullptr) {
    *error = "unknown config name '" + k + "' (gsf params lists them)";
    return false;
  }
  char* end = nullptr;
  const double x = std::strtod(v.c_str(), &end);
  if (v.empty() || *end != '\0') {
    *error = "override '" + a + "': value is not a number";
    return false;
  }
  if (set_parameter(c, *p, x) != Status::Ok) {
    *error = "override '" + a + "': " + k + " must be " + range_text(*p);
    return false;
  }
  return true;
}

bool apply_overrides(LocalizerConfig* c, const std::string& list, std::string* error) {
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty() && !apply_override(c, item, error)) return false;
  const ConfigCheck check = check_config(*c);  // the rules between parameters
  if (check.status != Status::Ok) {
    *error = "config: " + describe(check, *c);
    return false;
  }
  return true;
}

bool parse_logit_mode(const std::string& s, LogitMode* out) {
  if (s == "none") {
    *out = LogitMode::None;
    return true;
  }
  if (s == "synthetic") {
    *out = LogitMode::Synthetic;
    return true;
  }
  return false;
}

namespace {
bool is_nuscenes(const std::string& root, const std::string& seq) {
  std::error_code ec;
  return std::filesystem::is_directory(std::filesystem::path(root) / "sequences" / seq / "lidarseg", ec);
}
}  // namespace

bool resolve_label_set(const std::string& spec, const std::string& root, const std::string& seq, LabelSet* out,
                       std::string* error) {
  const bool nuscenes_data = is_nuscenes(root, seq);
  out->name = spec == "auto" ? (nuscenes_data ? "nuscenes" : "semantic-kitti") : spec;
  out->semantic_kitti = out->name == "semantic-kitti";
  if (out->semantic_kitti) {
    semantic_kitti_class_table(&out->table);
  } else if (out->name == "nuscenes") {
    nuscenes_lidarseg_class_table(&out->table);
  } else {
    port::ClassTableParseError pe;
    const Status s = port::load_class_table(out->name, &out->table, &pe);
    if (s != Status::Ok) {
      *error = "class table '" + out->name + "': " + to_string(s) + " at line " + std::to_string(pe.line) + ", field " +
               std::to_string(pe.field) + (pe.message ? std::string(": ") + pe.message : "");
      return false;
    }
  }
  out->nuscenes_raw = nuscenes_data && !out->semantic_kitti;
  out->nuscenes_data = nuscenes_data;
  return true;
}

bool resolve_scan_label_errors(const LabelErrorOptions& o, const LabelSet& labels, const std::string& sequence,
                               ScanLabelErrors* out, std::string* note, std::string* error) {
  using label_errors::LabelSpace;
  note->clear();
  out->rates = o.rates;
  out->noise_seed = o.noise_seed;
  out->sequence = sequence;
  out->space = labels.nuscenes_raw ? LabelSpace::NuScenesLidarseg : LabelSpace::SemanticKitti;
  if (!o.rates.any()) return true;
  if (labels.nuscenes_data && !labels.nuscenes_raw) {
    *error =
        "--label-noise / --object-confusion / --thin-miss on nuScenes-lidarseg data need its lidarseg ids "
        "(--classes auto or nuscenes or a lidarseg class table): the errors are drawn in lidarseg classes";
    return false;
  }
  if (out->space == LabelSpace::NuScenesLidarseg && o.rates.thin_miss > 0)
    *note =
        "--thin-miss has no effect on nuScenes-lidarseg labels: they have no pole, sign or trunk class, and a "
        "missed one would take its background's class (static.manmade / static.vegetation), which it has";
  return true;
}

std::string describe(const ScanLabelErrors& e) {
  if (!e.rates.any()) return "none (ground-truth labels)";
  char line[200];
  std::snprintf(line, sizeof line, "label noise %g, object confusion %g, thin miss %g on %s labels, noise seed %llu",
                e.rates.label_noise, e.rates.object_confusion, e.rates.thin_miss,
                label_errors::label_space_name(e.space), static_cast<unsigned long long>(e.noise_seed));
  return line;
}

std::unique_ptr<port::ScanSource> open_source(const std::string& root, const std::string& seq, Status* status,
                                              const LabelSet* labels) {
  if (is_nuscenes(root, seq)) {
    auto src = std::make_unique<port::NuScenesLidarsegSource>();
    port::KittiReadOptions opt;
    opt.raw_labels = labels && labels->nuscenes_raw;
    *status = src->open(root, seq, opt);
    return src;
  }
  auto src = std::make_unique<port::SemanticKittiSource>();
  *status = src->open(root, seq);
  return src;
}

Status read_scan(port::ScanSource& src, uint32_t index, port::ScanBuffer& buf, LogitMode mode, uint64_t scan_id,
                 const ClassTable* classes, const ScanLabelErrors* errors) {
  const Status s = src.read(index, buf);
  if (s != Status::Ok) return s;
  if (errors && errors->rates.any())  // before the logits: the network's errors are in its labels
    label_errors::apply_label_errors(
        errors->rates, errors->space, buf.points, buf.labels, buf.count,
        label_errors::real_scan_seed(errors->noise_seed, errors->sequence, src.frame_id(index)));
  if (mode == LogitMode::Synthetic && buf.logits && !buf.has_logits) {
    port::LogitModel model;
    port::synthesize_logits(model, scan_id, buf.labels, buf.count, buf.logits, buf.labels, classes);
    buf.has_logits = true;
  }
  return Status::Ok;
}

Meta read_meta(const std::string& root) {
  Meta m;
  std::ifstream f(std::filesystem::path(root) / "meta.json");
  if (!f) return m;
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string s = ss.str();
  m.present = true;
  auto pos = s.find("\"road_length_m\":");
  if (pos != std::string::npos) m.road_length_m = std::strtof(s.c_str() + pos + 16, nullptr);
  pos = s.find("\"query_in_repetitive_zone\": [");
  if (pos != std::string::npos) {
    for (size_t i = pos + 29; i < s.size() && s[i] != ']'; ++i)
      if (s[i] == '0' || s[i] == '1') m.query_in_zone.push_back(s[i] == '1');
  }
  pos = s.find("\"query_near_zone\": [");
  if (pos != std::string::npos) {
    for (size_t i = pos + 20; i < s.size() && s[i] != ']'; ++i)
      if (s[i] == '0' || s[i] == '1') m.query_near_zone.push_back(s[i] == '1');
  }
  pos = s.find("\"zone\": {\"type\": \"");
  if (pos != std::string::npos) {
    const size_t b = pos + 18, e = s.find('"', b);
    if (e != std::string::npos) m.zone_type = s.substr(b, e - b);
    const size_t c = s.find("\"cue_density\":", pos);
    if (c != std::string::npos) m.cue_density = std::strtof(s.c_str() + c + 14, nullptr);
  }
  pos = s.find("\"stretches\": [");
  if (pos != std::string::npos) {
    const char* p = s.c_str() + pos + 14;
    while (*p != '\0' && *p != '\n') {  // [[first, length], ...] on one line
      if (*p++ != '[') continue;
      char* end = nullptr;
      const unsigned long first = std::strtoul(p, &end, 10);
      if (end == p || *end != ',') break;
      const unsigned long length = std::strtoul(end + 1, &end, 10);
      m.stretches.push_back({uint32_t(first), uint32_t(length)});
      p = end;
    }
  }
  pos = s.find("\"stretch_in_repetitive_zone\": [");
  if (pos != std::string::npos)
    for (size_t i = pos + 31; i < s.size() && s[i] != ']'; ++i)
      if (s[i] == '0' || s[i] == '1') m.stretch_in_zone.push_back(s[i] == '1');
  return m;
}

double path_length(port::ScanSource& src) {
  double len = 0;
  Eigen::Isometry3d prev;
  bool have = false;
  for (uint32_t i = 0; i < src.size(); ++i) {
    Eigen::Isometry3d p;
    if (src.pose(i, &p) != Status::Ok) continue;
    if (have) {
      const double d = (p.translation() - prev.translation()).norm();
      if (d < 50.0) len += d;
    }
    prev = p;
    have = true;
  }
  return len;
}

namespace {

// build-map's dataset as a drive the builder reads block by block (MapBuilder::build_blocked).
class DatasetDrive : public mapping::ScanSequence {
 public:
  DatasetDrive(port::ScanSource& src, const mapping::MapBuildConfig& config, LogitMode logits,
               const ScanLabelErrors* errors)
      : src_(src), config_(config), logits_(logits), errors_(errors), buf_(kMaxScanPoints, true) {}
  uint32_t size() const override { return src_.size(); }
  Status read(uint32_t i, ScanView* scan, Eigen::Isometry3d* pose) override {
    Status s = src_.pose(i, pose);
    if (s == Status::Ok)
      s = read_scan(src_, i, buf_.buffer(), logits_, 1000000u + src_.frame_id(i), config_.stages.classes, errors_);
    if (s == Status::Ok) *scan = buf_.buffer().view();
    return s;
  }

 private:
  port::ScanSource& src_;
  const mapping::MapBuildConfig& config_;
  LogitMode logits_;
  const ScanLabelErrors* errors_;
  port::OwnedScanBuffer buf_;
};

mapping::Progress progress_printer() {
  return [](const char* stage, uint64_t done, uint64_t total) {
    std::fprintf(stderr, "\r  build-map: %s %llu / %llu", stage, (unsigned long long)done, (unsigned long long)total);
    if (done == total) std::fprintf(stderr, "\n");
  };
}

}  // namespace

Status build_map(port::ScanSource& src, const mapping::MapBuildConfig& config, LogitMode logits, mapping::MapSink& sink,
                 size_t* bytes, mapping::MapBuildStats* stats, bool progress, uint32_t* failed_scan,
                 const ScanLabelErrors* errors) {
  if (failed_scan) *failed_scan = UINT32_MAX;
  mapping::MapBuilder builder(config);
  if (config.block_tiles > 0 && config.tile_size > 0.0f) {  // block by block, no spill file
    DatasetDrive drive(src, config, logits, errors);
    return builder.build_blocked(drive, sink, bytes, stats, progress ? progress_printer() : nullptr, failed_scan);
  }
  port::OwnedScanBuffer buf(kMaxScanPoints, true);
  for (uint32_t i = 0; i < src.size(); ++i) {
    Eigen::Isometry3d pose;
    Status s = src.pose(i, &pose);
    if (s != Status::Ok) {
      if (failed_scan) *failed_scan = i;
      return s;
    }
    s = read_scan(src, i, buf.buffer(), logits, 1000000u + src.frame_id(i), config.stages.classes, errors);
    if (s != Status::Ok) return s;
    s = builder.add_scan(buf.buffer().view(), pose);
    if (s != Status::Ok) {
      if (failed_scan) *failed_scan = i;
      if (progress) std::fprintf(stderr, "\n");
      return s;
    }
    if (progress && (i % 25 == 0 || i + 1 == src.size()))
      std::fprintf(stderr, "\r  build-map: accumulated %u / %u scans", i + 1, src.size());
  }
  if (progress) std::fprintf(stderr, "\n");
  return builder.build(sink, bytes, stats, progress ? progress_printer() : nullptr);
}

}  // namespace gsf::cli
