// Proves the "no heap after init" harness itself works: a clean region counts zero, and deliberately
// allocating regions (operator new, malloc, std::vector growth, Eigen dynamic matrices) are caught.
// Must be defined before any Eigen include: in Release NDEBUG disables Eigen's own assert, and we
// want the EIGEN_RUNTIME_NO_MALLOC check to report instead of abort.
#include <stdexcept>
#define EIGEN_RUNTIME_NO_MALLOC
#define eigen_assert(x)                                      \
  do {                                                       \
    if (!(x)) throw std::runtime_error("eigen_assert: " #x); \
  } while (0)

#include <catch2/catch.hpp>

#include <Eigen/Dense>
#include <cstdlib>
#include <vector>

#include "alloc_counter.h"
#include "gsf/detail/arena.h"
#include "gsf/detail/fixed_vector.h"

using gsf_test::AllocationScope;

TEST_CASE("A region without heap use counts zero allocations") {
  alignas(16) static uint8_t buf[4096];
  gsf::Arena arena(buf, sizeof(buf));
  gsf::FixedVector<float> v;
  REQUIRE(v.bind(arena, 64));
  AllocationScope scope;
  for (int i = 0; i < 64; ++i) v.push_back(static_cast<float>(i));
  Eigen::Matrix<float, 8, 8> m = Eigen::Matrix<float, 8, 8>::Identity() * 2.0f;
  Eigen::LLT<Eigen::Matrix<float, 8, 8>> llt(m);
  gsf_test::escape(&llt);
  CHECK(scope.allocations() == 0);
}

TEST_CASE("The counter catches operator new, malloc and container growth") {
  {
    AllocationScope scope;
    int* p = new int(3);
    gsf_test::escape(p);
    delete p;
    CHECK(scope.allocations() == 1);
    CHECK(scope.frees() == 1);
  }
  {
    AllocationScope scope;
    void* p = std::malloc(32);
    gsf_test::escape(p);
    std::free(p);
    CHECK(scope.allocations() == 1);
  }
  {
    AllocationScope scope;
    std::vector<double> v;
    for (int i = 0; i < 100; ++i) v.push_back(i);
    gsf_test::escape(v.data());
    CHECK(scope.allocations() >= 1);
  }
  {
    AllocationScope scope;
    Eigen::MatrixXf big(40, 40);
    big.setZero();
    gsf_test::escape(big.data());
    CHECK(scope.allocations() >= 1);
  }
}

TEST_CASE("EIGEN_RUNTIME_NO_MALLOC: fixed-size math passes, dynamic allocation is refused") {
  Eigen::MatrixXf preallocated(16, 16);  // allocated before the hot region, like init()
  preallocated.setIdentity();
  Eigen::internal::set_is_malloc_allowed(false);
  Eigen::Matrix4f a = Eigen::Matrix4f::Random();
  Eigen::Matrix4f b = a * a.transpose();
  preallocated.topLeftCorner<4, 4>() = b;  // writes into existing storage: fine
  bool caught = false;
  try {
    Eigen::MatrixXf c = preallocated * preallocated;  // temporary needs heap: must be refused
    gsf_test::escape(c.data());
  } catch (const std::runtime_error&) { caught = true; }
  Eigen::internal::set_is_malloc_allowed(true);
  CHECK(caught);
  CHECK(preallocated(0, 0) == Approx(b(0, 0)));
}
