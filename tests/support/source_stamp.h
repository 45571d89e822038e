// Test helper: the sources' stamp (git commit, plus a hash of uncommitted changes), generated at every
// build by tests/support/source_stamp.cmake into the build tree's source_stamp.cpp.
#pragma once

namespace gsf_test {

const char* source_stamp();

}  // namespace gsf_test
