// Fuzz poses.txt parsing: any text gives Ok (all poses finite) or CorruptData.
#include <cstdint>
#include <string>
#include <vector>

#include "gsf/port/semantic_kitti.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<Eigen::Isometry3d> poses;
  const gsf::Status s = gsf::port::parse_poses(std::string(reinterpret_cast<const char*>(data), size),
                                               Eigen::Isometry3d::Identity(), &poses);
  if (s == gsf::Status::Ok)
    for (const auto& p : poses)
      if (!p.matrix().allFinite()) __builtin_trap();
  return 0;
}
