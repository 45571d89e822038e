// The parameter list (gsf/parameters.h, core/src/parameters.def): names, defaults within their ranges,
// set/get through the table, and check_config() naming the failing parameter and rule.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <set>
#include <string>

#include "gsf/config.h"
#include "gsf/gsf.h"
#include "gsf/parameters.h"

namespace test_config {

using namespace gsf;

TEST_CASE("The parameter list: unique names, at most 25 user-facing, defaults valid and inside their ranges") {
  std::set<std::string> names;
  uint32_t user = 0;
  const LocalizerConfig defaults;
  REQUIRE(parameter_count() > 60);
  for (uint32_t i = 0; i < parameter_count(); ++i) {
    const ParamInfo& p = parameter(i);
    INFO(p.name);
    CHECK(names.insert(p.name).second);
    CHECK(find_parameter(p.name) == &p);
    CHECK(std::strlen(p.doc) > 10);
    CHECK(std::strchr(p.doc, '\n') == nullptr);
    CHECK(p.lo <= p.hi);
    user += p.level == ParamLevel::User;
    CHECK(parameter_accepts(p, get_parameter(defaults, p)));
  }
  CHECK(user <= kMaxUserParameters);
  CHECK(find_parameter("match.nonsense") == nullptr);
  CHECK(find_parameter(nullptr) == nullptr);
  CHECK(check_config(defaults).status == Status::Ok);
  CHECK(validate(defaults) == Status::Ok);
  // The history switches and dead knobs are gone (CHANGELOG.md, 2026-12-03).
  for (const char* gone :
       {"match.reject_mirrored", "match.fill_pairs", "hypotheses.shift_vote_support", "hypotheses.height_consensus",
        "poles.min_points", "poles.max_ring_voxels", "gsf.normalize_mass", "match.use_gsf"})
    CHECK(find_parameter(gone) == nullptr);
}

TEST_CASE("set_parameter stores the value in the field it names, of its type, only inside the range") {
  LocalizerConfig c;
  const ParamInfo& tau = *find_parameter("gsf.tau");
  CHECK(tau.type == ParamType::F32);
  REQUIRE(set_parameter(&c, tau, 0.1) == Status::Ok);
  CHECK(c.gsf.tau == 0.1f);
  CHECK(get_parameter(c, tau) == double(0.1f));
  CHECK(set_parameter(&c, tau, 0.0) == Status::InvalidArgument);  // (0, ...]
  CHECK(set_parameter(&c, tau, std::nan("")) == Status::InvalidArgument);
  CHECK(c.gsf.tau == 0.1f);  // unchanged by a refused value

  const ParamInfo& k = *find_parameter("triangle.neighbours");
  CHECK(set_parameter(&c, k, 12) == Status::Ok);
  CHECK(c.triangle.neighbours == 12u);
  CHECK(set_parameter(&c, k, 12.5) == Status::InvalidArgument);  // a whole number
  CHECK(set_parameter(&c, k, 1) == Status::InvalidArgument);     // [2, 64]

  const ParamInfo& on = *find_parameter("gsf.enabled");
  CHECK(on.type == ParamType::Bool);
  CHECK(on.level == ParamLevel::Expert);
  CHECK(set_parameter(&c, on, 0) == Status::Ok);
  CHECK_FALSE(c.gsf.enabled);
  CHECK(set_parameter(&c, on, 2) == Status::InvalidArgument);

  const ParamInfo& budget = *find_parameter("hypotheses.first_budget");
  CHECK(budget.type == ParamType::U64);
  CHECK(set_parameter(&c, budget, 5e9) == Status::Ok);
  CHECK(c.hypotheses.first_budget == 5000000000ull);

  // One value for the thin vertical classes; the others keep theirs.
  const ParamInfo& vt = *find_parameter("cluster.vertical_tolerance");
  CHECK(vt.classes == kThinClasses);
  CHECK(set_parameter(&c, vt, 1.5) == Status::Ok);
  for (int cls = 0; cls < kNumClasses; ++cls)
    CHECK(c.cluster.vertical_tolerance[cls] == ((kThinClasses & class_bit(cls)) ? 1.5f : 0.0f));
  CHECK(get_parameter(c, vt) == 1.5);
  c.cluster.vertical_tolerance[kTrunk] = 10.0f;  // set directly, out of range: check_config sees it
  const ConfigCheck bad = check_config(c);
  CHECK(bad.status == Status::InvalidArgument);
  CHECK(bad.param == &vt);
}

TEST_CASE("check_config names the first failing parameter: its range, or the rule it breaks") {
  LocalizerConfig c;
  c.verify.disagree_weight = 101.0f;
  ConfigCheck r = check_config(c);
  REQUIRE(r.status == Status::InvalidArgument);
  CHECK(std::string(r.param->name) == "verify.disagree_weight");
  CHECK(r.rule == nullptr);  // a range failure: lo..hi tell it
  CHECK(r.param->lo == 0.0);
  CHECK(r.param->hi == 100.0);
  CHECK(validate(c) == Status::InvalidArgument);

  struct Case {
    const char* name;
    void (*spoil)(LocalizerConfig*);
  };
  const Case rules[] = {
      {"voxel.max_range", [](LocalizerConfig* x) { x->voxel.max_range = x->voxel.min_range; }},
      {"voxel.column_size", [](LocalizerConfig* x) { x->voxel.column_size = 0.5f * x->voxel.voxel_size; }},
      {"field.grid_layers", [](LocalizerConfig* x) { x->field.grid_layers = 2; }},
      {"field.grid_nx", [](LocalizerConfig* x) { x->field.grid_nx = x->field.grid_ny = 12; }},
      {"triangle.map_neighbours", [](LocalizerConfig* x) { x->triangle.map_neighbours = x->triangle.neighbours - 1; }},
      {"triangle.max_side", [](LocalizerConfig* x) { x->triangle.max_side = x->triangle.min_side; }},
      {"triangle.max_side", [](LocalizerConfig* x) { x->triangle.side_bin = 0.0005f; }},
      {"triangle.sparse_side_tolerance",
       [](LocalizerConfig* x) { x->triangle.sparse_side_tolerance = x->triangle.relative_side_tolerance; }},
      {"hypotheses.tls_threshold", [](LocalizerConfig* x) { x->hypotheses.tls_threshold = 2.5f; }},
      {"refine.radius_start", [](LocalizerConfig* x) { x->refine.radius_end = 1.0f, x->refine.radius_start = 0.8f; }},
      {"refine.radius_start", [](LocalizerConfig* x) { x->refine.cell = 0.5f; }},
  };
  for (const Case& rc : rules) {
    LocalizerConfig x;
    rc.spoil(&x);
    r = check_config(x);
    INFO(rc.name);
    REQUIRE(r.status == Status::InvalidArgument);
    CHECK(std::string(r.param->name) == rc.name);
    CHECK(r.rule != nullptr);
  }
  // The three-dimensional field passes with its layers.
  LocalizerConfig three;
  three.field.input_dims = 3;
  three.field.grid_layers = 3;
  CHECK(check_config(three).status == Status::Ok);
}

TEST_CASE("gsf_config carries the user-facing parameters; gsf_config_check names a bad one") {
  gsf_config c;
  gsf_config_default(&c);
  const LocalizerConfig k;
  CHECK(c.gsf_tau == k.gsf.tau);
  CHECK(c.voxel_voxel_size == k.voxel.voxel_size);
  CHECK(c.hypotheses_first_budget == k.hypotheses.first_budget);
  CHECK(c.verify_enabled == 1u);
  CHECK(gsf_config_check(&c) == nullptr);
  CHECK(std::string(gsf_config_check(nullptr)) == "config");
  gsf_config bad = c;
  bad.hypotheses_tls_threshold = 3.0f;  // beyond the (expert) shift_bin 2 m
  CHECK(std::string(gsf_config_check(&bad)) == "hypotheses.tls_threshold");
  bad = c;
  bad.refine_enabled = 2;
  CHECK(std::string(gsf_config_check(&bad)) == "refine.enabled");
  bad = c;
  bad.confidence_min_probability = -0.5f;
  CHECK(std::string(gsf_config_check(&bad)) == "confidence.min_probability");
  bad = c;
  bad.label_set = 7;
  CHECK(std::string(gsf_config_check(&bad)) == "label_set");
  bad = c;
  bad.struct_bytes = 4;
  CHECK(std::string(gsf_config_check(&bad)) == "struct_bytes");
  uint32_t user = 0;
  for (uint32_t i = 0; i < parameter_count(); ++i) user += parameter(i).level == ParamLevel::User;
  CHECK(user == 25);  // each one a gsf_config field (c_api.cpp asserts the struct holds exactly those)
}

}  // namespace test_config
