// Test fixture cache: the byte-level writer and reader of a cached TinyWorld file (save_world and
// load_world in tiny_world.h). Every read is checked; a short or corrupted file reads as not ok.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "mapping/map_builder.h"

namespace gsf_test {
namespace world_cache {

constexpr char kMagic[8] = {'G', 'S', 'F', 'T', 'W', 'L', 'D', '1'};
static_assert(std::is_trivially_copyable<gsf::mapping::MapBuildStats>::value, "stats are written as bytes");

class Writer {
 public:
  explicit Writer(FILE* f) : f_(f) {}
  void bytes(const void* p, size_t n) { ok_ = ok_ && (n == 0 || std::fwrite(p, 1, n, f_) == n); }
  template <class T>
  void pod(const T& v) {
    bytes(&v, sizeof(T));
  }
  template <class T>
  void array(const std::vector<T>& v) {
    pod(static_cast<uint64_t>(v.size()));
    bytes(v.data(), v.size() * sizeof(T));
  }
  bool ok() const { return ok_; }

 private:
  FILE* f_;
  bool ok_ = true;
};

class Reader {
 public:
  explicit Reader(FILE* f) : f_(f) {}
  void bytes(void* p, size_t n) { ok_ = ok_ && (n == 0 || std::fread(p, 1, n, f_) == n); }
  template <class T>
  void pod(T* v) {
    bytes(v, sizeof(T));
  }
  // max_count bounds what a corrupted length may ask for (the tiny worlds are far below it).
  template <class T>
  void array(std::vector<T>* v, uint64_t max_count = uint64_t{1} << 28) {
    uint64_t n = 0;
    pod(&n);
    if (!ok_ || n > max_count) {
      ok_ = false;
      return;
    }
    v->resize(n);
    bytes(v->data(), n * sizeof(T));
  }
  bool ok() const { return ok_; }

 private:
  FILE* f_;
  bool ok_ = true;
};

}  // namespace world_cache
}  // namespace gsf_test
