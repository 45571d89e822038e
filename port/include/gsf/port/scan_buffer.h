// Caller-owned, fixed-capacity scan storage that scan sources fill, and its ScanView for core.
#pragma once
#include <cstdint>
#include <vector>

#include "gsf/scan.h"
#include "gsf/semantic_classes.h"

namespace gsf::port {

struct ScanBuffer {
  float* points = nullptr;     // capacity x 4 (x, y, z, intensity)
  uint32_t* labels = nullptr;  // capacity
  float* logits = nullptr;     // capacity x kNumClasses, or nullptr
  uint32_t capacity = 0;
  uint32_t count = 0;
  bool has_logits = false;

  ScanView view() const {
    ScanView v;
    v.points = points;
    v.stride = 4;
    v.labels = labels;
    v.logits = has_logits ? logits : nullptr;
    v.logit_dim = has_logits ? kNumClasses : 0;
    v.count = count;
    return v;
  }
};

// Host convenience: storage allocated once at construction.
class OwnedScanBuffer {
 public:
  explicit OwnedScanBuffer(uint32_t capacity, bool with_logits = true)
      : points_(size_t(capacity) * 4), labels_(capacity), logits_(with_logits ? size_t(capacity) * kNumClasses : 0) {
    buf_.points = points_.data();
    buf_.labels = labels_.data();
    buf_.logits = with_logits ? logits_.data() : nullptr;
    buf_.capacity = capacity;
  }
  ScanBuffer& buffer() { return buf_; }
  const ScanBuffer& buffer() const { return buf_; }

 private:
  std::vector<float> points_;
  std::vector<uint32_t> labels_;
  std::vector<float> logits_;
  ScanBuffer buf_;
};

}  // namespace gsf::port
