#include <cstdio>
#include <fstream>

#include "commands.h"

namespace gsf::cli {

Status read_map_file(const std::string& path, MapFile* out, std::string* error) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) {
    *error = "cannot open map file '" + path + "'";
    return Status::IoError;
  }
  const std::streamoff size = f.tellg();
  if (size < 0) {
    *error = "cannot read map file '" + path + "'";
    return Status::IoError;
  }
  out->bytes = static_cast<size_t>(size);
  out->words.assign(out->bytes / 8 + 1, 0);
  f.seekg(0);
  if (!f.read(reinterpret_cast<char*>(out->words.data()), size)) {
    *error = "short read on map file '" + path + "'";
    return Status::IoError;
  }
  return Status::Ok;
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
