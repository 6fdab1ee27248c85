#pragma once
// The named simulation presets of `svbtdf simulate` (docs/simulator.md, "Presets").

#include <string>
#include <vector>

#include "svbtdf/simulate/montecarlo_truth.h"
#include "svbtdf/simulate/rig.h"

namespace svbtdf::simulate {

struct SimulationPreset {
  std::string name;
  std::string description;
  RigConfig rig;
  std::string pattern;          // TruthMaterial::FromPattern
  double eta = 1.5;
  // Exposure bracket as multiples of the base exposure, which is chosen so that the brightest
  // dot image (the dot nearest to straight-through) peaks at `peak_fill` of the full well.
  std::vector<double> bracket = {1.0, 16.0};
  double peak_fill = 0.9;
  // `--truth montecarlo`: how finely each slab material's slices are traced, and the view grid.
  MonteCarloPrecision montecarlo;
  int view_nodes_per_axis = 3;
};

std::vector<std::string> PresetNames();
// Throws svbtdf::Error(kInvalidInput) naming the known presets for an unknown name.
SimulationPreset MakePreset(const std::string& name);

}  // namespace svbtdf::simulate
