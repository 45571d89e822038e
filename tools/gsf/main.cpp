// gsf: the host command-line tool. Subcommands: simulate, build-map, localize, evaluate, inspect, demo, params.
#include <cstdio>
#include <cstring>
#include <string>

#include "commands.h"

namespace {

struct Command {
  const char* name;
  int (*run)(int, char**);
  const char* summary;
};

const Command kCommands[] = {
    {"simulate", gsf::cli::cmd_simulate, "generate a semantic LiDAR world in the SemanticKITTI layout"},
    {"build-map", gsf::cli::cmd_build_map, "build a map file from a labelled sequence with poses"},
    {"localize", gsf::cli::cmd_localize, "localize one scan or a whole sequence against a map"},
    {"evaluate", gsf::cli::cmd_evaluate, "localize a query sequence with ground truth and report metrics"},
    {"inspect", gsf::cli::cmd_inspect, "print a map's header, counts and memory budget"},
    {"demo", gsf::cli::cmd_demo, "simulate -> build map -> evaluate all modes, on the built-in default"},
    {"params", gsf::cli::cmd_params, "list the localizer's parameters (--markdown: docs/parameters.md)"},
};

void print_help(FILE* f) {
  std::fprintf(f,
               "gsf - one-shot LiDAR global localization with Gaussian semantic fields (Outram-GSF)\n\n"
               "usage: gsf <command> [options]    (gsf <command> --help for its options)\n\ncommands:\n");
  for (const auto& c : kCommands) std::fprintf(f, "  %-10s %s\n", c.name, c.summary);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    print_help(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  for (const auto& c : kCommands)
    if (!std::strcmp(argv[1], c.name)) return c.run(argc, argv);
  std::fprintf(stderr, "gsf: unknown command '%s'\n\n", argv[1]);
  print_help(stderr);
  return 2;
}
