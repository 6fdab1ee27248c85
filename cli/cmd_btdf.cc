// svbtdf btdf eval: evaluates the dual-microfacet BTDF for one pair of directions.
// Useful to check a material by hand, to compare against other implementations, and as the
// command-line contract of the model (docs/model.md).

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "svbtdf/common/error.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/ndf_factory.h"

namespace svbtdf::cli {
namespace {

struct BtdfEvalOptions {
  std::string ndf = "ggx";
  double roughness = 0.2;
  double roughness_y = 0.2;
  bool anisotropic = false;  // --roughness-y given
  double eta = 1.5;
  double alpha = 0.5;
  std::string shadowing = "none";
  double shadowing_roughness = -1.0;
  std::vector<double> wi, wo;
  std::vector<double> k_s = {1.0, 1.0, 1.0};
  std::vector<double> rho_d = {0.0, 0.0, 0.0};
  bool json = false;
};

model::Vec3 ParseDirection(const std::vector<double>& xyz, const std::string& flag) {
  const model::Vec3 v(xyz.at(0), xyz.at(1), xyz.at(2));
  if (!v.allFinite() || v.norm() == 0.0) {
    common::ThrowInvalidInput(flag, "must be a non-zero finite vector X Y Z");
  }
  return v.normalized();
}

void ValidateDirections(const model::Vec3& wi, const model::Vec3& wo) {
  if (wi.z() * wo.z() > 0) {
    common::ThrowInvalidInput("--wi/--wo", "both directions are on the same side of the sample",
                      "a BTDF needs --wi toward the light below the sample (z < 0) and --wo toward "
                      "the camera above it (z > 0)");
  }
  if (!(wi.z() < 0)) {
    common::ThrowInvalidInput("--wi", "must point toward the light, below the sample (z < 0)",
                      "directions point away from the surface; z is the normal toward the camera");
  }
  if (!(wo.z() > 0)) {
    common::ThrowInvalidInput("--wo", "must point toward the camera, above the sample (z > 0)",
                      "directions point away from the surface; z is the normal toward the camera");
  }
}

void RequireRoughness(const char* flag, double value) {
  if (!(value > 0) || !std::isfinite(value)) {
    common::ThrowInvalidInput(flag, "must be a finite number > 0 (the GGX/Beckmann alpha), got " + std::to_string(value));
  }
}

model::SmithShadowing MakeShadowing(const BtdfEvalOptions& options) {
  if (options.shadowing == "none") {
    if (options.shadowing_roughness >= 0) {
      common::ThrowInvalidInput("--shadowing-roughness", "given, but --shadowing is none",
                        "add --shadowing smith");
    }
    return model::SmithShadowing::None();
  }
  if (options.shadowing_roughness < 0) {
    common::ThrowInvalidInput("--shadowing-roughness", "is required with --shadowing smith",
                      "the paper starts at 0.2");
  }
  return model::SmithShadowing::Ggx(options.shadowing_roughness);
}

nlohmann::json ToJson(const model::Vec3& v) { return {v.x(), v.y(), v.z()}; }

void RunBtdfEval(const BtdfEvalOptions& options) {
  const model::Vec3 wi = ParseDirection(options.wi, "--wi");
  const model::Vec3 wo = ParseDirection(options.wo, "--wo");
  ValidateDirections(wi, wo);
  if (!(options.eta > 1.0) || !std::isfinite(options.eta)) {
    common::ThrowInvalidInput("--eta", "must be > 1 (eta = n_slab / n_air), got " + std::to_string(options.eta));
  }
  if (!(options.alpha >= 0.0 && options.alpha <= 1.0)) {
    common::ThrowInvalidInput("--alpha", "the blend weight must lie in [0, 1], got " + std::to_string(options.alpha));
  }
  RequireRoughness("--roughness", options.roughness);
  if (options.anisotropic) RequireRoughness("--roughness-y", options.roughness_y);
  model::AnalyticNdfParams ndf_params;
  ndf_params.alpha_x = options.roughness;
  ndf_params.alpha_y = options.anisotropic ? options.roughness_y : options.roughness;
  const std::unique_ptr<model::Ndf> ndf = model::MakeAnalyticNdf(options.ndf, ndf_params);

  model::DualMicrofacetParams params;
  params.eta = options.eta;
  params.alpha = options.alpha;
  params.shadowing = MakeShadowing(options);
  for (int c = 0; c < 3; ++c) {
    params.k_s[c] = options.k_s[c];
    params.rho_d[c] = options.rho_d[c];
  }
  const model::DualMicrofacetModel btdf(params.eta, params.shadowing);
  const model::VirtualConfiguration entry = btdf.RoughEntry(wi, wo);
  const model::VirtualConfiguration exit = btdf.RoughExit(wi, wo);
  const double rho_T = entry.valid ? entry.factor * ndf->D(entry.h) : 0.0;
  const double rho_B = exit.valid ? exit.factor * ndf->D(exit.h) : 0.0;
  const double rho = model::LogBlend(rho_T, rho_B, params.alpha);
  const model::Rgb rgb = model::EvaluateMaterial(*ndf, params, wi, wo);

  if (!options.json) {
    std::printf("rho_T = %.9g\nrho_B = %.9g\nrho   = %.9g   (alpha = %g)\nR_rgb = %.9g %.9g %.9g\n",
                rho_T, rho_B, rho, params.alpha, rgb[0], rgb[1], rgb[2]);
    return;
  }
  nlohmann::json out;
  out["rho_T"] = rho_T;
  out["rho_B"] = rho_B;
  out["rho"] = rho;
  out["rgb"] = {rgb[0], rgb[1], rgb[2]};
  out["wi"] = ToJson(wi);
  out["wo"] = ToJson(wo);
  out["h_T"] = entry.valid ? ToJson(entry.h) : nlohmann::json(nullptr);
  out["h_B"] = exit.valid ? ToJson(exit.h) : nlohmann::json(nullptr);
  out["eta"] = params.eta;
  out["alpha"] = params.alpha;
  out["ndf"] = {{"name", ndf->name()}, {"alpha_x", ndf_params.alpha_x}, {"alpha_y", ndf_params.alpha_y}};
  out["shadowing"] = params.shadowing.enabled()
                         ? nlohmann::json{{"model", "smith-ggx"}, {"roughness", params.shadowing.roughness()}}
                         : nlohmann::json{{"model", "none"}};
  out["k_s"] = options.k_s;
  out["rho_d"] = options.rho_d;
  std::cout << out.dump(2) << "\n";
}

}  // namespace

void AddBtdfCommand(CLI::App& app) {
  CLI::App* btdf = app.add_subcommand("btdf", "Evaluate the dual-microfacet BTDF model");
  btdf->require_subcommand(1);
  auto options = std::make_shared<BtdfEvalOptions>();
  CLI::App* eval = btdf->add_subcommand(
      "eval", "rho_T, rho_B and their log-space blend rho for one light and view direction");
  eval->add_option("--ndf", options->ndf, "normal distribution: ggx, beckmann, ellipsoid, vmf")
      ->capture_default_str();
  eval->add_option("--roughness", options->roughness, "NDF roughness (the GGX/Beckmann alpha, x axis)")
      ->capture_default_str();
  eval->add_option("--roughness-y", options->roughness_y, "y-axis roughness for an anisotropic NDF");
  eval->add_option("--eta", options->eta, "relative index of refraction n_slab / n_air (> 1)")
      ->capture_default_str();
  eval->add_option("--alpha", options->alpha, "blend weight of the rough-entry term, in [0, 1]")
      ->capture_default_str();
  eval->add_option("--shadowing", options->shadowing, "none or smith")
      ->check(CLI::IsMember({"none", "smith"}))
      ->capture_default_str();
  eval->add_option("--shadowing-roughness", options->shadowing_roughness,
                   "Smith (GGX) shadowing roughness alpha_b, with --shadowing smith");
  eval->add_option("--wi", options->wi, "direction toward the light, X Y Z with Z < 0")
      ->expected(3)
      ->required();
  eval->add_option("--wo", options->wo, "direction toward the camera, X Y Z with Z > 0")
      ->expected(3)
      ->required();
  eval->add_option("--ks", options->k_s, "RGB transmission scale k_s")->expected(3);
  eval->add_option("--rho-d", options->rho_d, "RGB diffuse transmission rho_d")->expected(3);
  eval->add_flag("--json", options->json, "print one JSON object");
  eval->callback([options, eval] {
    options->anisotropic = eval->count("--roughness-y") > 0;
    RunBtdfEval(*options);
  });
}

}  // namespace svbtdf::cli
