// Test helper: a synthetic labelled scan built point by point, viewed as a gsf::ScanView
// (with logits when `logits` is filled, count x kNumClasses).
#pragma once
#include <cstdint>
#include <vector>

#include "gsf/scan.h"
#include "gsf/semantic_classes.h"

namespace gsf_test {

struct Cloud {
  std::vector<float> pts;
  std::vector<uint32_t> labels;
  std::vector<float> logits;  // empty, or count x kNumClasses
  void add(float x, float y, float z, uint32_t label) {
    pts.insert(pts.end(), {x, y, z, 0.0f});
    labels.push_back(label);
  }
  gsf::ScanView view() const {
    gsf::ScanView v;
    v.points = pts.data();
    v.labels = labels.data();
    v.count = static_cast<uint32_t>(labels.size());
    if (!logits.empty()) {
      v.logits = logits.data();
      v.logit_dim = gsf::kNumClasses;
    }
    return v;
  }
};

}  // namespace gsf_test
