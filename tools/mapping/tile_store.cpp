#include "mapping/tile_store.h"

#include "mapping/floor_div.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <iterator>

#include <unistd.h>

namespace gsf::mapping {
namespace {

// One spilled voxel: its key and raw accumulator (host byte order; the file never outlives the process).
constexpr size_t kRecordBytes = sizeof(uint64_t) + sizeof(VoxelAccum);
constexpr size_t kIoChunkRecords = 4096;

}  // namespace

TileStore::TileStore(const TileStoreConfig& config) : config_(config) {
  if (config_.tile_voxels < 0) config_.tile_voxels = 0;
  if (config_.tile_voxels == 0) config_.max_resident_tiles = 0;  // one tile: nothing to spill
  if (!(config_.max_spill_ratio >= 1.0)) config_.max_spill_ratio = 1.0;
}

TileStore::~TileStore() {
  if (spill_file_) std::fclose(spill_file_);
  if (!spill_path_.empty()) std::remove(spill_path_.c_str());
}

uint64_t TileStore::tile_of(uint64_t voxel_key) const {
  if (config_.tile_voxels == 0) return tile_id(0, 0);
  return tile_id(static_cast<int32_t>(floor_div(voxel_key_x(voxel_key), config_.tile_voxels)),
                 static_cast<int32_t>(floor_div(voxel_key_y(voxel_key), config_.tile_voxels)));
}

std::vector<uint64_t> TileStore::tile_ids() const {
  std::vector<uint64_t> ids;
  ids.reserve(tiles_.size());
  for (const auto& kv : tiles_) ids.push_back(kv.first);
  std::sort(ids.begin(), ids.end());
  return ids;
}

uint64_t TileStore::voxel_count() const {
  uint64_t n = 0;
  for (const auto& kv : tiles_) n += kv.second.resident ? kv.second.voxels.size() : kv.second.voxel_count;
  return n;
}

VoxelAccum* TileStore::accumulator(uint64_t voxel_key, Status* status) {
  *status = Status::Ok;
  const uint64_t id = tile_of(voxel_key);
  Tile* tile = last_tile_;
  if (id != last_id_ || !tile || !tile->resident) {
    auto it = tiles_.find(id);
    if (it == tiles_.end()) {
      it = tiles_.emplace(id, Tile{}).first;
      resident_list_.push_back(&it->second);
      stats_.tiles = static_cast<uint32_t>(tiles_.size());
    }
    tile = &it->second;
    *status = make_resident(tile);
    if (*status != Status::Ok) return nullptr;
    last_id_ = id;
    last_tile_ = tile;
  }
  tile->last_use = ++clock_;
  tile->dirty = true;
  return &tile->voxels[voxel_key];
}

Status TileStore::append_voxels(uint64_t id, int32_t x0, int32_t x1, int32_t y0, int32_t y1,
                                std::vector<std::pair<uint64_t, VoxelAccum>>* out) {
  auto it = tiles_.find(id);
  if (it == tiles_.end()) return Status::Ok;
  Tile* tile = &it->second;
  const bool all = config_.tile_voxels == 0;
  auto wanted = [&](uint64_t key) {
    const int32_t x = voxel_key_x(key), y = voxel_key_y(key);
    return all || (x >= x0 && x < x1 && y >= y0 && y < y1);
  };
  if (tile->resident) {
    tile->last_use = ++clock_;
    for (const auto& kv : tile->voxels)
      if (wanted(kv.first)) out->push_back(kv);
    return Status::Ok;
  }
  // Spilled: read the wanted records straight from the file (the tile stays out of memory, so loading
  // a neighbourhood does not evict the tiles about to be read next).
  return read_spilled(*tile, wanted, out);
}

template <typename Wanted>
Status TileStore::read_spilled(const Tile& tile, const Wanted& wanted,
                               std::vector<std::pair<uint64_t, VoxelAccum>>* out) {
  if (std::fflush(spill_file_) != 0 || fseeko(spill_file_, static_cast<off_t>(tile.spill_offset), SEEK_SET) != 0)
    return Status::IoError;
  // Sized for this tile's records, up to a chunk: a zeroed 4096-record chunk per read of a small tile
  // was most of the builder's page faults.
  std::vector<unsigned char> buf(static_cast<size_t>(std::min<uint64_t>(kIoChunkRecords, tile.spill_count)) *
                                 kRecordBytes);
  for (uint64_t done = 0; done < tile.spill_count;) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(kIoChunkRecords, tile.spill_count - done));
    if (std::fread(buf.data(), 1, n * kRecordBytes, spill_file_) != n * kRecordBytes) return Status::IoError;
    for (size_t r = 0; r < n; ++r) {
      std::pair<uint64_t, VoxelAccum> kv;
      std::memcpy(&kv.first, buf.data() + r * kRecordBytes, sizeof kv.first);
      if (!wanted(kv.first)) continue;
      std::memcpy(&kv.second, buf.data() + r * kRecordBytes + sizeof kv.first, sizeof kv.second);
      out->push_back(kv);
    }
    done += n;
  }
  return Status::Ok;
}

