#include "gsf/detail/max_clique.h"

#include <cmath>

namespace gsf {
namespace {

inline uint32_t words_for(uint32_t n) { return (n + 63) / 64; }
inline int lowest_bit(uint64_t w) { return __builtin_ctzll(w); }

}  // namespace

size_t ConsistencyGraph::required_bytes(uint32_t max_vertices) { return counted_bytes<ConsistencyGraph>(max_vertices); }

Status ConsistencyGraph::bind(Arena& arena, uint32_t max_vertices) {
  if (max_vertices == 0 || max_vertices > 4096) return Status::InvalidArgument;
  max_vertices_ = max_vertices;
  bits_ = arena.allocate<uint64_t>(size_t(max_vertices) * words_for(max_vertices));
  n_ = 0;
  if (arena.counting()) return Status::Ok;
  return bits_ ? Status::Ok : Status::BufferTooSmall;
}

Status ConsistencyGraph::reset(uint32_t n) {
  if (!bits_) return Status::NotInitialized;
  if (n > max_vertices_) return Status::CapacityExceeded;
  n_ = n;
  words_ = words_for(n);
  for (size_t i = 0; i < size_t(n) * words_; ++i) bits_[i] = 0;
  return Status::Ok;
}

void ConsistencyGraph::add_edge(uint32_t i, uint32_t j) {
  if (i == j || i >= n_ || j >= n_) return;
  bits_[size_t(i) * words_ + (j >> 6)] |= uint64_t(1) << (j & 63);
  bits_[size_t(j) * words_ + (i >> 6)] |= uint64_t(1) << (i & 63);
}

void ConsistencyGraph::remove_edge(uint32_t i, uint32_t j) {
  if (i == j || i >= n_ || j >= n_) return;
  bits_[size_t(i) * words_ + (j >> 6)] &= ~(uint64_t(1) << (j & 63));
  bits_[size_t(j) * words_ + (i >> 6)] &= ~(uint64_t(1) << (i & 63));
}

uint32_t ConsistencyGraph::remove_edges_at_heading(const float* a, const float* b, double yaw, double tolerance,
                                                   float min_length) {
  const double c = std::cos(yaw), s = std::sin(yaw), cos_tol = std::cos(tolerance);
  const double min2 = double(min_length) * min_length;
  uint32_t removed = 0;
  // Each edge (i, j > i) once, by the set bits of row i: removing one clears only its own two bits.
  for (uint32_t i = 0; i + 1 < n_; ++i)
    for (uint32_t w = (i + 1) >> 6; w < words_; ++w) {
      uint64_t bits = row(i)[w];
      if (w == (i + 1) >> 6) bits &= ~uint64_t(0) << ((i + 1) & 63);  // only j > i
      for (; bits != 0; bits &= bits - 1) {
        const uint32_t j = w * 64 + uint32_t(lowest_bit(bits));
        const double ax = double(a[3 * j]) - a[3 * i], ay = double(a[3 * j + 1]) - a[3 * i + 1];
        const double bx = double(b[3 * j]) - b[3 * i], by = double(b[3 * j + 1]) - b[3 * i + 1];
        const double la2 = ax * ax + ay * ay, lb2 = bx * bx + by * by;
        if (la2 < min2 || lb2 < min2) continue;
        // cos of the angle between the rotated query direction and the map direction
        const double rx = c * ax - s * ay, ry = s * ax + c * ay;
        if ((rx * bx + ry * by) >= cos_tol * std::sqrt(la2 * lb2)) {
          remove_edge(i, j);
          ++removed;
        }
      }
    }
  return removed;
}

Status ConsistencyGraph::build(const float* a, const float* b, uint32_t n, float eps, float z_weight) {
  const Status s = reset(n);
  if (s != Status::Ok) return s;
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t j = i + 1; j < n; ++j) {
      const float dax = a[3 * i] - a[3 * j], day = a[3 * i + 1] - a[3 * j + 1],
                  daz = (a[3 * i + 2] - a[3 * j + 2]) * z_weight;
      const float dbx = b[3 * i] - b[3 * j], dby = b[3 * i + 1] - b[3 * j + 1],
                  dbz = (b[3 * i + 2] - b[3 * j + 2]) * z_weight;
      const float da = std::sqrt(dax * dax + day * day + daz * daz);
      const float db = std::sqrt(dbx * dbx + dby * dby + dbz * dbz);
      if (std::fabs(da - db) <= eps) add_edge(i, j);
    }
  return Status::Ok;
}

