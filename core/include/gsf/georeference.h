// Where a map sits on Earth: a double-precision origin and the name of the frame it is given in.
//
// Everything inside a map (instance centroids, fields, refinement points, the semantic layer) is float32
// in the map-local frame: metres relative to the origin. float32 has 24 bits of mantissa, so a
// coordinate of 5,412,345 m (a UTM northing) would be stored to the nearest 0.5 m; relative to an origin
// near the mapped area the same point keeps millimetres. The map frame is the frame the mapping poses were
// given in (e.g. "utm-32N"); a map-local pose becomes a map-frame pose by adding the origin to its
// translation, in double (to_map_frame), and back (to_map_local). Rotations are the same in both frames:
// the local frame is the map frame translated, never rotated.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

namespace gsf {

constexpr uint32_t kMapFrameNameBytes = 32;  // frame names: 1..31 printable ASCII characters, NUL-padded

struct MapGeoreference {
  double origin[3];                // map-frame coordinates (m) of the map-local (0, 0, 0)
  char frame[kMapFrameNameBytes];  // e.g. "local", "utm-32N"; NUL-terminated, NUL-padded to the end
};
static_assert(sizeof(MapGeoreference) == 56, "on-disk layout (docs/map-format.md)");

// The georeference of a map whose local frame is its frame: origin 0, frame "local".
MapGeoreference local_georeference();

// True if `name` is 1..31 printable ASCII characters (0x20..0x7E) followed by NUL bytes up to
// kMapFrameNameBytes, and every origin coordinate is finite. What load_map accepts.
bool valid_georeference(const MapGeoreference& g);

// Sets the frame name (NUL-padding the rest); false, leaving `g` unchanged, if `name` is null, empty,
// longer than 31 characters or not printable ASCII.
bool set_frame_name(MapGeoreference* g, const char* name);

// map_T_x (map-local) -> frame_T_x (the map's frame): the origin is added to the translation in double.
Eigen::Isometry3d to_map_frame(const MapGeoreference& g, const Eigen::Isometry3d& local_T_x);
// frame_T_x (the map's frame) -> map_T_x (map-local): the origin is subtracted in double. For a
// translation within a factor of two of the origin (any pose of the mapped area in UTM metres) the
// subtraction is exact (Sterbenz), so frame -> local -> frame gives back the same bits.
Eigen::Isometry3d to_map_local(const MapGeoreference& g, const Eigen::Isometry3d& frame_T_x);

}  // namespace gsf
