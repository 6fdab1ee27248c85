// The CPU check of native builds (common/cpu_features.h): what it says the build was compiled for
// agrees with the compiler's own macros in this file (compiled with the same flags), and what it
// says the CPU has agrees with the kernel's /proc/cpuinfo. (That the machine that built the tests
// can run them needs no test: the check would have stopped this program before main.)

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "svbtdf/common/cpu_features.h"

namespace svbtdf::common {
namespace {

std::map<std::string, CpuFeature> ByName() {
  std::map<std::string, CpuFeature> features;
  for (const CpuFeature& f : CpuFeatures()) features.emplace(f.name, f);
  return features;
}

#if defined(__x86_64__)

TEST(CpuFeatures, SaysWhatTheCompilerWasAllowedToUse) {
  const std::map<std::string, CpuFeature> f = ByName();
  ASSERT_EQ(f.size(), 15u);
  const auto built = [&](const char* name) { return f.at(name).built_for; };
#ifdef __AVX2__
  EXPECT_TRUE(built("avx2"));
#else
  EXPECT_FALSE(built("avx2"));
#endif
#ifdef __FMA__
  EXPECT_TRUE(built("fma"));
#else
  EXPECT_FALSE(built("fma"));
#endif
#ifdef __AVX512F__
  EXPECT_TRUE(built("avx512f"));
#else
  EXPECT_FALSE(built("avx512f"));
#endif
#ifdef __SSE4_2__
  EXPECT_TRUE(built("sse4.2"));
#else
  EXPECT_FALSE(built("sse4.2"));
#endif
}

TEST(CpuFeatures, AgreesWithTheKernelAboutThisCpu) {
  std::ifstream cpuinfo("/proc/cpuinfo");
  if (!cpuinfo) GTEST_SKIP() << "no /proc/cpuinfo";
  std::set<std::string> flags;
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("flags", 0) != 0) continue;
    std::istringstream words(line.substr(line.find(':') + 1));
    for (std::string w; words >> w;) flags.insert(w);
    break;
  }
  ASSERT_FALSE(flags.empty());
  // The kernel's spelling where it differs from GCC's.
  const std::map<std::string, std::string> kernel_name = {{"sse4.1", "sse4_1"}, {"sse4.2", "sse4_2"}, {"bmi", "bmi1"}};
  for (const CpuFeature& f : CpuFeatures()) {
    const auto renamed = kernel_name.find(f.name);
    const std::string name = renamed == kernel_name.end() ? f.name : renamed->second;
    EXPECT_EQ(f.supported, flags.count(name) == 1) << f.name;
  }
}

#endif

TEST(CpuFeatures, MissingAreThoseBuiltForButNotSupported) {
  const std::vector<CpuFeature> features = {
      {"avx2", true, true}, {"avx512f", true, false}, {"fma", false, false}, {"avx512bw", true, false}};
  EXPECT_EQ(MissingCpuFeatures(features), (std::vector<std::string>{"avx512f", "avx512bw"}));
}

}  // namespace
}  // namespace svbtdf::common
