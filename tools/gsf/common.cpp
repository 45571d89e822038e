#include <cstddef>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "commands.h"
#include "gsf/map_format.h"

namespace gsf::cli {

std::string map_load_error(const MapFile& file, Status status) {
  std::string msg = to_string(status);
  if (status == Status::VersionMismatch && file.bytes >= offsetof(MapHeader, header_bytes)) {
    uint32_t version = 0;
    std::memcpy(&version, static_cast<const uint8_t*>(file.data()) + offsetof(MapHeader, version), sizeof(version));
    msg += " (the file is map format version " + std::to_string(version) + ", this build reads version " +
           std::to_string(kMapVersion) + ": rebuild the map with gsf build-map)";
  }
  return msg;
}

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
