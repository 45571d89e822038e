// gsf_test_worlds DIR: builds the simulator's tiny worlds (tiny_world.h) once and writes them to DIR for
// the test executables that share them. ctest runs it as the test_worlds fixture (tests/CMakeLists.txt).
#include <chrono>
#include <cstdio>
#include <string>

#include "tiny_world.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: gsf_test_worlds DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  struct Named {
    const char* name;
    gsf::sim::SimConfig sim;
    const gsf::ClassTable* classes;
  };
  const Named worlds[] = {{"tiny", gsf::sim::SimConfig::tiny(), nullptr},
                          {"tiny_nuscenes", gsf::sim::SimConfig::tiny(), &gsf_test::nuscenes_table()},
                          {"tiny_lattice", gsf::sim::SimConfig::tiny_lattice(), nullptr}};
  for (const Named& w : worlds) {
    const auto t0 = std::chrono::steady_clock::now();
    const gsf_test::TinyWorld* world = gsf_test::build_sim_world(w.sim, w.classes);
    const std::string path = dir + "/" + w.name + ".world";
    const bool ok = gsf_test::save_world(*world, path);
    delete world;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s: %s (%.1f s)\n", path.c_str(), ok ? "written" : "FAILED", s);
    if (!ok) return 1;
  }
  return 0;
}
