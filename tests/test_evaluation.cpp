// The evaluation's metrics (tools/gsf/evaluation.cpp, compiled into this test): the confidence's
// reliability bins, expected calibration error and Brier score, the decision rule's counts and the
// precision curve, on a hand-computed case.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "evaluation.h"

using namespace gsf::cli;

namespace {

// Five queries: confidence, has a pose, success; answered under the rule confidence >= 0.5.
std::vector<QueryRecord> five_queries() {
  struct Q {
    double confidence;
    bool has_pose, success;
  };
  const Q qs[] = {{0.9, true, true}, {0.7, true, true}, {0.7, true, false}, {0.0, false, false}, {0.3, true, true}};
  std::vector<QueryRecord> records;
  for (const Q& q : qs) {
    QueryRecord r;
    r.confidence = q.confidence;
    r.has_pose = q.has_pose;
    r.success = q.success;
    r.answered = q.has_pose && q.confidence >= 0.5;
    records.push_back(r);
  }
  return records;
}

}  // namespace

TEST_CASE("Reliability bins are [k/10, (k+1)/10), the last one closed") {
  CHECK(reliability_bin(0.0) == 0);
  CHECK(reliability_bin(0.0999) == 0);
  CHECK(reliability_bin(0.1) == 1);
  CHECK(reliability_bin(0.3) == 3);
  CHECK(reliability_bin(0.7) == 7);
  CHECK(reliability_bin(0.9) == 9);
  CHECK(reliability_bin(1.0) == 9);
}

TEST_CASE("ECE and Brier score of a hand-computed case") {
  // Bins: 0 {0 / fail}, 3 {0.3 / success}, 7 {0.7 success, 0.7 fail}, 9 {0.9 / success}.
  // ECE = 1/5 |0 - 0| + 1/5 |1 - 0.3| + 2/5 |0.5 - 0.7| + 1/5 |1 - 0.9| = 0.14 + 0.08 + 0.02 = 0.24.
  // Brier = (0 + 0.49 + 0.09 + 0.49 + 0.01) / 5 = 0.216.
  const Calibration c = calibrate({{0.9, true}, {0.7, true}, {0.7, false}, {0.0, false}, {0.3, true}});
  CHECK(c.queries == 5);
  CHECK(c.ece == Approx(0.24).margin(1e-12));
  CHECK(c.brier == Approx(0.216).margin(1e-12));
  uint32_t total = 0;
  for (const ReliabilityBin& b : c.bins) total += b.count;
  CHECK(total == 5);
  CHECK(c.bins[7].count == 2);
  CHECK(c.bins[7].mean_confidence == Approx(0.7));
  CHECK(c.bins[7].success_rate == Approx(0.5));
  CHECK(c.bins[9].lo == Approx(0.9));
  CHECK(c.bins[9].hi == Approx(1.0));
  CHECK(c.bins[5].count == 0);
  CHECK(std::isnan(c.bins[5].mean_confidence));  // an empty bin has no mean (JSON null)
}

TEST_CASE("A perfectly calibrated or an empty set has ECE 0") {
  CHECK(calibrate({{1.0, true}, {0.0, false}}).ece == 0.0);
  CHECK(calibrate({{1.0, true}, {0.0, false}}).brier == 0.0);
  CHECK(calibrate({}).ece == 0.0);
  CHECK(calibrate({}).queries == 0);
}

TEST_CASE("The summary counts the decision rule's answers, wrong answers and declined right ones") {
  const ModeSummary s = summarize("gsf", five_queries(), 0.5);
  CHECK(s.queries == 5);
  CHECK(s.with_pose == 4);
  CHECK(s.successes == 3);
  CHECK(s.min_confidence == 0.5);
  CHECK(s.rule.answered == 3);
  CHECK(s.rule.wrong == 1);           // 0.7 and wrong
  CHECK(s.rule.declined_right == 1);  // 0.3 and right
  CHECK(s.rule.precision == Approx(2.0 / 3.0));
  CHECK(s.rule.answered_share == Approx(3.0 / 5.0));
  CHECK(s.calibration.ece == Approx(0.24).margin(1e-12));
  // The curve at the rule's threshold agrees with the rule; at 0 every query with a pose is answered.
  bool at_rule = false;
  for (const CurvePoint& p : s.curve) {
    if (p.threshold == 0.0) CHECK(p.answered == Approx(4.0 / 5.0));
    if (p.threshold == 0.7) {
      at_rule = true;  // 0.5 is not a query's confidence; 0.7 answers the same three
      CHECK(p.answered == Approx(s.rule.answered_share));
      CHECK(p.precision == Approx(s.rule.precision));
    }
  }
  CHECK(at_rule);
}
