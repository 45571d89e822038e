// The map builder's voxel accumulators, kept per square tile of the map-local x-y plane so the builder's
// memory is set by its configuration, not by the world: at most max_resident_tiles tiles are held in
// memory; touching another one spills the least recently used tile's accumulators to a temporary file
// (raw doubles, so reloading it on a revisit continues the same sums in the same order: a loop closes
// exactly as in memory). Host side; uses the heap and one temporary file.
// The file is a set of slots, one per spilled tile: a tile spilled again overwrites its slot when it
// fits, else the slot goes to a free list (coalesced, reused first fit) and the tile gets another, with
// a quarter of headroom now that it was revisited. Before the file would grow past twice the slots it
// holds, it is compacted (the slots moved down in offset order, the file truncated): its size never
// exceeds 2x (the config's max_spill_ratio) the largest total of live slots
// (TileStoreStats::spill_live_peak_bytes). A compaction moves less than the dead space that triggered
// it, and freed slots made that: at 2 the moves are of the order of the bytes the spills wrote (linear).
#pragma once
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "gsf/semantic_classes.h"
#include "gsf/status.h"

namespace gsf::mapping {

// One map voxel's running sums over every scan point that fell into it (point-count weighted).
struct VoxelAccum {
  double sum[3] = {0, 0, 0};
  double prob[kNumClasses] = {};
  uint64_t count = 0;
};

// Key of the map-local voxel (cell `size`) holding (x, y, z): 21 bits per axis, so 2^20 voxels either
// side of the origin (419 km at 0.4 m) before keys wrap; add_scan keeps poses within
// kMaxMapLocalCoordinate of it. x is in the top bits, so key order is x-major, then y, then z.
inline uint64_t voxel_key(double x, double y, double z, double size) {
  const int64_t ix = static_cast<int64_t>(std::floor(x / size)) + (1 << 20);
  const int64_t iy = static_cast<int64_t>(std::floor(y / size)) + (1 << 20);
  const int64_t iz = static_cast<int64_t>(std::floor(z / size)) + (1 << 20);
  return (uint64_t(ix & 0x1FFFFF) << 42) | (uint64_t(iy & 0x1FFFFF) << 21) | uint64_t(iz & 0x1FFFFF);
}
inline int32_t voxel_key_x(uint64_t key) { return int32_t((key >> 42) & 0x1FFFFF) - (1 << 20); }
inline int32_t voxel_key_y(uint64_t key) { return int32_t((key >> 21) & 0x1FFFFF) - (1 << 20); }

struct TileStoreConfig {
  // Tile side in voxels; 0: the whole world is one tile, held in memory (no spilling).
  int32_t tile_voxels = 0;
  // Tiles held in memory at once (>= 1; 0: no limit, nothing is spilled).
  uint32_t max_resident_tiles = 0;
  // Directory of the spill file (removed when the store is destroyed); empty: std::tmpfile().
  std::string spill_dir;
  // The spill file is compacted before it would grow past this multiple of its live slots (>= 1).
  // Freed slots are reused first, so at 2 it is rarely needed (the bound on fragmentation); 1 compacts
  // whenever there is a hole (tests; the moves are then no longer bounded by the spills' writes).
  double max_spill_ratio = 2.0;
};

struct TileStoreStats {
  uint32_t tiles = 0;
  uint64_t spills = 0;         // tiles written to the spill file (a dirty tile evicted)
  uint64_t reloads = 0;        // tiles read back from it
  uint64_t spill_bytes = 0;    // size of the spill file now (its slots and free space)
  uint32_t peak_resident = 0;  // most tiles in memory at once
  uint64_t peak_resident_voxels = 0;
  // The largest resident working set in the spill file's bytes (192 B a voxel: key and raw sums), the
  // unit of spill_peak_bytes; the hash maps that hold it in memory take more.
  uint64_t peak_resident_bytes = 0;
  uint64_t spill_peak_bytes = 0;       // the file's largest size (<= max_spill_ratio x the next)
  uint64_t spill_live_peak_bytes = 0;  // the largest total of live slots (tiles' copies with headroom)
  uint64_t compactions = 0;            // times the file was compacted
  uint64_t compaction_bytes = 0;       // bytes they moved
};

class TileStore {
 public:
  explicit TileStore(const TileStoreConfig& config);
  ~TileStore();
  TileStore(const TileStore&) = delete;
  TileStore& operator=(const TileStore&) = delete;

