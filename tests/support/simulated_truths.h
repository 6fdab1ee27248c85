#pragma once
// Test support: one simulation of the tiny preset per truth kind ("model", "montecarlo"), made in
// process the first time a test asks for it and removed when the test program ends, so that the
// tests of one program share it.

#include <unistd.h>

#include <filesystem>
#include <map>
#include <string>

#include "svbtdf/acquire/simulated_session.h"

namespace svbtdf {

class SimulatedTruths {
 public:
  // OUT/truth of `svbtdf simulate --preset tiny --truth <kind>`.
  static std::filesystem::path TruthFolder(const std::string& kind) {
    static SimulatedTruths truths;
    auto [it, made] = truths.folders_.try_emplace(kind);
    if (made) {
      const std::filesystem::path out = truths.root_ / kind;
      simulate::SimulationOptions options;
      options.preset = "tiny";
      options.truth = kind;
      options.threads = 2;
      options.progress = false;
      it->second = acquire::SimulateSession(out, options).truth;
    }
    return it->second;
  }

 private:
  SimulatedTruths()
      : root_(std::filesystem::temp_directory_path() / ("svbtdf-simulated-truths-" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(root_);
  }
  ~SimulatedTruths() { std::filesystem::remove_all(root_); }

  std::filesystem::path root_;
  std::map<std::string, std::filesystem::path> folders_;
};

}  // namespace svbtdf
