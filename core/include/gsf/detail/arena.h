// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Bump allocator carved once from a caller-provided buffer.
//
// The same layout code runs twice: once on a *counting* arena (no buffer) to learn how many bytes a
// Config needs (required_bytes), and once on the real buffer. That way the size computation can never
// drift from the layout. Nothing is ever freed individually; mark()/rewind() give scoped scratch.
#pragma once
#include <cstddef>
#include <cstdint>
#include <new>

namespace gsf {

class Arena {
 public:
  // Counting arena: allocations succeed as far as bookkeeping goes but return nullptr.
  Arena() = default;
  Arena(void* buffer, size_t bytes) : base_(static_cast<uint8_t*>(buffer)), capacity_(bytes) {}

  bool counting() const { return base_ == nullptr; }
  size_t used() const { return used_; }
  size_t capacity() const { return counting() ? SIZE_MAX : capacity_; }
  size_t high_water() const { return high_water_; }
  // True once any allocation did not fit; the arena then stays failed until rewound past it.
  bool overflowed() const { return overflowed_; }

  // Raw aligned bytes. Returns nullptr (and sets overflowed) when the buffer is exhausted.
  void* allocate_bytes(size_t bytes, size_t align) {
    const size_t start = (used_ + (align - 1)) & ~(align - 1);
    if (start < used_ || start + bytes < start) {
      overflowed_ = true;
      return nullptr;
    }
    const size_t end = start + bytes;
    if (!counting() && end > capacity_) {
      overflowed_ = true;
      return nullptr;
    }
    used_ = end;
    if (used_ > high_water_) high_water_ = used_;
    return counting() ? nullptr : base_ + start;
  }

  // Uninitialised array of n trivially-constructible T (value-initialised when zero=true).
  template <class T>
  T* allocate(size_t n, bool zero = false) {
    if (n > SIZE_MAX / sizeof(T)) {
      overflowed_ = true;
      return nullptr;
    }
    void* p = allocate_bytes(n * sizeof(T), alignof(T) < 16 ? 16 : alignof(T));
    if (p == nullptr) return nullptr;
    T* t = static_cast<T*>(p);
    if (zero)
      for (size_t i = 0; i < n; ++i) new (t + i) T();
    return t;
  }

  size_t mark() const { return used_; }
  void rewind(size_t mark) {
    if (mark <= used_) used_ = mark;
    overflowed_ = false;
  }

 private:
  uint8_t* base_ = nullptr;
  size_t capacity_ = 0;
  size_t used_ = 0;
  size_t high_water_ = 0;
  bool overflowed_ = false;
};

// Bytes a stage's bind(arena, args...) takes: the bind code itself runs on a counting arena, so a
// stage's required_bytes can never disagree with its layout.
template <class Stage, class... Args>
size_t counted_bytes(const Args&... args) {
  Arena counting;
  Stage stage;
  stage.bind(counting, args...);
  return counting.used();
}

}  // namespace gsf
