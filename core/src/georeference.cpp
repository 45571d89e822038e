#include "gsf/georeference.h"

#include <cmath>
#include <cstring>

namespace gsf {
namespace {

bool printable(char c) { return c >= 0x20 && c <= 0x7E; }

}  // namespace

MapGeoreference local_georeference() {
  MapGeoreference g;
  std::memset(&g, 0, sizeof(g));
  set_frame_name(&g, "local");
  return g;
}

bool valid_georeference(const MapGeoreference& g) {
  for (double o : g.origin)
    if (!std::isfinite(o)) return false;
  uint32_t n = 0;
  while (n < kMapFrameNameBytes && g.frame[n] != '\0') {
    if (!printable(g.frame[n])) return false;
    ++n;
  }
  if (n == 0 || n == kMapFrameNameBytes) return false;  // empty, or no terminating NUL
  for (uint32_t i = n; i < kMapFrameNameBytes; ++i)
    if (g.frame[i] != '\0') return false;  // padding must be NUL (same contents, same bytes)
  return true;
}

bool set_frame_name(MapGeoreference* g, const char* name) {
  if (g == nullptr || name == nullptr) return false;
  uint32_t n = 0;
  while (name[n] != '\0') {
    if (n + 1 >= kMapFrameNameBytes || !printable(name[n])) return false;
    ++n;
  }
  if (n == 0) return false;
  std::memset(g->frame, 0, sizeof(g->frame));
  std::memcpy(g->frame, name, n);
  return true;
}

Eigen::Isometry3d to_map_frame(const MapGeoreference& g, const Eigen::Isometry3d& local_T_x) {
  Eigen::Isometry3d out = local_T_x;
  out.translation() += Eigen::Vector3d(g.origin[0], g.origin[1], g.origin[2]);
  return out;
}

Eigen::Isometry3d to_map_local(const MapGeoreference& g, const Eigen::Isometry3d& frame_T_x) {
  Eigen::Isometry3d out = frame_T_x;
  out.translation() -= Eigen::Vector3d(g.origin[0], g.origin[1], g.origin[2]);
  return out;
}

}  // namespace gsf
