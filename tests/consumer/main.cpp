#include <cstdio>
#include "gsf/localizer.h"
int main() {
  gsf::LocalizerConfig cfg;
  std::printf("%zu %s\n", gsf::Localizer::required_bytes(cfg), gsf::to_string(gsf::Status::Ok));
  return 0;
}
