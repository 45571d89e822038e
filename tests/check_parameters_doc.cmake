# ctest parameters_doc: the committed docs/parameters.md is what `gsf params --markdown` writes from the
# parameter list (core/src/parameters.def). Run: cmake -DGSF=path/to/gsf -DDOC=docs/parameters.md -P this
execute_process(COMMAND ${GSF} params --markdown OUTPUT_VARIABLE generated RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "gsf params --markdown failed (${rc})")
endif()
file(READ ${DOC} committed)
if(NOT generated STREQUAL committed)
  message(FATAL_ERROR "docs/parameters.md is not what the parameter list gives: regenerate it with\n"
                      "  build/release/tools/gsf params --markdown > docs/parameters.md")
endif()
message(STATUS "docs/parameters.md matches the parameter list")
