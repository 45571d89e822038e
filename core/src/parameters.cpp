// The parameter table from the one list (parameters.def), and check_config().
#include "gsf/parameters.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>
#include <utility>

#include "gsf/detail/gaussian_field.h"
#include "gsf/detail/pose_hypotheses.h"
#include "gsf/detail/triangle.h"

namespace gsf {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

template <ParamType T>
struct CppType;
template <>
struct CppType<ParamType::F32> {
  using type = float;
};
template <>
struct CppType<ParamType::U32> {
  using type = uint32_t;
};
template <>
struct CppType<ParamType::U64> {
  using type = uint64_t;
};
template <>
struct CppType<ParamType::Bool> {
  using type = bool;
};

#define GSF_TYPE_F32 ParamType::F32
#define GSF_TYPE_U32 ParamType::U32
#define GSF_TYPE_U64 ParamType::U64
#define GSF_TYPE_BOOL ParamType::Bool
#define GSF_LEVEL_USER ParamLevel::User
#define GSF_LEVEL_EXPERT ParamLevel::Expert
#define GSF_BOUNDS_CC false, false
#define GSF_BOUNDS_OC true, false
#define GSF_BOUNDS_CO false, true
#define GSF_BOUNDS_OO true, true

// Each entry's type is its field's declared type.
#define GSF_SAME_TYPE(t, member)                                                                                 \
  static_assert(std::is_same<CppType<GSF_TYPE_##t>::type,                                                        \
                             std::remove_reference_t<decltype(std::declval<LocalizerConfig&>().member)>>::value, \
                "parameters.def: the type of " #member);
#define GSF_PARAM(level, type, group, field, unit, bounds, lo, hi, doc) GSF_SAME_TYPE(type, group.field)
#define GSF_PARAM_TOP(level, type, field, unit, bounds, lo, hi, doc) GSF_SAME_TYPE(type, field)
#define GSF_PARAM_CLASSES(level, type, group, field, classes, name, unit, bounds, lo, hi, doc) \
  GSF_SAME_TYPE(type, group.field[0])
#include "parameters.def"
#undef GSF_PARAM
#undef GSF_PARAM_TOP
#undef GSF_PARAM_CLASSES

#define GSF_PARAM(level, type, group, field, unit, bounds, lo, hi, doc) \
  {#group "." #field,                                                   \
   #group "." #field,                                                   \
   GSF_TYPE_##type,                                                     \
   GSF_LEVEL_##level,                                                   \
   unit,                                                                \
   double(lo),                                                          \
   double(hi),                                                          \
   GSF_BOUNDS_##bounds,                                                 \
   doc,                                                                 \
   [](LocalizerConfig* c) -> void* { return &c->group.field; },         \
   0},
#define GSF_PARAM_TOP(level, type, field, unit, bounds, lo, hi, doc) \
  {#field,                                                           \
   #field,                                                           \
   GSF_TYPE_##type,                                                  \
   GSF_LEVEL_##level,                                                \
   unit,                                                             \
   double(lo),                                                       \
   double(hi),                                                       \
   GSF_BOUNDS_##bounds,                                              \
   doc,                                                              \
   [](LocalizerConfig* c) -> void* { return &c->field; },            \
   0},
#define GSF_PARAM_CLASSES(level, type, group, field, classes, name, unit, bounds, lo, hi, doc) \
  {name,                                                                                       \
   #group "." #field "[]",                                                                     \
   GSF_TYPE_##type,                                                                            \
   GSF_LEVEL_##level,                                                                          \
   unit,                                                                                       \
   double(lo),                                                                                 \
   double(hi),                                                                                 \
   GSF_BOUNDS_##bounds,                                                                        \
   doc,                                                                                        \
   [](LocalizerConfig* c) -> void* { return &c->group.field[0]; },                             \
   classes},
const ParamInfo kParams[] = {
#include "parameters.def"
};
#undef GSF_PARAM
#undef GSF_PARAM_TOP
#undef GSF_PARAM_CLASSES

constexpr uint32_t kCount = sizeof(kParams) / sizeof(kParams[0]);

#define GSF_PARAM(level, type, group, field, unit, bounds, lo, hi, doc) +(GSF_LEVEL_##level == ParamLevel::User)
#define GSF_PARAM_TOP(level, type, field, unit, bounds, lo, hi, doc) +(GSF_LEVEL_##level == ParamLevel::User)
#define GSF_PARAM_CLASSES(level, type, group, field, classes, name, unit, bounds, lo, hi, doc) \
  +(GSF_LEVEL_##level == ParamLevel::User)
constexpr uint32_t kUserCount = 0
#include "parameters.def"
    ;
#undef GSF_PARAM
#undef GSF_PARAM_TOP
#undef GSF_PARAM_CLASSES
static_assert(kUserCount <= kMaxUserParameters, "parameters.def: at most 25 user-facing parameters");

template <typename T>
T* at(LocalizerConfig* c, const ParamInfo& p, int index = 0) {
  return static_cast<T*>(p.bind(c)) + index;
}

int first_class(ClassMask m) {
  for (int k = 0; k < kNumClasses; ++k)
    if (m & class_bit(k)) return k;
  return 0;
}

bool in_range(const ParamInfo& p, double v) {
  if (std::isnan(v)) return false;
  if (p.lo_open ? !(v > p.lo) : !(v >= p.lo)) return false;
  if (p.hi_open ? !(v < p.hi) : !(v <= p.hi)) return false;
  return true;
}

const ParamInfo& param(const char* name) {
  const ParamInfo* p = find_parameter(name);
  return p ? *p : kParams[0];  // every rule's name is in the list (test_config checks each rule fires)
}

// The rules between parameters, in the order check_config() tries them.
static_assert(kMaxGridPoints == 128, "the rule's text");
const ParamRule kRules[] = {
    {"voxel.max_range", "must be > voxel.min_range",
     [](const LocalizerConfig& c) { return !(c.voxel.max_range > c.voxel.min_range); }},
    {"voxel.column_size", "must be >= voxel.voxel_size",
     [](const LocalizerConfig& c) { return !(c.voxel.column_size >= c.voxel.voxel_size); }},
    {"field.grid_layers", "must be 1 for bird's-eye fields (field.input_dims = 2)",
     [](const LocalizerConfig& c) { return c.field.input_dims == 2 && c.field.grid_layers != 1; }},
    {"field.grid_nx", "x field.grid_ny x field.grid_layers must be <= 128",
     [](const LocalizerConfig& c) { return grid_points(c.field) > kMaxGridPoints; }},
    {"triangle.map_neighbours", "must be 0 or >= triangle.neighbours",
     [](const LocalizerConfig& c) {
       return c.triangle.map_neighbours != 0 && c.triangle.map_neighbours < c.triangle.neighbours;
     }},
    {"triangle.max_side", "must be > triangle.min_side",
     [](const LocalizerConfig& c) { return !(c.triangle.max_side > c.triangle.min_side); }},
    {"triangle.max_side", "/ triangle.side_bin must be < 65534 (the key's 16 bits)",
     [](const LocalizerConfig& c) {
       return !(c.triangle.max_side / c.triangle.side_bin < float(kTriangleKeyMaxBin - 1));
     }},
    {"triangle.sparse_side_tolerance", "must be 0 or > triangle.relative_side_tolerance",
     [](const LocalizerConfig& c) {
       return c.triangle.sparse_side_tolerance != 0.0f &&
              !(c.triangle.sparse_side_tolerance > c.triangle.relative_side_tolerance);
     }},
    {"hypotheses.tls_threshold", "must be <= hypotheses.shift_bin (the shift votes' support radius)",
     [](const LocalizerConfig& c) { return c.hypotheses.tls_threshold > c.hypotheses.shift_bin; }},
    {"refine.radius_start", "must be >= refine.radius_end",
     [](const LocalizerConfig& c) { return !(c.refine.radius_start >= c.refine.radius_end); }},
    {"refine.radius_start", "must be <= 1.5 x refine.cell",
     [](const LocalizerConfig& c) { return c.refine.radius_start > c.refine.cell * 1.5f; }},
};
constexpr uint32_t kRuleCount = sizeof(kRules) / sizeof(kRules[0]);

}  // namespace

uint32_t parameter_count() { return kCount; }
const ParamInfo& parameter(uint32_t i) { return kParams[i < kCount ? i : 0]; }
uint32_t parameter_rule_count() { return kRuleCount; }
const ParamRule& parameter_rule(uint32_t i) { return kRules[i < kRuleCount ? i : 0]; }

const ParamInfo* find_parameter(const char* name) {
  if (name == nullptr) return nullptr;
  for (const ParamInfo& p : kParams)
    if (std::strcmp(p.name, name) == 0) return &p;
  return nullptr;
}

double get_parameter(const LocalizerConfig& config, const ParamInfo& p) {
  LocalizerConfig* c = const_cast<LocalizerConfig*>(&config);  // read only: bind() just locates the field
  const int k = p.classes ? first_class(p.classes) : 0;
  switch (p.type) {
    case ParamType::F32: return *at<float>(c, p, k);
    case ParamType::U32: return *at<uint32_t>(c, p, k);
    case ParamType::U64: return static_cast<double>(*at<uint64_t>(c, p, k));
    case ParamType::Bool: return *at<bool>(c, p, k) ? 1.0 : 0.0;
  }
  return 0.0;
}

bool parameter_accepts(const ParamInfo& p, double v) {
  if (!in_range(p, v)) return false;
  switch (p.type) {
    case ParamType::F32: return std::isfinite(static_cast<float>(v));
    case ParamType::U32: return v >= 0 && v <= 4294967295.0 && v == std::floor(v);
    case ParamType::U64: return v >= 0 && v < 18446744073709551616.0 && v == std::floor(v);
    case ParamType::Bool: return v == 0.0 || v == 1.0;
  }
  return false;
}

Status set_parameter(LocalizerConfig* c, const ParamInfo& p, double v) {
  if (c == nullptr || !parameter_accepts(p, v)) return Status::InvalidArgument;
  for (int k = 0; k < (p.classes ? kNumClasses : 1); ++k) {
    if (p.classes && !(p.classes & class_bit(k))) continue;
    switch (p.type) {
      case ParamType::F32: *at<float>(c, p, k) = static_cast<float>(v); break;
      case ParamType::U32: *at<uint32_t>(c, p, k) = static_cast<uint32_t>(v); break;
      case ParamType::U64: *at<uint64_t>(c, p, k) = static_cast<uint64_t>(v); break;
      case ParamType::Bool: *at<bool>(c, p, k) = v != 0.0; break;
    }
  }
  return Status::Ok;
}

ConfigCheck check_config(const LocalizerConfig& c) {
  LocalizerConfig* m = const_cast<LocalizerConfig*>(&c);  // read only
  for (const ParamInfo& p : kParams) {
    if (!p.classes) {
      if (!in_range(p, get_parameter(c, p))) return ConfigCheck{Status::InvalidArgument, &p, nullptr};
      continue;
    }
    for (int k = 0; k < kNumClasses; ++k)  // every class the parameter sets
      if ((p.classes & class_bit(k)) && !in_range(p, *at<float>(m, p, k)))
        return ConfigCheck{Status::InvalidArgument, &p, nullptr};
  }
  for (const ParamRule& r : kRules)
    if (r.broken(c)) return ConfigCheck{Status::InvalidArgument, &param(r.name), r.rule};
  return ConfigCheck{};
}

}  // namespace gsf
