// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// The map's compact semantic layer and the whole-scan verification of a pose hypothesis.
//
// Layer: a bird's-eye grid of `cell` metre cells grouped in square tiles of tile_cells x tile_cells,
// only tiles the mapping drive saw are stored (sorted tile keys + cells). A cell is a class mask:
// bit c set when class c makes at least the builder's minimum share of the cell's ground voxels (for
// ground classes) or of its above-ground voxels (other classes); bit 31 marks a cell the map observed.
// Stored with a palette per tile (format v4): a tile lists its distinct masks once (a road tile has a
// handful) and each cell is a 1-byte index into that list, so a 16 x 16 tile is 256 B + 4 B a mask
// instead of 1 KiB; tile_cells is therefore at most 16 (at most 256 distinct masks a tile). Since format
// v6 a palette entry is a pair: the cell's mask and its neighbour mask, the union of the masks of the
// four cells sharing an edge with it (0 for a side in a tile not stored), so a tile lists its distinct
// pairs (still at most 256: one per cell) and the neighbour test below costs one more load.
//
// Verification: every sampled voxel of the query scan (stuff included: terrain, vegetation, fences,
// walls, not only instances) is moved by the hypothesis into the map and compared with its cell:
//   ground-class voxel: agrees if the cell has that ground class; disagrees if the cell has other ground
//                       classes only; unknown if the cell has no ground.
//   other voxel:        agrees if the cell has that class; disagrees if the cell was observed without it
//                       (the map saw that spot and it held something else or nothing above ground);
//                       unknown if the cell was never observed.
//   either, disagreeing: agrees after all if one of the cell's four edge neighbours has the class (a
//                       hypothesis pose is good to about a cell).
// score = sum of stability weights of agreeing voxels - the same sum over disagreeing voxels, each times
// its disagree weight (DisagreeWeights). In a
// lattice every shift of the columns agrees on the columns and the roads; the hedge, the terrain
// island, the fence 30 m away are what separate the shifts, and they are in the score.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/map_format.h"
#include "gsf/semantic_classes.h"
#include "gsf/stage_results.h"
#include "gsf/status.h"

namespace gsf {

class VoxelLayer;

constexpr uint32_t kCellObserved = 1u << 31;
constexpr ClassMask kGroundClasses =
    class_bit(kRoad) | class_bit(kParking) | class_bit(kSidewalk) | class_bit(kOtherGround) | class_bit(kTerrain);
constexpr uint32_t kMaxSemanticTileCells = 16;  // tile_cells^2 <= 256: a cell's palette index is a byte

// Tile key of integer tile coordinates; valid for |tx|, |ty| < 32768 (false otherwise).
bool semantic_tile_key(int64_t tx, int64_t ty, uint32_t* key);

struct SemanticGridView {
  float cell = 0.0f;        // m
  uint32_t tile_cells = 0;  // cells per tile side
  uint32_t tile_count = 0;
  uint32_t palette_count = 0;                 // masks over all tiles' palettes
  const uint32_t* tile_keys = nullptr;        // tile_count, strictly increasing
  const uint32_t* palette_offsets = nullptr;  // tile_count + 1: tile t's masks are palette[off[t] .. off[t+1])
  const uint32_t* palette = nullptr;          // palette_count class masks
  const uint8_t* cells = nullptr;        // tile_count x tile_cells^2 indices into the tile's palette, row-major (y, x)
  const uint32_t* neighbours = nullptr;  // palette_count: each entry's 4-neighbour mask (see above)