Status TileStore::make_resident(Tile* tile) {
  if (!tile->resident) {
    const Status s = reload(tile);
    if (s != Status::Ok) return s;
    tile->resident = true;
    resident_list_.push_back(tile);
  }
  // Over budget: spill the least recently used other tiles.
  while (config_.max_resident_tiles > 0 && resident_list_.size() > config_.max_resident_tiles) {
    const Status s = evict_one(tile);
    if (s != Status::Ok) return s;
  }
  stats_.peak_resident = std::max(stats_.peak_resident, static_cast<uint32_t>(resident_list_.size()));
  return Status::Ok;
}

void TileStore::note_resident_voxels() {
  uint64_t voxels = 0;
  for (const Tile* t : resident_list_) voxels += t->voxels.size();
  stats_.peak_resident_voxels = std::max(stats_.peak_resident_voxels, voxels);
  stats_.peak_resident_bytes = stats_.peak_resident_voxels * kRecordBytes;
}

void TileStore::clear() {
  tiles_.clear();
  resident_list_.clear();
  last_tile_ = nullptr;
  last_id_ = UINT64_MAX;
}

Status TileStore::spill_resident() {
  if (config_.max_resident_tiles == 0) return Status::Ok;
  while (!resident_list_.empty()) {
    const Status s = evict_one(nullptr);
    if (s != Status::Ok) return s;
  }
  return Status::Ok;
}

Status TileStore::evict_one(const Tile* keep) {
  size_t victim_at = SIZE_MAX;
  for (size_t i = 0; i < resident_list_.size(); ++i)
    if (resident_list_[i] != keep &&
        (victim_at == SIZE_MAX || resident_list_[i]->last_use < resident_list_[victim_at]->last_use))
      victim_at = i;
  if (victim_at == SIZE_MAX) return Status::Ok;
  Tile* victim = resident_list_[victim_at];
  if (victim->dirty) {
    const Status s = spill(victim);
    if (s != Status::Ok) return s;
  }
  victim->voxel_count = victim->voxels.size();
  std::unordered_map<uint64_t, VoxelAccum>().swap(victim->voxels);  // give the memory back
  victim->resident = false;
  resident_list_[victim_at] = resident_list_.back();
  resident_list_.pop_back();
  if (victim == last_tile_) last_tile_ = nullptr;
  return Status::Ok;
}

Status TileStore::open_spill_file() {
  if (spill_file_) return Status::Ok;
  if (config_.spill_dir.empty()) {
    spill_file_ = std::tmpfile();
  } else {
    std::string path = config_.spill_dir + "/gsf-tiles-XXXXXX";
    std::vector<char> name(path.begin(), path.end());
    name.push_back('\0');
    const int fd = mkstemp(name.data());
    if (fd >= 0) {
      spill_file_ = fdopen(fd, "w+b");
      spill_path_ = name.data();
      if (!spill_file_) close(fd);
    }
  }
  return spill_file_ ? Status::Ok : Status::IoError;
}

Status TileStore::spill(Tile* tile) {
  Status s = open_spill_file();
  if (s != Status::Ok) return s;
  // A tile spilled again (after a revisit) overwrites its old copy when that slot is big enough, else
  // the old slot is freed and the tile takes another, with a quarter of headroom for the next revisit
  // (a first spill takes none: most tiles are never revisited, their headroom would be dead space).
  const uint64_t count = tile->voxels.size();
  if (count > tile->spill_capacity) {
    const bool revisited = tile->spill_capacity > 0;
    release_slot(tile);
    s = allocate_slot(tile, revisited ? count + count / 4 : count);
    if (s != Status::Ok) return s;
  }
  if (fseeko(spill_file_, static_cast<off_t>(tile->spill_offset), SEEK_SET) != 0) return Status::IoError;
  std::vector<unsigned char> buf;
  buf.reserve(kIoChunkRecords * kRecordBytes);
  for (const auto& kv : tile->voxels) {
    const size_t at = buf.size();
    buf.resize(at + kRecordBytes);
    std::memcpy(buf.data() + at, &kv.first, sizeof(uint64_t));
    std::memcpy(buf.data() + at + sizeof(uint64_t), &kv.second, sizeof(VoxelAccum));
    if (buf.size() == kIoChunkRecords * kRecordBytes) {
      if (std::fwrite(buf.data(), 1, buf.size(), spill_file_) != buf.size()) return Status::IoError;
      buf.clear();
    }
  }
  if (!buf.empty() && std::fwrite(buf.data(), 1, buf.size(), spill_file_) != buf.size()) return Status::IoError;
  tile->spill_count = count;
  tile->dirty = false;
  if (std::fflush(spill_file_) != 0) return Status::IoError;  // the file's size is then spill_file_size_
  spill_file_size_ = std::max(spill_file_size_, tile->spill_offset + count * kRecordBytes);
  stats_.spills++;
  stats_.spill_bytes = spill_file_size_;
  stats_.spill_peak_bytes = std::max(stats_.spill_peak_bytes, spill_file_size_);
  return Status::Ok;
}

