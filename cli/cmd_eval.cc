// svbtdf eval: the fitted material's BTDF R(x, i, o) at one texel for one pair of directions.

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "svbtdf/common/error.h"
#include "svbtdf/fit/material.h"
#include "svbtdf/model/internal_reflection.h"

namespace svbtdf::cli {
namespace {

struct EvalOptions {
  std::string material;
  std::vector<int> texel;
  std::vector<double> wi, wo;
  bool json = false;
};

model::Vec3 Direction(const std::vector<double>& xyz, const char* flag, bool toward_light) {
  const model::Vec3 v(xyz.at(0), xyz.at(1), xyz.at(2));
  if (!v.allFinite() || v.norm() == 0.0) common::ThrowInvalidInput(flag, "must be a non-zero finite vector X Y Z");
  if (toward_light ? !(v.z() < 0) : !(v.z() > 0)) {
    common::ThrowInvalidInput(flag, toward_light ? "must point toward the light, below the sample (z < 0)"
                                         : "must point toward the camera, above the sample (z > 0)");
  }
  return v.normalized();
}

// The terms behind R, for the reader: rho_T, rho_B and alpha of a dual-microfacet texel, or the
// lobe of a baseline texel, the two interfaces of a slab texel. R itself always comes from
// TexelBtdf::Evaluate.
nlohmann::json ModelTerms(const fit::TexelBtdf& texel, const model::Vec3& wi, const model::Vec3& wo) {
  const model::DualMicrofacetParams& p = texel.params();
  if (const auto& slab = texel.slab()) {
    const auto side = [](const fit::SlabSide& s) {
      return nlohmann::json{{"alpha_x", s.alpha_x}, {"alpha_y", s.alpha_y}, {"azimuth", s.azimuth}, {"roughness", s.Roughness()}};
    };
    return {{"slab_entry", side(slab->entry)},
            {"slab_exit", side(slab->exit)},
            {"slab_internal_reflection", slab->internal_reflection},
            {"slab_longer_paths", slab->longer_paths},
            {"rho", fit::SlabShape(*slab, p.eta, wi, wo)}};
  }
  if (const auto& lobe = texel.baseline()) {
    return {{"baseline_alpha_x", lobe->alpha_x},
            {"baseline_alpha_y", lobe->alpha_y},
            {"baseline_azimuth", lobe->azimuth},
            {"rho", fit::BaselineShape(*lobe, p.eta, wi, wo)}};
  }
  const model::DualMicrofacetModel btdf(p.eta, p.shadowing);
  const double rho_T = btdf.RhoT(texel.ndf(), wi, wo), rho_B = btdf.RhoB(texel.ndf(), wi, wo);
  nlohmann::json terms = {{"rho_T", rho_T},
                          {"rho_B", rho_B},
                          {"rho", model::LogBlend(rho_T, rho_B, p.alpha)},
                          {"alpha", p.alpha},
                          {"shadowing_roughness", p.shadowing.roughness()}};
  // Material format 4: rho = the blend + the light reflected inside the slab (R = k_s rho + rho_d).
  if (p.internal_reflection) {
    const double internal = model::InternalReflection(p.eta).Blend(texel.ndf(), p.alpha, wi, wo);
    terms["internal_reflection"] = internal;
    terms["rho"] = terms["rho"].get<double>() + internal;
  }
  return terms;
}

void PrintSummary(const model::Rgb& value, const nlohmann::json& terms) {
  std::printf("R = %.9g %.9g %.9g   ", value[0], value[1], value[2]);
  if (terms.contains("baseline_alpha_x")) {
    std::printf("(walter-ggx: alpha_x %.4f, alpha_y %.4f, azimuth %.3f)\n", terms["baseline_alpha_x"].get<double>(),
                terms["baseline_alpha_y"].get<double>(), terms["baseline_azimuth"].get<double>());
  } else if (terms.contains("slab_entry")) {
    const auto side = [&](const char* key) {
      const nlohmann::json& s = terms[key];
      return std::to_string(s["alpha_x"].get<double>()).substr(0, 6) + " x " + std::to_string(s["alpha_y"].get<double>()).substr(0, 6) +
             " at " + std::to_string(std::lround(s["azimuth"].get<double>() * 180 / model::kPi)) + " deg";
    };
    std::printf("(slab: entry %s, exit %s, internal reflection %.3f, longer paths %.3f, rho %.6g)\n",
                side("slab_entry").c_str(), side("slab_exit").c_str(), terms["slab_internal_reflection"].get<double>(),
                terms["slab_longer_paths"].get<double>(), terms["rho"].get<double>());
  } else {
    std::printf("(rho_T %.6g, rho_B %.6g, alpha %.3f", terms["rho_T"].get<double>(), terms["rho_B"].get<double>(),
                terms["alpha"].get<double>());
    if (terms.contains("internal_reflection")) std::printf(", internal reflection %.6g", terms["internal_reflection"].get<double>());
    std::printf(")\n");
  }
}

void RunEval(const EvalOptions& options) {
  const model::Vec3 wi = Direction(options.wi, "--wi", true), wo = Direction(options.wo, "--wo", false);
  const fit::Material material = fit::ReadMaterial(options.material);
  const fit::MaterialEvaluator evaluator(material);
  const int x = options.texel.at(0), y = options.texel.at(1);
  const fit::TexelBtdf texel = evaluator.Texel(x, y);
  const model::Rgb value = texel.Evaluate(wi, wo);
  const nlohmann::json terms = ModelTerms(texel, wi, wo);
  if (!options.json) return PrintSummary(value, terms);
  const model::DualMicrofacetParams& p = texel.params();
  nlohmann::json out = {
      {"texel", {x, y}},
      {"btdf", fit::MaterialModelName(texel.model())},
      {"rgb", {value[0], value[1], value[2]}},
      {"eta", p.eta},
      {"k_s", p.k_s},
      {"rho_d", p.rho_d},
      {"wi", {wi.x(), wi.y(), wi.z()}},
      {"wo", {wo.x(), wo.y(), wo.z()}},
  };
  out.update(terms);
  std::cout << out.dump(2) << "\n";
}

}  // namespace

void AddEvalCommand(CLI::App& app) {
  auto options = std::make_shared<EvalOptions>();
  CLI::App* eval = app.add_subcommand("eval", "Evaluate a fitted material at one texel for one light and view direction");
  eval->add_option("material", options->material, "material folder (docs/material-format.md)")->required();
  eval->add_option("--texel", options->texel, "texel column and row, U V")->expected(2)->required();
  eval->add_option("--wi", options->wi, "direction toward the light, X Y Z with Z < 0")->expected(3)->required();
  eval->add_option("--wo", options->wo, "direction toward the camera, X Y Z with Z > 0")->expected(3)->required();
  eval->add_flag("--json", options->json, "print one JSON object");
  eval->callback([options] { RunEval(*options); });
}

}  // namespace svbtdf::cli