  bool empty() const { return tile_count == 0; }
  // Cell mask at (x, y) in the map frame; 0 outside stored tiles. *tile_hint caches the last tile index.
  uint32_t cell_at(float x, float y, uint32_t* tile_hint) const;
  // The cell's neighbour mask at (x, y) (the union of its four edge neighbours' masks); 0 outside.
  uint32_t neighbours_at(float x, float y) const;
  // Structural checks for untrusted arrays: parameters, keys strictly increasing, palette offsets
  // monotone from 0 to palette_count with 1..256 entries a tile, every cell's index inside its tile's
  // palette, masks and neighbour masks (present with any tile) use only class bits below num_classes
  // and the observed bit.
  Status validate(uint32_t num_classes) const;
};

// The map's semantic layer (empty when the map has none).
inline SemanticGridView semantic_grid_view(const MapView& map) {
  SemanticGridView g;
  g.cell = map.params.semantic_cell;
  g.tile_cells = map.params.semantic_tile_cells;
  g.tile_count = map.counts.semantic_tiles;
  g.palette_count = map.counts.semantic_palette;
  g.tile_keys = map.semantic_tile_keys;
  g.palette_offsets = map.semantic_palette_offsets;
  g.palette = map.semantic_palette;
  g.cells = map.semantic_cells;
  g.neighbours = map.semantic_neighbours;
  return g;
}

// What a voxel the map contradicts costs, per unit of its class weight (score = agree - these).
// `contradicted`: a voxel on a cell the map saw empty above ground, or a ground voxel on other ground.
// `other_class`: an above-ground voxel on (or beside) a cell the map saw holding other above-ground
// classes, none its own. The map saw something there, so the voxel may be right and its label wrong:
// how much less than a contradiction that costs depends on the scan's segmentation noise
// (disagree_weights.h estimates it per scan). One weight converts to both (the same penalty for every
// disagreement).
struct DisagreeWeights {
  DisagreeWeights(float w = 1.0f) : contradicted(w), other_class(w) {}  // NOLINT: one weight is both
  DisagreeWeights(float contradicted_w, float other_class_w)
      : contradicted(contradicted_w), other_class(other_class_w) {}
  float contradicted;
  float other_class;
};

// Unweighted counts of a pose's sampled above-ground voxels on the map's observed cells, by verdict:
// what disagree_weights.h compares between the best pose and its competitors. (Ground voxels and cells
// the map never observed are left out.)
struct VerdictCounts {
  uint32_t agree = 0;
  uint32_t other_class = 0;   // on or beside cells holding other above-ground classes only
  uint32_t contradicted = 0;  // on a cell the map saw empty above ground
};

// The bird's-eye part of a query voxel that verification reads (12 B of the voxel's 96): a query scores
// a few hundred poses on strided samples of its voxels, and this compact copy keeps them in cache.
struct VerifyPoint {
  float x, y;
  uint32_t label;  // dense class
};
// out[i] for every voxel i of the layer (out holds voxels.size()).
void fill_verify_points(const VoxelLayer& voxels, VerifyPoint* out);

// Scores map_T_scan over at most max_points voxels of the query's voxel layer, sampled with a uniform
// stride over the layer (never "the first N"). weights: stability weight per dense class.
PoseVerification verify_pose(const VoxelLayer& voxels, const SemanticGridView& grid,
                             const Eigen::Isometry3d& map_T_scan, uint32_t max_points, const float* weights,
                             DisagreeWeights disagree = DisagreeWeights());

// The pattern search below makes at most this many passes a round; each pass can move once along x, once
// along y and once in heading, so a round moves at most this many steps along each (what a caller that
// bounds the search's reach needs: tracker.cpp).
constexpr uint32_t kPatternSearchPassesPerRound = 2;

// The pattern search's record of the best pose so far, sample by sample, and a second slot for the
// probe's. A translation probe reuses the rotated positions and looks a sample up in the map only when
// the step moved it into another cell (a verdict is a function of the cell and the class): a 0.1 m step
// moves the few samples near a cell edge. Optional: without it, or when a round samples more than
// `capacity`, every probe scores every sample from scratch, with the same results bit for bit. The
// caller owns the storage (20 B a sample a slot).
struct SearchMemo {
  struct Sample {
    float rotated[2];  // x, y rotated into the map, before the translation
    int32_t cell[2];   // along x, y: tile x kMaxSemanticTileCells + cell within it (INT32_MIN: outside the tiles)
    uint32_t verdict;
  };
  Sample* slot[2] = {};
  uint32_t capacity = 0;  // samples a slot
};

// verify_pose after a small bird's-eye pattern search around map_T_scan (moves of step_m along x and y
// and step_deg of heading, halved each round, 6 probes a pass, a second pass when the first moved), so
// a hypothesis whose clique pose is a fraction of a metre off is compared at its best alignment; the
// pose found is then scored on max_points. Coarse to fine: the probes of every round but the last are
// scored on max_points / search_divisor voxels, the last (finest) round's on max_points /
// polish_divisor. *refined (optional) receives the best pose found. at_start (optional):
// verify_pose(map_T_scan, max_points) already computed by the caller, returned as is when the search
// does not move. Cost: at most (12 (rounds - 1) + 1) x max_points / search_divisor + 13 x max_points /
// polish_divisor + max_points cell lookups.
PoseVerification verify_pose_refined(const VoxelLayer& voxels, const SemanticGridView& grid,
                                     const Eigen::Isometry3d& map_T_scan, uint32_t max_points, const float* weights,
                                     uint32_t rounds, float step_m, float step_deg, Eigen::Isometry3d* refined,
                                     uint32_t search_divisor = 4, uint32_t polish_divisor = 4,
                                     const PoseVerification* at_start = nullptr,
                                     DisagreeWeights disagree = DisagreeWeights());

// verify_pose over compact points that also writes each sampled voxel's evidence: evidence[k] = +w when
// the k-th sample (voxel k x stride) agrees, -w x its disagree weight when it disagrees, 0 when unknown
// (w its class weight).
// evidence holds at least min(n, max_points) floats. Same score as verify_pose, bit for bit.
PoseVerification verify_pose_evidence(const VerifyPoint* points, uint32_t n, const SemanticGridView& grid,
                                      const Eigen::Isometry3d& map_T_scan, uint32_t max_points, const float* weights,
                                      DisagreeWeights disagree, float* evidence);

// The verdicts of map_T_scan's sampled voxels (the strided sample verify_pose scores on max_points).
VerdictCounts count_verdicts(const VerifyPoint* points, uint32_t n, const SemanticGridView& grid,
                             const Eigen::Isometry3d& map_T_scan, uint32_t max_points);

// How many of n points (xyz triples, scan frame), moved by map_T_scan, land on or beside a cell the map
// observed: of the scan's instances, those the map could hold at this pose. An instance beyond the mapped
// area can match nothing at any pose, so the confidence's inlier share counts only these (confidence.h).
uint32_t count_observed(const SemanticGridView& grid, const Eigen::Isometry3d& map_T_scan, const float* xyz,
                        uint32_t n);

// The same two, over n compact points (fill_verify_points of the layer: the same results, bit for bit).
PoseVerification verify_pose(const VerifyPoint* points, uint32_t n, const SemanticGridView& grid,
                             const Eigen::Isometry3d& map_T_scan, uint32_t max_points, const float* weights,
                             DisagreeWeights disagree = DisagreeWeights());
// memo (optional, SearchMemo): the search's record of its samples' cells.
PoseVerification verify_pose_refined(const VerifyPoint* points, uint32_t n, const SemanticGridView& grid,
                                     const Eigen::Isometry3d& map_T_scan, uint32_t max_points, const float* weights,
                                     uint32_t rounds, float step_m, float step_deg, Eigen::Isometry3d* refined,
                                     uint32_t search_divisor = 4, uint32_t polish_divisor = 4,
                                     const PoseVerification* at_start = nullptr,
                                     DisagreeWeights disagree = DisagreeWeights(), SearchMemo* memo = nullptr);

}  // namespace gsf