// The tile's slot (if any) to the free list, merged with free neighbours; free space reaching the
// end of the slots shortens them instead.
void TileStore::release_slot(Tile* tile) {
  if (tile->spill_capacity == 0) return;
  uint64_t at = tile->spill_offset, bytes = tile->spill_capacity * kRecordBytes;
  live_bytes_ -= bytes;
  tile->spill_capacity = 0;
  tile->spill_count = 0;
  auto next = free_.lower_bound(at);
  if (next != free_.end() && next->first == at + bytes) {
    bytes += next->second;
    next = free_.erase(next);
  }
  if (next != free_.begin()) {
    const auto prev = std::prev(next);
    if (prev->first + prev->second == at) {
      at = prev->first;
      bytes += prev->second;
      free_.erase(prev);
    }
  }
  if (at + bytes == spill_end_) spill_end_ = at;
  else free_.emplace(at, bytes);
}

// A slot of `capacity` records: the first free one that fits (lowest offset), else at the end of the
// slots, after compacting the file if the end would pass max_spill_ratio x the live slots.
Status TileStore::allocate_slot(Tile* tile, uint64_t capacity) {
  const uint64_t bytes = capacity * kRecordBytes;
  auto fit = free_.begin();
  while (fit != free_.end() && fit->second < bytes) ++fit;
  if (fit != free_.end()) {
    tile->spill_offset = fit->first;
    if (fit->second > bytes) free_.emplace(fit->first + bytes, fit->second - bytes);
    free_.erase(fit);
  } else {
    if (double(spill_end_ + bytes) > config_.max_spill_ratio * double(live_bytes_ + bytes)) {
      const Status s = compact();
      if (s != Status::Ok) return s;
    }
    tile->spill_offset = spill_end_;
    spill_end_ += bytes;
  }
  tile->spill_capacity = capacity;
  live_bytes_ += bytes;
  stats_.spill_live_peak_bytes = std::max(stats_.spill_live_peak_bytes, live_bytes_);
  return Status::Ok;
}

// The live slots moved down in offset order (each keeps its headroom), the free list emptied and the
// file truncated to the slots: it then holds exactly the live slots.
Status TileStore::compact() {
  std::vector<Tile*> slots;
  for (auto& kv : tiles_)
    if (kv.second.spill_capacity > 0) slots.push_back(&kv.second);
  std::sort(slots.begin(), slots.end(), [](const Tile* a, const Tile* b) { return a->spill_offset < b->spill_offset; });
  uint64_t at = 0;
  for (Tile* t : slots) {
    if (t->spill_offset != at) {
      const Status s = move_bytes(t->spill_offset, at, t->spill_count * kRecordBytes);
      if (s != Status::Ok) return s;
      stats_.compaction_bytes += t->spill_count * kRecordBytes;
      t->spill_offset = at;
    }
    at += t->spill_capacity * kRecordBytes;
  }
  free_.clear();
  spill_end_ = at;
  if (std::fflush(spill_file_) != 0 || ftruncate(fileno(spill_file_), static_cast<off_t>(at)) != 0)
    return Status::IoError;
  spill_file_size_ = at;
  stats_.spill_bytes = at;
  stats_.compactions++;
  return Status::Ok;
}

// Copies `bytes` from offset `from` down to `to` (< from) chunk by chunk, front first: a chunk is read
// before any later write can reach it, so overlapping ranges copy correctly.
Status TileStore::move_bytes(uint64_t from, uint64_t to, uint64_t bytes) {
  std::vector<unsigned char> buf(static_cast<size_t>(std::min<uint64_t>(kIoChunkRecords * kRecordBytes, bytes)));
  if (std::fflush(spill_file_) != 0) return Status::IoError;
  for (uint64_t done = 0; done < bytes;) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(buf.size(), bytes - done));
    if (fseeko(spill_file_, static_cast<off_t>(from + done), SEEK_SET) != 0 ||
        std::fread(buf.data(), 1, n, spill_file_) != n)
      return Status::IoError;
    if (fseeko(spill_file_, static_cast<off_t>(to + done), SEEK_SET) != 0 ||
        std::fwrite(buf.data(), 1, n, spill_file_) != n)
      return Status::IoError;
    done += n;
  }
  return Status::Ok;
}

Status TileStore::reload(Tile* tile) {
  tile->voxels.reserve(tile->spill_count);
  std::vector<std::pair<uint64_t, VoxelAccum>> records;
  records.reserve(tile->spill_count);
  const Status s = read_spilled(
      *tile, [](uint64_t) { return true; }, &records);
  if (s != Status::Ok) return s;
  for (const auto& kv : records) tile->voxels.emplace(kv.first, kv.second);
  tile->dirty = false;  // the spilled copy is still exact until the tile changes
  stats_.reloads++;
  return Status::Ok;
}

}  // namespace gsf::mapping
