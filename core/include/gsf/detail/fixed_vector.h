// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Fixed-capacity vectors in the ETL style: FixedVector<T> is the capacity-erased view that functions
// take by reference; StaticVector<T, N> owns inline storage; a FixedVector can also be bound to arena
// memory at init. push_back on a full vector returns false and changes nothing (callers map it to
// Status::CapacityExceeded) - never reallocates, never writes out of bounds.
#pragma once
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "gsf/detail/arena.h"

namespace gsf {

template <class T>
class FixedVector {
  static_assert(std::is_trivially_destructible<T>::value, "FixedVector holds trivially destructible T");

 public:
  FixedVector() = default;
  FixedVector(T* storage, uint32_t capacity) : data_(storage), capacity_(storage ? capacity : 0) {}

  // Bind to arena memory; on a counting arena this only reserves bytes (capacity stays 0).
  bool bind(Arena& arena, uint32_t capacity) {
    data_ = arena.allocate<T>(capacity);
    capacity_ = data_ ? capacity : 0;
    size_ = 0;
    return data_ != nullptr || arena.counting();
  }

  uint32_t size() const { return size_; }
  uint32_t capacity() const { return capacity_; }
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ >= capacity_; }

  T* data() { return data_; }
  const T* data() const { return data_; }
  T& operator[](uint32_t i) { return data_[i]; }
  const T& operator[](uint32_t i) const { return data_[i]; }
  T& back() { return data_[size_ - 1]; }
  const T& back() const { return data_[size_ - 1]; }

  T* begin() { return data_; }
  T* end() { return data_ + size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }

  bool push_back(const T& v) {
    if (size_ >= capacity_) return false;
    data_[size_++] = v;
    return true;
  }
  void pop_back() {
    if (size_ > 0) --size_;
  }
  void clear() { size_ = 0; }
  // Shrink only; growing past size() would expose uninitialised elements.
  void truncate(uint32_t n) {
    if (n < size_) size_ = n;
  }
  // Grow to n default-initialised elements if it fits.
  bool resize(uint32_t n) {
    if (n > capacity_) return false;
    for (uint32_t i = size_; i < n; ++i) data_[i] = T();
    size_ = n;
    return true;
  }

 protected:
  T* data_ = nullptr;
  uint32_t size_ = 0;
  uint32_t capacity_ = 0;
};

template <class T, uint32_t N>
class StaticVector : public FixedVector<T> {
 public:
  StaticVector() : FixedVector<T>(storage_, N) {}
  StaticVector(const StaticVector& o) : FixedVector<T>(storage_, N) { copy_from(o); }
  StaticVector& operator=(const StaticVector& o) {
    if (this != &o) copy_from(o);
    return *this;
  }

 private:
  void copy_from(const StaticVector& o) {
    this->size_ = o.size_;
    for (uint32_t i = 0; i < o.size_; ++i) storage_[i] = o.storage_[i];
  }
  T storage_[N];
};

}  // namespace gsf
