// Non-owning view of one semantic LiDAR scan, in the sensor frame. The caller (port layer or firmware)
// owns the memory; core only reads it during the call that receives the view.
#pragma once
#include <cstdint>

namespace gsf {

struct ScanView {
  const float* points = nullptr;     // x, y, z [, intensity, ...] in metres, `stride` floats apart
  uint32_t stride = 4;               // floats per point (4 for KITTI x,y,z,intensity records)
  const uint32_t* labels = nullptr;  // one SemanticKITTI label word per point (low 16 bits = class id)
  const float* logits = nullptr;     // optional: count x logit_dim, dense class order (semantic_classes.h)
  uint32_t logit_dim = 0;            // must be kNumClasses when logits != nullptr
  uint32_t count = 0;                // number of points
};

}  // namespace gsf
