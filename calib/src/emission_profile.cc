#include "svbtdf/calib/emission_profile.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/json.h"

namespace svbtdf::calib {
namespace {

constexpr double kMaxExponent = 50.0;
constexpr double kMaxStepDeg = 30.0;
constexpr double kMaxTableValue = 10.0;

double Radians(double degrees) { return degrees * std::numbers::pi / 180.0; }

void Require(bool ok, const std::string& source, const std::string& problem) {
  if (!ok) common::ThrowFormatError(source, problem, "re-run 'svbtdf calibrate-emission' on the diffuser session");
}

}  // namespace

double EmissionProfile::operator()(double cos_theta) const {
  cos_theta = std::clamp(cos_theta, 0.0, 1.0);
  if (kind == "lambertian") return cos_theta;
  if (kind == "lcd") return std::pow(cos_theta, exponent);
  if (kind == "measured") return AtDegrees(std::acos(cos_theta) * 180.0 / std::numbers::pi);
  return 1.0;
}

double EmissionProfile::AtDegrees(double theta_deg) const {
  theta_deg = std::clamp(theta_deg, 0.0, 90.0);
  if (kind != "measured") return (*this)(std::cos(Radians(theta_deg)));
  const double last_deg = step_deg * static_cast<double>(table.size() - 1);
  if (theta_deg >= last_deg) {
    // Beyond the angles the diffuser reached: the measured cos^n, continuous at the last node.
    const double ratio = std::max(0.0, std::cos(Radians(theta_deg))) / std::cos(Radians(last_deg));
    return table.back() * std::pow(ratio, exponent);
  }
  // Linear in ln P between nodes: exact for an exponential fall-off, and never negative.
  const double x = theta_deg / step_deg;
  const size_t k = std::min(static_cast<size_t>(x), table.size() - 2);
  const double f = x - static_cast<double>(k);
  return std::exp((1.0 - f) * std::log(table[k]) + f * std::log(table[k + 1]));
}

void PutEmissionProfile(const EmissionProfile& profile, nlohmann::json* monitor) {
  (*monitor)["emission"] = profile.kind;
  (*monitor)["emission_exponent"] = profile.exponent;
  if (profile.kind == "measured") {
    (*monitor)["emission_profile"] = {{"step_deg", profile.step_deg},
                                      {"table", profile.table},
                                      {"covered_deg", {profile.covered_min_deg, profile.covered_max_deg}}};
  } else {
    monitor->erase("emission_profile");
  }
}

EmissionProfile EmissionProfileFromJson(const nlohmann::json& monitor, const std::string& source) {
  EmissionProfile p;
  try {
    p.kind = monitor.value("emission", std::string("isotropic"));
    p.exponent = monitor.value("emission_exponent", 0.0);
    if (p.kind == "measured") {
      const nlohmann::json& m = monitor.at("emission_profile");
      p.step_deg = m.at("step_deg").get<double>();
      p.table = m.at("table").get<std::vector<double>>();
      p.covered_min_deg = m.at("covered_deg").at(0).get<double>();
      p.covered_max_deg = m.at("covered_deg").at(1).get<double>();
    }
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(source, std::string("has a malformed monitor emission profile: ") + e.what());
  }
  if (p.kind != "isotropic" && p.kind != "lambertian" && p.kind != "lcd" && p.kind != "measured") {
    common::ThrowFormatError(source, "has an unknown monitor.emission '" + p.kind + "'",
                             "use isotropic, lambertian, lcd or measured (docs/calibration-format.md)");
  }
  Require(std::isfinite(p.exponent) && p.exponent >= 0.0 && p.exponent <= kMaxExponent, source,
          "has emission_exponent " + std::to_string(p.exponent) + "; it must be in [0, 50]");
  if (p.kind != "measured") return p;
  Require(std::isfinite(p.step_deg) && p.step_deg > 0.0 && p.step_deg <= kMaxStepDeg, source,
          "has emission_profile.step_deg " + std::to_string(p.step_deg) + "; it must be in (0, 30] degrees");
  Require(p.table.size() >= 2, source, "has an emission_profile.table of fewer than 2 values");
  Require(p.step_deg * static_cast<double>(p.table.size() - 1) < 90.0, source,
          "has an emission_profile.table reaching 90 degrees or beyond");
  for (size_t k = 0; k < p.table.size(); ++k) {
    Require(std::isfinite(p.table[k]) && p.table[k] > 0.0 && p.table[k] <= kMaxTableValue, source,
            "has emission_profile.table[" + std::to_string(k) + "] = " + std::to_string(p.table[k]) +
                "; every value must be in (0, 10]");
  }
  Require(std::abs(p.table.front() - 1.0) < 1e-9, source, "has an emission_profile.table that does not start at 1");
  Require(std::isfinite(p.covered_min_deg) && std::isfinite(p.covered_max_deg) && p.covered_min_deg >= 0.0 &&
              p.covered_min_deg <= p.covered_max_deg && p.covered_max_deg < 90.0,
          source, "has emission_profile.covered_deg outside 0 <= from <= to < 90");
  return p;
}

void WriteEmissionProfileFile(const std::filesystem::path& path, const EmissionProfile& profile,
                              const EmissionFitReport& report, const nlohmann::json& provenance) {
  nlohmann::json monitor = nlohmann::json::object();
  PutEmissionProfile(profile, &monitor);
  const nlohmann::json out = {
      {"format", "svbtdf-emission-profile"},
      {"version", kEmissionProfileFormatVersion},
      {"monitor", monitor},
      {"fit",
       {{"observations", report.observations},
        {"texels", report.texels},
        {"residual_rms", report.residual_rms},
        {"table_std", report.table_std},
        {"table_observations", report.table_observations},
        {"cos_power_residual_rms", report.cos_power_residual_rms}}},
      {"provenance", provenance},
  };
  common::WriteTextAtomically(path, out.dump(2) + "\n", /*overwrite=*/true);
}

EmissionProfile ReadEmissionProfileFile(const std::filesystem::path& path) {
  const std::string source = path.string();
  const nlohmann::json json = common::ReadJsonFile(path);
  if (!json.is_object() || json.value("format", std::string()) != "svbtdf-emission-profile") {
    common::ThrowFormatError(source, "is not an svbtdf emission profile (format key)",
                             "give the file 'svbtdf calibrate-emission --out' wrote");
  }
  const nlohmann::json version = json.value("version", nlohmann::json());
  if (common::IntegerIfFits<int>(version) != kEmissionProfileFormatVersion) {
    common::ThrowFormatError(source, "has emission profile version " + version.dump() + "; this svbtdf reads version " +
                                         std::to_string(kEmissionProfileFormatVersion));
  }
  if (!json.contains("monitor") || !json.at("monitor").is_object()) {
    common::ThrowFormatError(source, "has no monitor object");
  }
  EmissionProfile profile = EmissionProfileFromJson(json.at("monitor"), source);
  if (profile.kind != "measured") {
    common::ThrowFormatError(source, "holds a '" + profile.kind + "' profile, not a measured one");
  }
  return profile;
}

}  // namespace svbtdf::calib
