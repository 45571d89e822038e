// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Inlier selection by maximum clique (paper Eq. 6-7): correspondences i, j are consistent when
// | |a_i - a_j| - |b_i - b_j| | <= eps; the largest mutually consistent set is the inlier set.
//
// ConsistencyGraph stores the graph as a bit-adjacency matrix (uint64 words) in the arena.
// MaxCliqueSolver is exact branch and bound with a greedy-colouring upper bound on bitsets (San Segundo's
// BBMC, in the Tomita MCQ family), written iteratively with an explicit stack whose depth is bounded by
// the vertex cap. A node budget bounds the worst case: when it runs out the search stops and returns
// the largest clique found so far (never smaller than the greedy start clique) with
// Status::BudgetExhausted. Among cliques of equal size the first found in the deterministic search
// order wins.
#pragma once
#include <cstdint>

#include "gsf/detail/arena.h"
#include "gsf/detail/fixed_vector.h"
#include "gsf/status.h"

namespace gsf {

class ConsistencyGraph {
 public:
  static size_t required_bytes(uint32_t max_vertices);
  Status bind(Arena& arena, uint32_t max_vertices);
  // a, b: n x 3 (query and map positions of each correspondence). z_weight scales height differences
  // (1: Euclidean 3-D distances; 0: horizontal distances only).
  Status build(const float* a, const float* b, uint32_t n, float eps, float z_weight = 1.0f);
  // Arbitrary graphs (tests, adversarial inputs).
  Status reset(uint32_t n);
  void add_edge(uint32_t i, uint32_t j);
  void remove_edge(uint32_t i, uint32_t j);
  // Removes every edge (i, j) whose bird's-eye pair direction turns by `yaw` (rad) from query to map,
  // within `tolerance` (rad): the edges a clique at that heading is made of. Pairs shorter than
  // min_length (m) on either side carry no usable direction and stay. Returns the edges removed.
  uint32_t remove_edges_at_heading(const float* a, const float* b, double yaw, double tolerance, float min_length);

  uint32_t size() const { return n_; }
  uint32_t words() const { return words_; }
  bool adjacent(uint32_t i, uint32_t j) const { return (row(i)[j >> 6] >> (j & 63)) & 1u; }
  const uint64_t* row(uint32_t i) const { return bits_ + size_t(i) * words_; }
  uint32_t max_vertices() const { return max_vertices_; }

 private:
  uint64_t* bits_ = nullptr;
  uint32_t max_vertices_ = 0;
  uint32_t n_ = 0;
  uint32_t words_ = 0;
};

struct CliqueStats {
  uint64_t nodes = 0;
  uint32_t greedy_size = 0;
};

class MaxCliqueSolver {
 public:
  static size_t required_bytes(uint32_t max_vertices);
  Status bind(Arena& arena, uint32_t max_vertices);
  // Writes the clique's vertex ids (ascending) into `clique`. `allowed` (graph.words() words, or null
  // for all vertices) restricts the search to a vertex subset: the hypothesis stage peels one clique
  // after another without rebuilding the graph. Cliques stop growing at kMaxCliqueDepth vertices (a
  // clique that large is an answer already; the bound keeps the search stack small).
  Status solve(const ConsistencyGraph& graph, uint64_t node_budget, FixedVector<uint32_t>& clique, CliqueStats* stats,
               const uint64_t* allowed = nullptr);
  static constexpr uint32_t kMaxCliqueDepth = 255;

 private:
  struct Frame {
    uint64_t* cand;    // candidate set P (words)
    uint32_t* order;   // vertices of P in colour order
    uint32_t* colour;  // their colour bounds
    uint32_t count;    // entries in order/colour
    uint32_t pos;      // next entry to branch on, counting down
  };
  uint32_t colour_sort(const ConsistencyGraph& g, const uint64_t* cand, uint32_t* order, uint32_t* colour);
  // The steps of solve(): a greedy clique as the first bound, then branch and bound (true when the
  // budget ran out); the best clique is in best_[0, size).
  void fill_candidates(const ConsistencyGraph& g, const uint64_t* allowed, uint64_t* cand) const;
  uint32_t greedy_clique(const ConsistencyGraph& g, const uint64_t* allowed);
  bool branch_and_bound(const ConsistencyGraph& g, uint64_t budget, const uint64_t* allowed, uint32_t* best_size,
                        CliqueStats* st);
  uint32_t max_vertices_ = 0;
  uint32_t words_max_ = 0;
  Frame* frames_ = nullptr;
  uint64_t* pool_words_ = nullptr;
  uint32_t* pool_order_ = nullptr;
  uint32_t* pool_colour_ = nullptr;
  uint64_t* u_ = nullptr;  // colouring scratch
  uint64_t* q_ = nullptr;
  uint32_t* current_ = nullptr;
  uint32_t* best_ = nullptr;
  bool bound_ = false;
};

}  // namespace gsf
