#pragma once
// The instruction-set extensions this build was compiled for, and whether the CPU running it has
// them. With SVBTDF_NATIVE_ARCH (the default, CMakeLists.txt) everything is compiled for the build
// machine's CPU (-march=native: AVX2 and AVX-512 where it has them), so a binary copied to an
// older CPU would die of an illegal instruction somewhere in its work. Every program that links
// svbtdf_common checks first, before any other code of its own runs (src/cpu_check.cc), and stops
// with one line naming what is missing instead.

#include <string>
#include <vector>

namespace svbtdf::common {

struct CpuFeature {
  const char* name;     // as GCC's __builtin_cpu_supports and /proc/cpuinfo spell it
  bool built_for;       // the compiler was allowed to use it in this build
  bool supported;       // the CPU running this program has it
};

// Every extension the check knows (x86-64; empty elsewhere).
std::vector<CpuFeature> CpuFeatures();

// The names of the features in `features` built for but not supported.
std::vector<std::string> MissingCpuFeatures(const std::vector<CpuFeature>& features);

}  // namespace svbtdf::common
