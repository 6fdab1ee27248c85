# Helpers shared by the module folders so that every library is built the same way.

# svbtdf_add_library(NAME <module> SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates svbtdf_<module> with alias svbtdf::<module>; headers live in <module>/include.
function(svbtdf_add_library)
  cmake_parse_arguments(ARG "" "NAME" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  set(target svbtdf_${ARG_NAME})
  add_library(${target} ${ARG_SOURCES})
  add_library(svbtdf::${ARG_NAME} ALIAS ${target})
  target_include_directories(${target} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  svbtdf_set_warnings(${target})
  svbtdf_report_fuzz_coverage(${target})
  svbtdf_precompile_headers(${target})
endfunction()

function(svbtdf_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wno-unused-parameter)
  if(SVBTDF_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# In the fuzzing build (SVBTDF_FUZZ) the libraries report their coverage to libFuzzer, so that a
# harness learns from every branch of the reader it calls, not only from its own few lines. Test
# programs are left uninstrumented: no fuzzer runs their code, and the instrumentation costs
# compile time.
function(svbtdf_report_fuzz_coverage target)
  if(SVBTDF_FUZZ)
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link)
  endif()
endfunction()

# The headers most of svbtdf's files include (counted with grep): with SVBTDF_PRECOMPILE_HEADERS
# each target parses them once instead of once a file. Only the checked build turns it on, where
# every file is compiled afresh: a test file spent about 3 s of its 13 in these headers.
set(SVBTDF_PRECOMPILED_HEADERS
  <algorithm> <array> <cmath> <cstdint> <cstdio> <cstring> <filesystem> <fstream> <functional>
  <limits> <map> <memory> <optional> <random> <sstream> <string> <utility> <vector>
  <Eigen/Dense> <nlohmann/json.hpp>)

# svbtdf_precompile_headers(<target> [<extra header> ...])
function(svbtdf_precompile_headers target)
  if(NOT SVBTDF_PRECOMPILE_HEADERS)
    return()
  endif()
  # The precompiled headers need their libraries' include paths, whether the target uses them or not.
  target_link_libraries(${target} PRIVATE Eigen3::Eigen nlohmann_json::nlohmann_json)
  target_precompile_headers(${target} PRIVATE ${SVBTDF_PRECOMPILED_HEADERS} ${ARGN})
endfunction()
