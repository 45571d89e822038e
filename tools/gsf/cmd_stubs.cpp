// Subcommands whose pipeline stages have not landed yet report that clearly instead of pretending.
#include <cstdio>

#include "commands.h"

namespace gsf::cli {

static int not_yet(const char* name) {
  std::fprintf(stderr, "gsf %s: not available in this build yet\n", name);
  return 1;
}
int cmd_simulate(int, char**) { return not_yet("simulate"); }
int cmd_build_map(int, char**) { return not_yet("build-map"); }
int cmd_localize(int, char**) { return not_yet("localize"); }
int cmd_evaluate(int, char**) { return not_yet("evaluate"); }
int cmd_demo(int, char**) { return not_yet("demo"); }

}  // namespace gsf::cli
