// A Localizer initialised on a tiny world's map, with its own workspace: the fixture of the tests that
// call the vehicle modes (test_position_prior, test_tracker, test_localize_next).
#pragma once
#include <catch2/catch.hpp>

#include <cstdint>
#include <vector>

#include "gsf/localizer.h"
#include "tiny_world.h"

namespace gsf_test {

struct ReadyLocalizer {
  std::vector<uint64_t> words;
  gsf::Localizer loc;
  explicit ReadyLocalizer(const TinyWorld& w) : ReadyLocalizer(w, w.config) {}
  ReadyLocalizer(const TinyWorld& w, const gsf::LocalizerConfig& c) : words(gsf::Localizer::required_bytes(c) / 8 + 2) {
    REQUIRE(loc.init(c, w.map, words.data(), words.size() * 8) == gsf::Status::Ok);
  }
};

}  // namespace gsf_test
