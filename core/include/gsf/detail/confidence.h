// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h and the C API gsf.h.
// The answer's confidence: a calibrated probability that the chosen pose is right (translation < 5 m and
// rotation < 10 deg from the truth), and the default decision rule built on it.
#pragma once
#include <cstdint>

namespace gsf {

struct ConfidenceConfig {
  // The default decision rule: LocalizeResult::confident = confidence >= min_probability.
  float min_probability = 0.5f;
};

}  // namespace gsf
