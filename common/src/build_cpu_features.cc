// Compiled with the build's own flags (unlike cpu_check.cc): the predefined macros here say which
// instruction-set extensions the compiler was allowed to use for the rest of svbtdf. Data only,
// so that reading it runs no instruction the CPU might lack.

#include "build_cpu_features.h"

namespace svbtdf::common::internal {

extern const unsigned kBuildCpuFeatures = 0u
#ifdef __SSE4_1__
    | kSse41
#endif
#ifdef __SSE4_2__
    | kSse42
#endif
#ifdef __POPCNT__
    | kPopcnt
#endif
#ifdef __AVX__
    | kAvx
#endif
#ifdef __AVX2__
    | kAvx2
#endif
#ifdef __FMA__
    | kFma
#endif
#ifdef __BMI__
    | kBmi
#endif
#ifdef __BMI2__
    | kBmi2
#endif
#ifdef __AVX512F__
    | kAvx512f
#endif
#ifdef __AVX512BW__
    | kAvx512bw
#endif
#ifdef __AVX512DQ__
    | kAvx512dq
#endif
#ifdef __AVX512VL__
    | kAvx512vl
#endif
#ifdef __AVX512CD__
    | kAvx512cd
#endif
#ifdef __AVX512VBMI__
    | kAvx512vbmi
#endif
#ifdef __AVX512IFMA__
    | kAvx512ifma
#endif
    ;

}  // namespace svbtdf::common::internal
