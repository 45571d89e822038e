// The translation unit CMake builds the tests' precompiled header with (tests/CMakeLists.txt,
// gsf_test_pch); it has no code of its own.
