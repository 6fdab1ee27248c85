// Fuzzes a capture plan (docs/capture.md, "The capture plan") and expands the plans it accepts
// into their captures, as `acquire` does before it drives the rig.
#include <string>

#include "fuzz_support.h"
#include "svbtdf/acquire/capture_plan.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  svbtdf::fuzz::ExpectOnlySvbtdfErrors([&] {
    const svbtdf::acquire::CapturePlan plan = svbtdf::acquire::ParseCapturePlan(text, "plan.json");
    (void)svbtdf::acquire::PlanKeys(svbtdf::acquire::ExpandPlan(plan));
    (void)svbtdf::acquire::CapturePlanToJson(plan);
  });
  return 0;
}
