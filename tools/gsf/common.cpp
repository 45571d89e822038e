#include <cstdio>
#include <fstream>

#include "commands.h"

namespace gsf::cli {

Status read_map_file(const std::string& path, MapFile* out, std::string* error) {
  const Status s = out->file.open(path);
  out->bytes = out->file.size();
  if (s != Status::Ok) *error = "cannot open map file '" + path + "'";
  return s;
}

bool write_file(const std::string& path, const void* data, size_t bytes, std::string* error) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f || !f.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes))) {
    *error = "cannot write '" + path + "'";
    return false;
  }
  return true;
}

bool wants_help(int argc, char** argv) {
  for (int i = 2; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") return true;
  return false;
}

int usage_error(const std::string& command, const std::string& message) {
  std::fprintf(stderr, "gsf %s: error: %s\n(see 'gsf %s --help')\n", command.c_str(), message.c_str(), command.c_str());
  return 2;
}

}  // namespace gsf::cli
