// Fuzz the SemanticKITTI scan parser: the input is split into .bin / .label / logits byte ranges by its
// first bytes. Any input must give a status; on Ok every point is finite and count <= capacity.
#include <cmath>
#include <cstdint>
#include <cstring>

#include "gsf/port/semantic_kitti.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  const uint8_t flags = data[0];
  const size_t rest = size - 4;
  size_t bin = rest * data[1] / 255, lab = (rest - bin) * data[2] / 255;
  const uint8_t* p = data + 4;
  static gsf::port::OwnedScanBuffer buf(256, true);
  gsf::port::KittiReadOptions opt;
  opt.drop_non_finite = flags & 1;
  opt.require_labels = flags & 2;
  const gsf::Status s =
      gsf::port::parse_scan(p, bin, (flags & 4) ? p + bin : nullptr, lab, (flags & 8) ? p + bin + lab : nullptr,
                            rest - bin - lab, opt, buf.buffer());
  if (s == gsf::Status::Ok) {
    if (buf.buffer().count > buf.buffer().capacity) __builtin_trap();
    for (uint32_t i = 0; i < buf.buffer().count; ++i)
      for (int k = 0; k < 4; ++k)
        if (!std::isfinite(buf.buffer().points[4 * i + k])) __builtin_trap();
  } else if (buf.buffer().count != 0) {
    __builtin_trap();  // errors never leave a partial scan
  }
  return 0;
}
