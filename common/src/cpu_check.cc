// Compiled for any x86-64 CPU, whatever the build's flags (common/CMakeLists.txt), so that it can
// run on a CPU that lacks what the rest of svbtdf was compiled for, and say so. The check itself
// (svbtdf_check_cpu) uses no template that other files instantiate too: the linker keeps one copy
// of such code, and it could be a copy compiled for the build's CPU.

#include <cstdio>
#include <cstdlib>

#include "build_cpu_features.h"
#include "svbtdf/common/cpu_features.h"

namespace svbtdf::common {
namespace {

using namespace internal;

struct NamedBit {
  const char* name;  // as GCC's __builtin_cpu_supports and /proc/cpuinfo spell it
  unsigned bit;
};

constexpr NamedBit kFeatures[] = {
    {"sse4.1", kSse41},     {"sse4.2", kSse42},     {"popcnt", kPopcnt},       {"avx", kAvx},
    {"avx2", kAvx2},        {"fma", kFma},          {"bmi", kBmi},             {"bmi2", kBmi2},
    {"avx512f", kAvx512f},  {"avx512bw", kAvx512bw}, {"avx512dq", kAvx512dq}, {"avx512vl", kAvx512vl},
    {"avx512cd", kAvx512cd}, {"avx512vbmi", kAvx512vbmi}, {"avx512ifma", kAvx512ifma},
};

// The extensions the CPU running this has, as bits (all of them where the check cannot ask).
unsigned SupportedBits() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  __builtin_cpu_init();  // the check runs before the constructor that would initialise it
  // __builtin_cpu_supports takes only string literals, hence one line each.
  unsigned bits = 0;
  if (__builtin_cpu_supports("sse4.1")) bits |= kSse41;
  if (__builtin_cpu_supports("sse4.2")) bits |= kSse42;
  if (__builtin_cpu_supports("popcnt")) bits |= kPopcnt;
  if (__builtin_cpu_supports("avx")) bits |= kAvx;
  if (__builtin_cpu_supports("avx2")) bits |= kAvx2;
  if (__builtin_cpu_supports("fma")) bits |= kFma;
  if (__builtin_cpu_supports("bmi")) bits |= kBmi;
  if (__builtin_cpu_supports("bmi2")) bits |= kBmi2;
  if (__builtin_cpu_supports("avx512f")) bits |= kAvx512f;
  if (__builtin_cpu_supports("avx512bw")) bits |= kAvx512bw;
  if (__builtin_cpu_supports("avx512dq")) bits |= kAvx512dq;
  if (__builtin_cpu_supports("avx512vl")) bits |= kAvx512vl;
  if (__builtin_cpu_supports("avx512cd")) bits |= kAvx512cd;
  if (__builtin_cpu_supports("avx512vbmi")) bits |= kAvx512vbmi;
  if (__builtin_cpu_supports("avx512ifma")) bits |= kAvx512ifma;
  return bits;
#else
  return ~0u;
#endif
}

}  // namespace

std::vector<CpuFeature> CpuFeatures() {
  std::vector<CpuFeature> features;
#if defined(__x86_64__)
  const unsigned supported = SupportedBits();
  for (const NamedBit& f : kFeatures) {
    features.push_back({f.name, (kBuildCpuFeatures & f.bit) != 0, (supported & f.bit) != 0});
  }
#endif
  return features;
}

std::vector<std::string> MissingCpuFeatures(const std::vector<CpuFeature>& features) {
  std::vector<std::string> missing;
  for (const CpuFeature& f : features) {
    if (f.built_for && !f.supported) missing.emplace_back(f.name);
  }
  return missing;
}

}  // namespace svbtdf::common

// Runs before the program's other static constructors (priority 101, the first an application may
// use) and so before main. The linker keeps this object in every program that links
// svbtdf_common because that target asks it to (-u svbtdf_check_cpu, common/CMakeLists.txt).
extern "C" __attribute__((constructor(101))) void svbtdf_check_cpu() {
  using namespace svbtdf::common;
  const unsigned missing = internal::kBuildCpuFeatures & ~SupportedBits();
  if (missing == 0) return;
  std::fputs("svbtdf: this build was compiled for another CPU: it uses", stderr);
  const char* separator = " ";
  for (const NamedBit& f : kFeatures) {
    if (missing & f.bit) std::fprintf(stderr, "%s%s", separator, f.name), separator = ", ";
  }
  std::fputs(", which this CPU lacks; rebuild it on this machine, or with cmake -DSVBTDF_NATIVE_ARCH=OFF "
             "for any x86-64 CPU\n",
             stderr);
  std::_Exit(2);
}
