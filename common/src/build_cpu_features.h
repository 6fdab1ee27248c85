#pragma once
// Shared by build_cpu_features.cc (compiled for the build's CPU) and cpu_check.cc (compiled for
// any x86-64): one bit per instruction-set extension the check knows.

namespace svbtdf::common::internal {

enum CpuFeatureBit : unsigned {
  kSse41 = 1u << 0,
  kSse42 = 1u << 1,
  kPopcnt = 1u << 2,
  kAvx = 1u << 3,
  kAvx2 = 1u << 4,
  kFma = 1u << 5,
  kBmi = 1u << 6,
  kBmi2 = 1u << 7,
  kAvx512f = 1u << 8,
  kAvx512bw = 1u << 9,
  kAvx512dq = 1u << 10,
  kAvx512vl = 1u << 11,
  kAvx512cd = 1u << 12,
  kAvx512vbmi = 1u << 13,
  kAvx512ifma = 1u << 14,
};

// The extensions the rest of svbtdf was compiled for (build_cpu_features.cc).
extern const unsigned kBuildCpuFeatures;

}  // namespace svbtdf::common::internal
