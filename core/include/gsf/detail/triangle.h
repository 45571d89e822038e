// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Triangle descriptors over the object layer (Outram / STD style): each instance with its K nearest
// instances forms triangles; the key is the labels in vertex order and the sorted, quantised side
// lengths (permutation invariant).
//
// Canonical vertex order: side[0] = |v0 v1| <= side[1] = |v1 v2| <= side[2] = |v2 v0| (the paper's
// d12 <= d23 <= d31), so v0 joins the shortest and longest sides. Exact ties are broken by instance id,
// so the order is deterministic. The same vertex set reached from several anchors is emitted once.
#pragma once
#include <cstdint>

#include "gsf/detail/arena.h"
#include "gsf/detail/bounded_hash_map.h"
#include "gsf/detail/fixed_vector.h"
#include "gsf/map_format.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

// Bird's-eye turning sense of a triangle's vertices in canonical order (v0 -> v1 -> v2). A rotation about
// the vertical keeps it and a mirror image reverses it, and the side lengths cannot tell the two apart: in
// a symmetric layout (a hall's rows, a lattice) a triangle's mirror twin matches it as well as the true
// one, and a clique of such matches fits an upside-down pose. The matcher rejects a match whose senses
// are both known and disagree (triangle_matcher.h). A triangle whose apex lies within
// kOrientationMinHeight of its longest side's line has no reliable sense (centroids are ~0.3 m noisy).
enum TriangleOrientation : uint8_t {  // 0 is no sense: load_map refuses a record holding it
  kOrientationCounterClockwise = 1,
  kOrientationClockwise = 2,
  kOrientationFlat = 3,  // near-collinear: either sense
};
constexpr float kOrientationMinHeight = 1.0f;  // m

using Triangle = MapTriangle;  // the on-disk map record (map_format.h): v[3], side[3], label[3], orientation

Status validate(const TriangleConfig& config);

// The sense of p0 -> p1 -> p2 seen from above (x, y; TriangleOrientation), flat when the apex is within
// kOrientationMinHeight of the line through the longest side (of length longest_side).
uint8_t triangle_orientation(const float* p0, const float* p1, const float* p2, float longest_side);
// Whether two senses contradict each other (both reliable and opposite), `flip` reversing the first (a
// vertex order that is an odd permutation of the canonical one).
inline bool orientations_contradict(uint8_t a, uint8_t b, bool flip) {
  if ((a != kOrientationCounterClockwise && a != kOrientationClockwise) ||
      (b != kOrientationCounterClockwise && b != kOrientationClockwise))
    return false;
  return (a == b) == flip;
}
// The one sense a map triangle may not have against a query triangle of sense a (flip as above): b
// contradicts a exactly when b == contradicting_orientation(a, flip); 0 (no sense, never stored) when a
// has no reliable sense. The matcher's loop compares one byte instead of calling the test.
inline uint8_t contradicting_orientation(uint8_t a, bool flip) {
  if (a != kOrientationCounterClockwise && a != kOrientationClockwise) return 0;
  if (flip) return a;
  return a == kOrientationCounterClockwise ? uint8_t(kOrientationClockwise) : uint8_t(kOrientationCounterClockwise);
}

// The index key (map format v5, docs/map-format.md): bits 62..48 the three labels in vertex order (5 bits
// each), then the quantised sides q_k = floor(side_k / side_bin), 16 bits each (47..32 q0, 31..16 q1, 15..0
// q2). Sorted keys therefore group a label triple's triangles, then q0, q1, q2: the three q2 neighbours of
// a (labels, q0, q1) are one contiguous key range. validate() keeps max_side / side_bin below
// kTriangleKeyMaxBin so every side of a valid triangle fits, with room for the +1 neighbour.
constexpr uint32_t kTriangleKeyMaxBin = 65535;          // largest quantised side a key can hold
constexpr uint32_t kTriangleKeyLabelLimit = 32;         // labels must be below this (5 bits)
constexpr uint64_t kInvalidTriangleKey = ~uint64_t(0);  // never a valid key (bit 63 is always 0)
inline uint64_t triangle_key(const uint8_t* labels, uint32_t q0, uint32_t q1, uint32_t q2) {
  return (uint64_t(labels[0]) << 58) | (uint64_t(labels[1]) << 53) | (uint64_t(labels[2]) << 48) |
         (uint64_t(q0) << 32) | (uint64_t(q1) << 16) | uint64_t(q2);
}
// The key of a triangle; kInvalidTriangleKey when a label is >= kTriangleKeyLabelLimit or a side is
// negative, not finite or quantises above kTriangleKeyMaxBin.
uint64_t triangle_key(const Triangle& t, float side_bin);

// The key of a triangle's vertex set (ids below 2^21, in any order): the same three instances give the
// same key whichever triangle (or vertex order) they came from. The builder emits each set once by it.
inline uint64_t triangle_vertex_set_key(uint32_t a, uint32_t b, uint32_t c) {
  if (a > b) {
    const uint32_t t = a;
    a = b;
    b = t;
  }
  if (b > c) {
    const uint32_t t = b;
    b = c;
    c = t;
  }
  if (a > b) {
    const uint32_t t = a;
    a = b;
    b = t;
  }
  return (uint64_t(a) << 42) | (uint64_t(b) << 21) | c;
}

// Canonical triangle of three instances (ids a, b, c with positions pa, pb, pc).
Triangle make_triangle(uint32_t a, uint32_t b, uint32_t c, const float* pa, const float* pb, const float* pc,
                       const uint8_t* labels);

class TriangleBuilder {
 public:
  static size_t required_bytes(const TriangleConfig& config, uint32_t max_instances);
  Status bind(Arena& arena, const TriangleConfig& config, uint32_t max_instances);
  // centroids: n x 3 (stride floats apart), labels: n. Appends to `out` (cleared first). Returns
  // CapacityExceeded (keeping the deterministic prefix) when out or max_triangles is full.
  Status build(const float* centroids, uint32_t stride, const uint8_t* labels, uint32_t n, FixedVector<Triangle>& out);

 private:
  TriangleConfig config_{};
  uint32_t max_instances_ = 0;
  uint32_t* knn_ = nullptr;  // n x K neighbour ids
  float* knn_d_ = nullptr;   // n x K distances
  uint32_t* knn_count_ = nullptr;
  BoundedHashMap<uint8_t> seen_;
  bool bound_ = false;
};

}  // namespace gsf
