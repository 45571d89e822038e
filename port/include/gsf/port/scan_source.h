// A sequence of labelled scans with poses (dataset readers implement it; firmware has its driver).
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/port/scan_buffer.h"
#include "gsf/status.h"

namespace gsf::port {

class ScanSource {
 public:
  virtual ~ScanSource() = default;
  virtual uint32_t size() const = 0;
  virtual uint32_t frame_id(uint32_t index) const = 0;  // file number (frames may be sparse)
  // Fills `out`; on any error out.count == 0 and the source stays usable.
  virtual Status read(uint32_t index, ScanBuffer& out) = 0;
  virtual Status pose(uint32_t index, Eigen::Isometry3d* world_T_lidar) const = 0;
};

}  // namespace gsf::port