  // The accumulator of a voxel, created empty on first use; its tile becomes resident (which may spill
  // another). The reference is valid until the next call. IoError if the spill file fails.
  VoxelAccum* accumulator(uint64_t voxel_key, Status* status);

  // Tile ids (sorted: x-major, like voxel keys) and the id of a voxel key's tile.
  std::vector<uint64_t> tile_ids() const;
  uint64_t tile_of(uint64_t voxel_key) const;
  // Tile coordinates of a tile id.
  static int32_t tile_x(uint64_t id) { return int32_t(uint32_t(id >> 32) - 0x80000000u); }
  static int32_t tile_y(uint64_t id) { return int32_t(uint32_t(id) - 0x80000000u); }
  static uint64_t tile_id(int32_t tx, int32_t ty) {
    return (uint64_t(uint32_t(tx) + 0x80000000u) << 32) | uint64_t(uint32_t(ty) + 0x80000000u);
  }
  bool has_tile(uint64_t id) const { return tiles_.count(id) != 0; }
  int32_t tile_voxels() const { return config_.tile_voxels; }

  // Appends the voxels of tile `id` whose voxel x, y lie in [x0, x1) x [y0, y1) (every voxel of a
  // single-tile store) to *out, unsorted. A spilled tile is read from the file and stays spilled.
  Status append_voxels(uint64_t id, int32_t x0, int32_t x1, int32_t y0, int32_t y1,
                       std::vector<std::pair<uint64_t, VoxelAccum>>* out);
  uint64_t voxel_count() const;
  // Spills every resident tile (bounded stores only: max_resident_tiles > 0), so the memory goes to the
  // next phase; append_voxels() reads them back from the file.
  Status spill_resident();
  // Records the voxels now in memory for stats().peak_resident_voxels (the builder calls it per scan).
  void note_resident_voxels();
  // Forgets every tile (an unbounded store only: the blocked build empties it between blocks); the stats
  // stay.
  void clear();
  const TileStoreStats& stats() const { return stats_; }

 private:
  struct Tile {
    std::unordered_map<uint64_t, VoxelAccum> voxels;
    bool resident = true;
    bool dirty = true;          // changed since its last spilled copy (or never spilled)
    uint64_t last_use = 0;      // LRU clock
    uint64_t spill_offset = 0;  // latest spilled copy: byte offset, voxel count and slot size (voxels)
    uint64_t spill_count = 0;
    uint64_t spill_capacity = 0;
    uint64_t voxel_count = 0;  // voxels, resident or not
  };
  Status make_resident(Tile* tile);
  Status evict_one(const Tile* keep);
  Status open_spill_file();
  Status spill(Tile* tile);
  Status reload(Tile* tile);
  // The spill file's slots: a free list (offset -> bytes, coalesced), first-fit allocation, compaction.
  void release_slot(Tile* tile);
  Status allocate_slot(Tile* tile, uint64_t capacity);
  Status compact();
  Status move_bytes(uint64_t from, uint64_t to, uint64_t bytes);
  template <typename Wanted>
  Status read_spilled(const Tile& tile, const Wanted& wanted, std::vector<std::pair<uint64_t, VoxelAccum>>* out);

  TileStoreConfig config_;
  std::unordered_map<uint64_t, Tile> tiles_;
  std::vector<Tile*> resident_list_;  // tiles in memory (map nodes: stable addresses)
  uint64_t clock_ = 0;
  uint64_t last_id_ = UINT64_MAX;  // the last tile used (most voxels of a scan in a row share one)
  Tile* last_tile_ = nullptr;
  std::FILE* spill_file_ = nullptr;
  std::string spill_path_;
  uint64_t spill_end_ = 0;             // end of the last slot (a slot freed at the end shortens it)
  uint64_t spill_file_size_ = 0;       // bytes the file spans (written since its last truncation)
  uint64_t live_bytes_ = 0;            // the tiles' slots
  std::map<uint64_t, uint64_t> free_;  // free slots below spill_end_: offset -> bytes, none adjacent
  TileStoreStats stats_;
};

}  // namespace gsf::mapping