size_t MaxCliqueSolver::required_bytes(uint32_t max_vertices) { return counted_bytes<MaxCliqueSolver>(max_vertices); }

Status MaxCliqueSolver::bind(Arena& arena, uint32_t max_vertices) {
  bound_ = false;
  if (max_vertices == 0 || max_vertices > 4096) return Status::InvalidArgument;
  max_vertices_ = max_vertices;
  words_max_ = words_for(max_vertices);
  const size_t depth = size_t(max_vertices < kMaxCliqueDepth ? max_vertices : kMaxCliqueDepth) + 1;
  frames_ = arena.allocate<Frame>(depth);
  pool_words_ = arena.allocate<uint64_t>(depth * words_max_);
  pool_order_ = arena.allocate<uint32_t>(depth * max_vertices);
  pool_colour_ = arena.allocate<uint32_t>(depth * max_vertices);
  u_ = arena.allocate<uint64_t>(words_max_);
  q_ = arena.allocate<uint64_t>(words_max_);
  current_ = arena.allocate<uint32_t>(depth);
  best_ = arena.allocate<uint32_t>(depth);
  if (arena.counting()) return Status::Ok;
  if (!frames_ || !pool_words_ || !pool_order_ || !pool_colour_ || !u_ || !q_ || !current_ || !best_)
    return Status::BufferTooSmall;
  for (size_t d = 0; d < depth; ++d) {
    frames_[d].cand = pool_words_ + d * words_max_;
    frames_[d].order = pool_order_ + d * max_vertices;
    frames_[d].colour = pool_colour_ + d * max_vertices;
  }
  bound_ = true;
  return Status::Ok;
}

// Greedy sequential colouring of the candidate set (BBMC): colour classes are independent sets, so a
// vertex with colour k bounds the clique size reachable through it (and the vertices before it) by k.
uint32_t MaxCliqueSolver::colour_sort(const ConsistencyGraph& g, const uint64_t* cand, uint32_t* order,
                                      uint32_t* colour) {
  const uint32_t w = g.words();
  for (uint32_t i = 0; i < w; ++i) u_[i] = cand[i];
  uint32_t count = 0, k = 0;
  bool any = true;
  while (any) {
    any = false;
    ++k;
    for (uint32_t i = 0; i < w; ++i) q_[i] = u_[i];
    for (uint32_t wi = 0; wi < w; ++wi) {
      while (q_[wi]) {
        const uint32_t v = wi * 64 + static_cast<uint32_t>(lowest_bit(q_[wi]));
        any = true;
        u_[wi] &= ~(uint64_t(1) << (v & 63));
        q_[wi] &= ~(uint64_t(1) << (v & 63));
        const uint64_t* nb = g.row(v);
        for (uint32_t x = wi; x < w; ++x) q_[x] &= ~nb[x];
        order[count] = v;
        colour[count] = k;
        ++count;
      }
    }
  }
  return count;
}

Status MaxCliqueSolver::solve(const ConsistencyGraph& g, uint64_t budget, FixedVector<uint32_t>& clique,
                              CliqueStats* stats, const uint64_t* allowed) {
  clique.clear();
  CliqueStats st;
  if (!bound_) return Status::NotInitialized;
  const uint32_t n = g.size();
  if (n > max_vertices_) return Status::CapacityExceeded;
  if (n == 0) {
    if (stats) *stats = st;
    return Status::Ok;
  }
  uint32_t best_size = greedy_clique(g, allowed);
  st.greedy_size = best_size;
  const bool exhausted = branch_and_bound(g, budget, allowed, &best_size, &st);
  // Ascending output.
  for (uint32_t i = 1; i < best_size; ++i)
    for (uint32_t j = i; j > 0 && best_[j - 1] > best_[j]; --j) {
      const uint32_t t = best_[j];
      best_[j] = best_[j - 1];
      best_[j - 1] = t;
    }
  for (uint32_t i = 0; i < best_size; ++i)
    if (!clique.push_back(best_[i])) return Status::CapacityExceeded;
  if (stats) *stats = st;
  return exhausted ? Status::BudgetExhausted : Status::Ok;
}

