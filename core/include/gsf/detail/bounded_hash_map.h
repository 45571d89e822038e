// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Open-addressing hash map with a fixed slot count, for the per-scan voxel grid and dedup tables.
//
// Keys are uint64 (packed voxel coordinates, packed index pairs). Linear probing; slot count is a power
// of two chosen at bind() time as the smallest >= capacity / max_load. Inserting beyond `capacity`
// entries fails (returns nullptr) so probe chains stay short and the worst case per lookup is bounded by
// the slot count. No erase: the tables are cleared wholesale per scan in O(slots).
// clear_for(n) is a clear() for a caller that will insert at most n keys this time: only a power-of-two
// prefix of the slots (>= 2 n, so the load stays <= 0.5) is used until the next clear, which keeps the
// touched memory proportional to the data, not to the capacity. Lookups see the same keys and values
// either way; only the slot order of for_each differs.
#pragma once
#include <cstdint>
#include <type_traits>

#include "gsf/detail/arena.h"

namespace gsf {

inline uint64_t mix64(uint64_t x) {  // splitmix64 finaliser: good avalanche, deterministic
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return x;
}

template <class V>
class BoundedHashMap {
  static_assert(std::is_trivially_copyable<V>::value, "values are copied as bytes");

 public:
  static uint32_t slots_for(uint32_t capacity) {
    uint64_t want = static_cast<uint64_t>(capacity) * 2u;  // max load factor 0.5
    uint32_t s = 16;
    while (s < want && s < (1u << 31)) s <<= 1;
    return s;
  }

  bool bind(Arena& arena, uint32_t capacity) {
    capacity_ = capacity;
    slots_ = slots_for(capacity);
    keys_ = arena.allocate<uint64_t>(slots_);
    used_ = arena.allocate<uint8_t>(slots_);
    values_ = arena.allocate<V>(slots_);
    size_ = 0;
    if (arena.counting()) {
      slots_ = active_ = 0;
      return true;
    }
    if (!keys_ || !used_ || !values_) {
      slots_ = active_ = 0;
      return false;
    }
    active_ = slots_;
    clear();
    return true;
  }

  void clear() { clear_for(capacity_); }
  // Clears, then uses only the slots needed for at most `entries` keys (see the header comment).
  void clear_for(uint32_t entries) {
    uint8_t* used = used_;
    const uint32_t n = active_;  // only the previously used prefix can hold keys
    for (uint32_t i = 0; i < n; ++i) used[i] = 0;
    size_ = 0;
    const uint32_t want = slots_for(entries < capacity_ ? entries : capacity_);
    active_ = want < slots_ ? want : slots_;
  }

  uint32_t size() const { return size_; }
  uint32_t capacity() const { return capacity_; }

  V* find(uint64_t key) {
    if (active_ == 0) return nullptr;
    const uint32_t mask = active_ - 1;
    for (uint32_t i = static_cast<uint32_t>(mix64(key)) & mask, n = 0; n < active_; ++n, i = (i + 1) & mask) {
      if (!used_[i]) return nullptr;
      if (keys_[i] == key) return &values_[i];
    }
    return nullptr;
  }
  const V* find(uint64_t key) const { return const_cast<BoundedHashMap*>(this)->find(key); }

  // Returns the value slot for key, inserting a default V when absent. `inserted` tells which.
  // nullptr when the key is absent and the map already holds `capacity` entries.
  V* find_or_insert(uint64_t key, bool* inserted = nullptr) {
    if (inserted) *inserted = false;
    if (active_ == 0) return nullptr;
    const uint32_t mask = active_ - 1;
    for (uint32_t i = static_cast<uint32_t>(mix64(key)) & mask, n = 0; n < active_; ++n, i = (i + 1) & mask) {
      if (!used_[i]) {
        if (size_ >= capacity_) return nullptr;
        used_[i] = 1;
        keys_[i] = key;
        values_[i] = V();
        ++size_;
        if (inserted) *inserted = true;
        return &values_[i];
      }
      if (keys_[i] == key) return &values_[i];
    }
    return nullptr;
  }

  // The slot of a value pointer returned by find/find_or_insert, and back (valid until the next clear).
  uint32_t slot_of(const V* value) const { return static_cast<uint32_t>(value - values_); }
  V& at_slot(uint32_t slot) { return values_[slot]; }

  // Iterate occupied slots in slot order (deterministic for a given insertion sequence).
  template <class F>
  void for_each(F&& f) {
    for (uint32_t i = 0; i < active_; ++i)
      if (used_[i]) f(keys_[i], values_[i]);
  }

 private:
  uint64_t* keys_ = nullptr;
  uint8_t* used_ = nullptr;
  V* values_ = nullptr;
  uint32_t slots_ = 0;
  uint32_t active_ = 0;  // slots in use since the last clear (a power of two <= slots_)
  uint32_t size_ = 0;
  uint32_t capacity_ = 0;
};

}  // namespace gsf
