// The gsf CLI's subcommands. Each returns the process exit code: 0 ok, 1 runtime failure, 2 usage error.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "gsf/port/mapped_file.h"
#include "gsf/status.h"

namespace gsf::cli {

int cmd_inspect(int argc, char** argv);
int cmd_simulate(int argc, char** argv);
int cmd_build_map(int argc, char** argv);
int cmd_localize(int argc, char** argv);
int cmd_evaluate(int argc, char** argv);
int cmd_demo(int argc, char** argv);
int cmd_params(int argc, char** argv);

// A map file in 16-byte aligned memory (as load_map requires): memory-mapped read-only where the platform
// allows, else read into a buffer (port/mapped_file.h). load_map then uses it in place.
struct MapFile {
  port::MappedFile file;
  size_t bytes = 0;
  const void* data() const { return file.data(); }
};
Status read_map_file(const std::string& path, MapFile* out, std::string* error);
// Why load_map refused a map file, for a message: the status, and for VersionMismatch the file's format
// version and what to do (rebuild with gsf build-map).
std::string map_load_error(const MapFile& file, Status status);
bool write_file(const std::string& path, const void* data, size_t bytes, std::string* error);

// True if --help/-h is among the arguments (then print usage and exit 0).
bool wants_help(int argc, char** argv);

// Prints "gsf <cmd>: error: msg" plus a hint, returns 2.
int usage_error(const std::string& command, const std::string& message);

}  // namespace gsf::cli