// Every vertex of the graph, within `allowed` when given.
void MaxCliqueSolver::fill_candidates(const ConsistencyGraph& g, const uint64_t* allowed, uint64_t* cand) const {
  const uint32_t n = g.size(), w = g.words();
  for (uint32_t i = 0; i < w; ++i) cand[i] = 0;
  for (uint32_t v = 0; v < n; ++v) cand[v >> 6] |= uint64_t(1) << (v & 63);
  if (allowed)
    for (uint32_t i = 0; i < w; ++i) cand[i] &= allowed[i];
}

// Greedy start: repeatedly take the candidate with the most neighbours among the candidates (into
// best_; frame 0's candidate words are the scratch). Returns its size.
uint32_t MaxCliqueSolver::greedy_clique(const ConsistencyGraph& g, const uint64_t* allowed) {
  const uint32_t n = g.size(), w = g.words();
  uint32_t best_size = 0;
  uint64_t* cand = frames_[0].cand;
  fill_candidates(g, allowed, cand);
  for (;;) {
    int best_v = -1, best_deg = -1;
    for (uint32_t v = 0; v < n; ++v) {
      if (!((cand[v >> 6] >> (v & 63)) & 1u)) continue;
      int deg = 0;
      for (uint32_t x = 0; x < w; ++x) deg += __builtin_popcountll(cand[x] & g.row(v)[x]);
      if (deg > best_deg) {
        best_deg = deg;
        best_v = static_cast<int>(v);
      }
    }
    if (best_v < 0 || best_size >= kMaxCliqueDepth) break;
    best_[best_size++] = static_cast<uint32_t>(best_v);
    const uint64_t* nb = g.row(static_cast<uint32_t>(best_v));
    for (uint32_t x = 0; x < w; ++x) cand[x] &= nb[x];
  }
  return best_size;
}

// Branch and bound, iterative. Frame d holds the candidates after choosing current_[0..d); a frame's
// vertices are tried in reverse colour order, and a branch whose colour bound cannot beat *best_size
// ends. A larger clique replaces best_. True when the node budget ran out first.
bool MaxCliqueSolver::branch_and_bound(const ConsistencyGraph& g, uint64_t budget, const uint64_t* allowed,
                                       uint32_t* best_size_io, CliqueStats* st) {
  const uint32_t w = g.words();
  uint32_t best_size = *best_size_io;
  uint32_t depth = 0;
  Frame* f = &frames_[0];
  fill_candidates(g, allowed, f->cand);
  const uint32_t max_depth = max_vertices_ < kMaxCliqueDepth ? max_vertices_ : kMaxCliqueDepth;
  f->count = colour_sort(g, f->cand, f->order, f->colour);
  f->pos = f->count;
  st->nodes = 1;
  bool exhausted = false;
  while (true) {
    f = &frames_[depth];
    if (f->pos == 0 || depth + f->colour[f->pos - 1] <= best_size) {
      if (depth == 0) break;
      --depth;  // backtrack
      continue;
    }
    const uint32_t v = f->order[--f->pos];
    f->cand[v >> 6] &= ~(uint64_t(1) << (v & 63));  // v handled in this frame
    current_[depth] = v;
    Frame* next = &frames_[depth + 1];
    const uint64_t* nb = g.row(v);
    bool empty = true;
    for (uint32_t x = 0; x < w; ++x) {
      next->cand[x] = f->cand[x] & nb[x];
      empty = empty && next->cand[x] == 0;
    }
    if (empty || depth + 1 >= max_depth) {  // a leaf, or the depth bound
      if (depth + 1 > best_size) {
        best_size = depth + 1;
        for (uint32_t k = 0; k < best_size; ++k) best_[k] = current_[k];
      }
      continue;
    }
    if (st->nodes >= budget) {
      exhausted = true;
      break;
    }
    ++st->nodes;
    next->count = colour_sort(g, next->cand, next->order, next->colour);
    next->pos = next->count;
    ++depth;
  }
  *best_size_io = best_size;
  return exhausted;
}

}  // namespace gsf
