// LocalizerConfig's parameters by name: the one list (core/src/parameters.def) as a table, with each
// parameter's type, unit, valid range, class and one-line doc. From it come the CLI's `--set name=value`
// (set_parameter), the C API's gsf_config mapping (c_api.cpp), check_config() (validate() naming the
// failing parameter) and docs/parameters.md (`gsf params --markdown`).
//
// Why an X-macro list rather than a constexpr array: one list must give (1) a runtime table of names,
// units, ranges and docs, (2) a compile-time check that each entry's type is its field's declared type,
// and (3) the C mapping, which pastes `group` and `field` into the gsf_config member `group_field` - C++17
// has no way to reach a member by a name held in a constexpr table. The macro writes each of them from
// the same line, so a parameter cannot be in one and missing from another.
#pragma once
#include <cstdint>

#include "gsf/config.h"
#include "gsf/semantic_classes.h"
#include "gsf/status.h"

namespace gsf {

enum class ParamType : uint8_t { F32, U32, U64, Bool };
// User-facing parameters (at most kMaxUserParameters) are what an integrator sets: capacities, the scan's
// range, the values a map must be built with, the main tuning and the decision rule; each is a field of
// the C API's gsf_config. Expert parameters keep their defaults unless an evaluation or a study sets them
// (C++ and `--set` only).
enum class ParamLevel : uint8_t { User, Expert };
constexpr uint32_t kMaxUserParameters = 25;

// The thin vertical classes cluster.vertical_tolerance sets as one value.
constexpr ClassMask kThinClasses = class_bit(kPole) | class_bit(kTrunk) | class_bit(kTrafficSign);

struct ParamInfo {
  const char* name;   // the `--set` name, e.g. "verify.disagree_weight"
  const char* field;  // the LocalizerConfig member it binds, e.g. "verify.disagree_weight"
  ParamType type;
  ParamLevel level;
  const char* unit;  // "m", "deg", "points", ...; "" for none
  // Valid range: lo..hi, each end open or closed; hi may be +infinity. A bool's is [0, 1].
  double lo, hi;
  bool lo_open, hi_open;
  const char* doc;  // one line
  // Where the value lives: the field, or for a per-class parameter the array's first element, of which
  // the classes in `classes` hold the value (0: a single field).
  void* (*bind)(LocalizerConfig* config);
  ClassMask classes;
};

uint32_t parameter_count();
const ParamInfo& parameter(uint32_t index);         // 0 <= index < parameter_count(), in the list's order
const ParamInfo* find_parameter(const char* name);  // nullptr for an unknown name

// The value as a double (bool: 0 or 1; a per-class parameter: its first class's value).
double get_parameter(const LocalizerConfig& config, const ParamInfo& p);
// True when `value` is of the parameter's type (a whole number for integers, 0 or 1 for a bool) and in
// its range (NaN never is).
bool parameter_accepts(const ParamInfo& p, double value);
// Stores `value` (converted to the parameter's type) if parameter_accepts(p, value); else InvalidArgument
// and the config is unchanged.
Status set_parameter(LocalizerConfig* config, const ParamInfo& p, double value);

// A rule between parameters: `name` (the parameter it is reported on) breaks `rule` when broken(config).
struct ParamRule {
  const char* name;
  const char* rule;  // what follows the name: "must be > voxel.min_range", "/ triangle.side_bin must be < 65534"
  bool (*broken)(const LocalizerConfig& config);
};
uint32_t parameter_rule_count();
const ParamRule& parameter_rule(uint32_t index);

// What check_config found: Ok, or the first parameter that is out of its range or breaks a rule with
// another one (`rule` then says which, e.g. "must be > voxel.min_range"; nullptr for a range failure:
// param's lo..hi tell it).
struct ConfigCheck {
  Status status = Status::Ok;
  const ParamInfo* param = nullptr;  // the failing parameter (nullptr when Ok)
  const char* rule = nullptr;
};
// Every listed parameter's range, then the rules between them (what validate() returns the status of).
ConfigCheck check_config(const LocalizerConfig& config);

}  // namespace gsf
