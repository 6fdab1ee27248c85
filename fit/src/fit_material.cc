#include "svbtdf/fit/fit_material.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <random>

#include "svbtdf/common/durable_log.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/common/statistics.h"
#include "svbtdf/fit/refine_texels.h"

namespace svbtdf::fit {
namespace fs = std::filesystem;
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void CheckOptions(const FitMaterialOptions& options, double eta) {
  if (!(eta > 1.0) || !std::isfinite(eta)) {
    common::ThrowInvalidInput("--eta", "must be > 1 (the sample's relative index of refraction), got " + std::to_string(eta),
                      "give --eta; the session does not record it");
  }
  if (!(options.representative_fraction > 0.0)) {
    common::ThrowInvalidInput("--representatives", "must be a fraction in (0, 1] or 'all'");
  }
  if (!(options.holdout >= 0.0 && options.holdout < 0.9)) {
    common::ThrowInvalidInput("--holdout", "must be in [0, 0.9), got " + std::to_string(options.holdout));
  }
  const int r = options.ndf_resolution;
  if (r < 4 || r > 128) common::ThrowInvalidInput("--ndf-resolution", "must be in [4, 128], got " + std::to_string(r));
  const double correlation = options.standard_errors.correlation_radius;
  if (!(correlation >= 0.0) || !std::isfinite(correlation)) {
    common::ThrowInvalidInput("standard_errors.correlation_radius", "must be >= 0 dot spacings, got " + std::to_string(correlation));
  }
  const int pool = options.standard_errors.model_error_pool_radius;
  if (pool < 0) common::ThrowInvalidInput("--model-error-pool", "must be >= 0 texels, got " + std::to_string(pool));
  if (options.slab_anisotropic && options.model != MaterialModel::kSlab) {
    common::ThrowInvalidInput("--anisotropic-sides", "is an option of --model slab");
  }
  if (options.internal_reflection && options.model != MaterialModel::kDualMicrofacet) {
    common::ThrowInvalidInput("--internal-reflection", std::string("is a term of the dual-microfacet model; --model ") +
                                                           (options.model == MaterialModel::kSlab ? "slab" : "ggx") + " has none");
  }
  // The term integrates D over every facet normal, the grazing ones too, where a free horizon
  // leaves D to the smoothness prior (and k_s scales it up): on the Monte Carlo truth that made
  // the held-out error worse (27.3% -> 29.1%, docs/validation.md) instead of better, and still
  // does with the escaping texels fitted fixed (6.06% -> 6.90%).
  if (options.internal_reflection && options.free_horizon) {
    common::ThrowInvalidInput("--internal-reflection", "needs the NDF's horizon fixed: the term reaches D at grazing normals, "
                              "which a free horizon leaves unconstrained", "add --fixed-horizon");
  }
}

// The texels the fit can use (mask = 1).
std::vector<int64_t> ValidTexels(const SliceStore& store) {
  std::vector<int64_t> valid;
  const common::FloatImage& mask = store.mask();
  for (int64_t t = 0; t < static_cast<int64_t>(mask.pixels.size()); ++t) {
    if (mask.pixels[t] > 0) valid.push_back(t);
  }
  if (valid.empty()) {
    common::ThrowInvalidInput(store.folder().string(), "has no texel with enough valid samples to fit",
                      "check the session's exposures and the calibration");
  }
  return valid;
}

// Clusters the valid texels and extends the result to every texel: a masked-out texel takes the
// weights of the nearest valid texel on the grid (it has no data of its own).
Clustering ClusterTexels(const SliceStore& store, const std::vector<int64_t>& valid, const FitMaterialOptions& options) {
  SliceSource source;
  source.num_texels = static_cast<int64_t>(valid.size());
  source.dimension = store.light_grid().num_cells();
  source.read = [&](int64_t k, float* out) { store.ReadSlice(valid[k], out); };
  ClusteringOptions clustering_options;
  clustering_options.representative_fraction = std::min(1.0, options.representative_fraction);
  clustering_options.seed = options.seed;
  clustering_options.threads = options.threads;
  clustering_options.progress = options.progress;
  const Clustering on_valid = ClusterSlices(source, clustering_options);

  const int64_t texels = store.geometry().num_texels();
  const int width = store.info().texels_x;
  Clustering all;
  for (int64_t r : on_valid.representatives) all.representatives.push_back(valid[r]);
  all.explained_variance = on_valid.explained_variance;
  all.cluster.assign(texels, 0);
  all.weights.assign(texels, {});
  const std::vector<int64_t> nearest_valid = NearestSources(width, store.info().texels_y, valid);
  for (int64_t t = 0; t < texels; ++t) {
    const int64_t k = nearest_valid[t];  // t itself when t is valid
    all.cluster[t] = on_valid.cluster[k];
    all.weights[t] = on_valid.weights[k];
  }
  return all;
}

nlohmann::json FitToJson(const TexelFitResult& f) {
  return {{"alpha", f.alpha},       {"shadowing_roughness", f.shadowing_roughness},
          {"k_s", f.k_s},           {"k_s_rgb", f.k_s_rgb},
          {"ln_d", f.ln_d},         {"log_rms", f.log_rms},
          {"relative_rmse", f.relative_rmse}, {"alternations", f.alternations},
          {"samples_used", f.samples_used},
          {"shadowing_roughness_se", f.shadowing_roughness_se},
          {"ndf_width", f.ndf_width},
          {"ndf_width_se", f.ndf_width_se},
          {"alpha_profile_se", f.alpha_profile_se},
          {"k_s_profile_relative_se", f.k_s_profile_relative_se},
          {"horizon_fixed_instead", f.horizon_fixed_instead}};
}

nlohmann::json BaselineToJson(const BaselineFitResult& f) {
  return {{"alpha_x", f.alpha_x}, {"alpha_y", f.alpha_y}, {"azimuth", f.azimuth},
          {"k_s", f.k_s},         {"k_s_rgb", f.k_s_rgb}, {"log_rms", f.log_rms},
          {"relative_rmse", f.relative_rmse}, {"converged", f.converged}};
}

// The fields the parametric fits (baseline, slab) share: the scale and how well the fit matches.
template <typename ParametricFit>
void ReadScaleAndResiduals(const nlohmann::json& j, ParametricFit* f) {
  f->k_s = j.at("k_s").get<double>();
  f->k_s_rgb = j.at("k_s_rgb").get<std::array<double, 3>>();
  f->log_rms = j.at("log_rms").get<double>();
  f->relative_rmse = j.at("relative_rmse").get<double>();
  f->converged = j.at("converged").get<bool>();
}

BaselineFitResult BaselineFromJson(const nlohmann::json& j) {
  BaselineFitResult f;
  f.alpha_x = j.at("alpha_x").get<double>();
  f.alpha_y = j.at("alpha_y").get<double>();
  f.azimuth = j.at("azimuth").get<double>();
  ReadScaleAndResiduals(j, &f);
  return f;
}

TexelFitResult FitFromJson(const nlohmann::json& j, const std::string& source) {
  TexelFitResult f;
  f.alpha = j.at("alpha").get<double>();
  f.shadowing_roughness = j.at("shadowing_roughness").get<double>();
  f.k_s = j.at("k_s").get<double>();
  f.k_s_rgb = j.at("k_s_rgb").get<std::array<double, 3>>();
  f.ln_d = j.at("ln_d").get<std::vector<double>>();
  f.log_rms = j.at("log_rms").get<double>();
  f.relative_rmse = j.at("relative_rmse").get<double>();
  f.alternations = common::IntegerAt(j, "alternations", source);
  f.samples_used = common::IntegerAt(j, "samples_used", source);
  // Journals written before the standard errors existed resume without them.
  f.shadowing_roughness_se = j.value("shadowing_roughness_se", -1.0);
  f.ndf_width = j.value("ndf_width", -1.0);
  f.ndf_width_se = j.value("ndf_width_se", -1.0);
  f.alpha_profile_se = j.value("alpha_profile_se", -1.0);
  f.k_s_profile_relative_se = j.value("k_s_profile_relative_se", -1.0);
  f.horizon_fixed_instead = j.value("horizon_fixed_instead", false);
  return f;
}

// The append-only journal of finished representative fits. Its first line records what the fit
// is (store, options, representatives), so that a rerun with anything different is refused
// rather than mixing fits.
class Checkpoint {
 public:
  Checkpoint(const fs::path& path, const nlohmann::json& identity) {
    if (path.empty()) return;
    log_ = common::DurableLog::Open(path, common::IsJsonObjectLine);
    const std::vector<std::string>& lines = log_->lines();
    if (lines.empty()) {
      log_->Append(nlohmann::json{{"fit", identity}}.dump());
      return;
    }
    nlohmann::json header;
    try {
      header = common::ParseJson(lines[0], path.string());
    } catch (const common::Error&) {  // an unreadable header is a checkpoint of other inputs
    }
    if (header != nlohmann::json{{"fit", identity}}) {
      common::ThrowInvalidInput(path.string(), "is the checkpoint of a fit with other inputs or options",
                        "re-run with the same options, or delete it to start over");
    }
    for (size_t n = 1; n < lines.size(); ++n) {
      try {  // a damaged line does not count: that representative is fitted again
        const nlohmann::json entry = common::ParseJson(lines[n], path.string());
        done_[common::IntegerAt(entry, "representative", path.string())] = entry.at("result");
      } catch (const std::exception&) {  // common::Error or a json type error
      }
    }
  }

  const std::map<int, nlohmann::json>& done() const { return done_; }

  void Record(int representative, const nlohmann::json& result) {
    if (!log_) return;
    const std::string line = nlohmann::json{{"representative", representative}, {"result", result}}.dump();
    std::lock_guard<std::mutex> lock(mutex_);
    log_->Append(line);
  }

 private:
  std::optional<common::DurableLog> log_;  // none when no checkpoint was asked for
  std::map<int, nlohmann::json> done_;
  std::mutex mutex_;
};

// Workspaces handed to whichever thread fits next (the symbolic analysis is reused).
class WorkspacePool {
 public:
  FitWorkspace Take() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (free_.empty()) return FitWorkspace();
    FitWorkspace w = std::move(free_.back());
    free_.pop_back();
    return w;
  }
  void Give(FitWorkspace w) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(w));
  }

 private:
  std::mutex mutex_;
  std::vector<FitWorkspace> free_;
};

// The texel indices of the representatives whose own fit failed (for the provenance).
std::vector<int64_t> FailedTexels(const std::vector<int64_t>& reps, const std::vector<uint8_t>& failed) {
  std::vector<int64_t> texels;
  for (size_t r = 0; r < reps.size(); ++r) {
    if (failed[r]) texels.push_back(reps[r]);
  }
  return texels;
}

nlohmann::json SlabToJson(const SlabFitResult& f) {
  const auto side = [](const SlabSide& s) { return nlohmann::json{s.alpha_x, s.alpha_y, s.azimuth}; };
  return {{"entry", side(f.interfaces.entry)}, {"exit", side(f.interfaces.exit)},
          {"internal_reflection", f.interfaces.internal_reflection}, {"longer_paths", f.interfaces.longer_paths},
          {"entry_roughness_se", f.entry_roughness_se},     {"exit_roughness_se", f.exit_roughness_se},
          {"roughness_correlation", f.roughness_correlation}, {"k_s", f.k_s},
          {"k_s_rgb", f.k_s_rgb},                           {"log_rms", f.log_rms},
          {"relative_rmse", f.relative_rmse},               {"converged", f.converged}};
}

SlabFitResult SlabFromJson(const nlohmann::json& j) {
  SlabFitResult f;
  const auto side = [&](const char* key) {
    const std::array<double, 3> v = j.at(key).get<std::array<double, 3>>();
    return SlabSide{v[0], v[1], v[2]};
  };
  f.interfaces.entry = side("entry");
  f.interfaces.exit = side("exit");
  f.interfaces.internal_reflection = j.at("internal_reflection").get<double>();
  f.interfaces.longer_paths = j.at("longer_paths").get<double>();
  f.entry_roughness_se = j.at("entry_roughness_se").get<double>();
  f.exit_roughness_se = j.at("exit_roughness_se").get<double>();
  f.roughness_correlation = j.at("roughness_correlation").get<double>();
  ReadScaleAndResiduals(j, &f);
  return f;
}

// The fits of all representatives with one model, as the journal records them.
class RepresentativeFits {
 public:
  RepresentativeFits(double eta, const FitMaterialOptions& options, size_t count)
      : model_(options.model), dual_(eta, DualOptions(options)), baseline_(eta), slab_(eta, SlabOptions(options)),
        results_(count) {}

  // Fits one slice (svbtdf::Error kNumerical when it cannot be fitted).
  nlohmann::json Fit(const TexelSlice& slice, FitWorkspace* workspace) const {
    if (model_ == MaterialModel::kWalterGgx) return BaselineToJson(baseline_.Fit(slice));
    if (model_ == MaterialModel::kSlab) return SlabToJson(slab_.Fit(slice));
    return FitToJson(dual_.Fit(slice, workspace));
  }
  void Set(size_t r, nlohmann::json result) { results_[r] = std::move(result); }
  double RelativeRmse(size_t r) const { return results_[r].at("relative_rmse").get<double>(); }
  // Dual-microfacet fits whose free horizon left k_s implausible, fitted fixed instead (a failed
  // representative has no fit until it borrows one).
  int64_t HorizonFixedInstead() const {
    return std::count_if(results_.begin(), results_.end(),
                         [](const nlohmann::json& j) { return j.is_object() && j.value("horizon_fixed_instead", false); });
  }

  // A failed representative takes its lender's fit; its residual says it is not its own (-1).
  void Lend(const std::vector<int>& lender) {
    for (size_t r = 0; r < results_.size(); ++r) {
      if (lender[r] == static_cast<int>(r)) continue;
      results_[r] = results_[lender[r]];
      results_[r]["relative_rmse"] = -1.0;
    }
  }

  Material Assemble(const SliceStore& store, double eta, int ndf_resolution, const Clustering& clustering) const {
    const int width = store.info().texels_x, height = store.info().texels_y;
    if (model_ == MaterialModel::kWalterGgx) {
      std::vector<BaselineFitResult> fits;
      for (const nlohmann::json& j : results_) fits.push_back(BaselineFromJson(j));
      return AssembleBaselineMaterial(width, height, eta, ndf_resolution, clustering, fits, store.rho_d());
    }
    if (model_ == MaterialModel::kSlab) {
      std::vector<SlabFitResult> fits;
      for (const nlohmann::json& j : results_) fits.push_back(SlabFromJson(j));
      return AssembleSlabMaterial(width, height, eta, ndf_resolution, clustering, fits, store.rho_d());
    }
    std::vector<TexelFitResult> fits;
    for (const nlohmann::json& j : results_) fits.push_back(FitFromJson(j, "a representative fit in the checkpoint"));
    return AssembleMaterial(width, height, eta, ndf_resolution, clustering, fits, store.rho_d());
  }

 private:
  static SlabFitOptions SlabOptions(const FitMaterialOptions& options) {
    SlabFitOptions slab;
    slab.anisotropic = options.slab_anisotropic;
    return slab;
  }

  static TexelFitOptions DualOptions(const FitMaterialOptions& options) {
    TexelFitOptions fit_options;
    fit_options.ndf_resolution = options.ndf_resolution;
    fit_options.free_horizon = options.free_horizon;
    fit_options.secant_alternations = options.secant_alternations;
    fit_options.profile_uncertainty = options.uncertainty;
    fit_options.standard_errors = options.standard_errors;
    fit_options.internal_reflection = options.internal_reflection;
    return fit_options;
  }

  MaterialModel model_;
  TexelFitter dual_;
  BaselineFitter baseline_;
  SlabFitter slab_;
  std::vector<nlohmann::json> results_;
};

// Fits the representatives the checkpoint does not hold yet, in parallel (one workspace per
// worker), recording each in the checkpoint. Returns which failed (kNumerical).
std::vector<uint8_t> FitPending(const SliceStore& store, const std::vector<int64_t>& reps, const std::vector<bool>& use_dot,
                                const FitMaterialOptions& options, Checkpoint* checkpoint, RepresentativeFits* fits) {
  std::vector<int> todo;
  for (size_t r = 0; r < reps.size(); ++r) {
    const auto done = checkpoint->done().find(static_cast<int>(r));
    if (done != checkpoint->done().end()) {
      fits->Set(r, done->second);
    } else {
      todo.push_back(static_cast<int>(r));
    }
  }
  std::unique_ptr<common::ProgressBar> progress;
  if (options.progress) {
    progress = std::make_unique<common::ProgressBar>("fit", static_cast<int64_t>(reps.size()), "texels");
    progress->SkipAlreadyDone(static_cast<int64_t>(reps.size() - todo.size()));
  }
  // Bytes, not vector<bool>: workers write neighbouring flags at the same time.
  std::vector<uint8_t> failed(reps.size(), 0);
  WorkspacePool workspaces;
  common::ParallelFor(static_cast<int64_t>(todo.size()), options.threads, 1, [&](int64_t a, int64_t b) {
    FitWorkspace workspace = workspaces.Take();
    for (int64_t k = a; k < b; ++k) {
      common::ThrowIfInterrupted("fitting");
      const int r = todo[k];
      try {
        nlohmann::json result = fits->Fit(store.MakeTexelSlice(reps[r], use_dot), &workspace);
        checkpoint->Record(r, result);
        fits->Set(r, std::move(result));
      } catch (const common::Error& e) {
        if (e.kind() != common::ErrorKind::kNumerical) throw;
        failed[r] = 1;  // not journalled: a rerun tries it again
      }
      if (progress) progress->Advance();
    }
    workspaces.Give(std::move(workspace));
  });
  if (progress) progress->Finish();
  return failed;
}

// Every sample of a texel was divided by the texel's white exitance, measured from one flat white
// frame: that frame's noise (SliceStoreInfo::white_exitance_noise, relative) scales the texel's
// whole slice, k_s and rho_d by the same factor, and no statistic over the dots sees it. It adds
// in quadrature to their standard errors and to the predicted relative error of the BTDF (whose
// luminance, the channels' mean, has sqrt(sum of the channels' variances) / 3 of it).
void AddWhiteExitanceNoise(const std::array<double, 3>& noise, Material* material) {
  const double luminance_noise = std::sqrt(model::Square(noise[0]) + model::Square(noise[1]) + model::Square(noise[2])) / 3.0;
  const auto add = [](float* se, double relative, double value) {
    if (*se >= 0) *se = static_cast<float>(std::hypot(static_cast<double>(*se), relative * value));
  };
  for (int y = 0; y < material->height; ++y) {
    for (int x = 0; x < material->width; ++x) {
      for (int c = 0; c < 3; ++c) {
        if (!material->k_s_se.pixels.empty()) add(&material->k_s_se.at(x, y, c), noise[c], material->k_s.at(x, y, c));
        if (!material->rho_d_se.pixels.empty()) add(&material->rho_d_se.at(x, y, c), noise[c], material->rho_d.at(x, y, c));
      }
      if (!material->prediction_se.pixels.empty()) add(&material->prediction_se.at(x, y), luminance_noise, 1.0);
    }
  }
}

}  // namespace

std::vector<int> HeldOutDots(int num_dots, double holdout, uint64_t seed) {
  std::vector<int> dots(num_dots);
  std::iota(dots.begin(), dots.end(), 0);
  std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ull);
  std::shuffle(dots.begin(), dots.end(), rng);
  dots.resize(static_cast<size_t>(std::lround(holdout * num_dots)));
  std::sort(dots.begin(), dots.end());
  return dots;
}

Material FitMaterial(const SliceStore& store, const FitMaterialOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  // 0 means "the session's"; anything else given (NaN or a negative number too) is checked as given.
  const double eta = options.eta != 0.0 ? options.eta : store.info().eta;
  CheckOptions(options, eta);
  const int num_dots = store.info().num_dots;
  const std::vector<int> held_out = HeldOutDots(num_dots, options.holdout, options.seed);
  std::vector<bool> use_dot(num_dots, true);
  for (int q : held_out) use_dot[q] = false;

  const std::vector<int64_t> valid = ValidTexels(store);
  const Clustering clustering = ClusterTexels(store, valid, options);
  const std::vector<int64_t>& reps = clustering.representatives;
  const double clustering_seconds = SecondsSince(start);

  nlohmann::json identity = {{"store", fs::absolute(store.folder()).string()},
                             {"model", MaterialModelName(options.model)},
                             {"eta", eta},
                             {"ndf_resolution", options.ndf_resolution},
                             {"holdout", held_out},
                             {"representatives", reps}};
  // Only when set, so that journals written before the option existed still resume.
  if (options.free_horizon) identity["free_horizon"] = true;
  if (options.internal_reflection) identity["internal_reflection"] = true;
  if (options.secant_alternations) identity["secant_alternations"] = true;
  if (options.model == MaterialModel::kSlab && options.slab_anisotropic) identity["slab_anisotropic"] = true;
  // A slab journal of before the longer paths' shape (material version 5) holds another model.
  if (options.model == MaterialModel::kSlab) identity["slab_longer_paths"] = true;
  Checkpoint checkpoint(options.checkpoint, identity);
  RepresentativeFits fits(eta, options, reps.size());
  const size_t resumed = checkpoint.done().size();
  const auto fit_start = std::chrono::steady_clock::now();
  const std::vector<uint8_t> failed = FitPending(store, reps, use_dot, options, &checkpoint, &fits);
  const double fit_seconds = SecondsSince(fit_start);
  const int64_t failures = std::count(failed.begin(), failed.end(), 1);
  if (failures == static_cast<int64_t>(reps.size())) {
    throw common::Error(common::ErrorKind::kNumerical, store.folder().string(), "no representative could be fitted (too few usable samples)");
  }
  std::vector<double> residuals;
  for (size_t r = 0; r < reps.size(); ++r) {
    if (!failed[r]) residuals.push_back(fits.RelativeRmse(r));
  }
  // Counted before lending: a failed representative that borrows a refitted fit was not refitted itself.
  const int64_t horizon_fixed_instead = fits.HorizonFixedInstead();
  fits.Lend(LendersOfFits(reps, store.info().texels_x, store.info().texels_y, failed));

  Material material = fits.Assemble(store, eta, options.ndf_resolution, clustering);
  material.internal_reflection = options.internal_reflection;
  material.width_m = store.geometry().width_m;
  material.height_m = store.geometry().height_m;
  RefineStatistics refined;
  const auto refine_start = std::chrono::steady_clock::now();
  if (options.refine_texels) {
    RefineOptions refine_options;
    refine_options.threads = options.threads;
    refine_options.progress = options.progress;
    refine_options.uncertainty = options.uncertainty;
    refine_options.standard_errors = options.standard_errors;
    refined = RefineTexels(store, use_dot, valid, refine_options, &material);
  }
  const double refine_seconds = SecondsSince(refine_start);
  if (options.uncertainty) {
    AddWhiteExitanceNoise(store.info().white_exitance_noise, &material);
  } else {
    for (common::FloatImage* map : {&material.alpha_se, &material.k_s_se, &material.rho_d_se, &material.shadowing_roughness_se,
                                    &material.ndf_width, &material.ndf_width_se, &material.prediction_se}) {
      *map = common::FloatImage();
    }
  }
  const double seconds = SecondsSince(start);
  material.provenance = {
      {"processed", fs::absolute(store.folder()).string()},
      {"session", common::StringOr(store.info().provenance, "session")},
      {"settings",
       {{"model", MaterialModelName(options.model)},
        {"eta", eta},
        {"representative_fraction", options.representative_fraction},
        {"ndf_resolution", options.ndf_resolution},
        {"refine_texels", options.refine_texels},
        {"free_horizon", options.free_horizon},
        {"secant_alternations", options.secant_alternations},
        {"uncertainty", options.uncertainty},
        {"internal_reflection", options.internal_reflection},
        {"slab_anisotropic", options.model == MaterialModel::kSlab && options.slab_anisotropic},
        {"seed", options.seed}}},
      {"statistics",
       {{"texels", store.geometry().num_texels()},
        {"valid_texels", valid.size()},
        {"representatives", reps.size()},
        {"failed_fits", failures},
        {"failed_representatives", FailedTexels(reps, failed)},
        {"resumed_fits", resumed},
        {"horizon_fixed_instead", horizon_fixed_instead},
        // The store's flat white noise, in the standard errors of k_s and rho_d (docs/fitting.md).
        {"white_exitance_noise", store.info().white_exitance_noise},
        {"median_relative_rmse", common::Median(residuals)},
        {"refined_representatives", refined.representatives},
        // The interpolated texels' residuals on their own samples, before and after refinement.
        {"refined_texels", refined.texels},
        {"median_relative_rmse_blended", refined.texels > 0 ? refined.median_rmse_blended : -1.0},
        {"median_relative_rmse_refined", refined.texels > 0 ? refined.median_rmse_refined : -1.0},
        {"pca_explained_variance", clustering.explained_variance},
        // Wall times: the whole fit and its three stages (docs/benchmarks.md, "scaling.py").
        {"seconds", seconds},
        {"clustering_seconds", clustering_seconds},  // reading the store and clustering its slices
        {"fit_seconds", fit_seconds},                // fitting the representatives
        {"refine_seconds", refine_seconds},          // refining every texel
        // Wall time per representative fitted in this run (all threads together).
        {"seconds_per_fit", reps.size() > resumed ? fit_seconds / (reps.size() - resumed) : 0.0},
        {"threads", common::ThreadCount(options.threads)}}},
  };
  // `svbtdf compare` measures the held-out error on exactly these dots.
  if (!held_out.empty()) {
    material.provenance["holdout"] = {{"fraction", options.holdout}, {"seed", options.seed}, {"dots", held_out}};
  }
  return material;
}

namespace {

// One line of the distance transform: for every q in [0, n), the p minimising (q - p)^2 + f[p]
// over the p with a finite f[p] (the lower envelope of parabolas rooted at them), or -1 when
// every f is infinite. `v` and `z` are scratch of n and n + 1.
void NearestOnLine(const std::vector<double>& f, std::vector<int>* nearest, std::vector<int>& v, std::vector<double>& z) {
  const int n = static_cast<int>(f.size());
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  int k = -1;  // the envelope's last parabola
  for (int q = 0; q < n; ++q) {
    if (f[q] == kInfinity) continue;
    double s = -kInfinity;  // where parabola q starts to lie below the envelope
    while (k >= 0) {
      s = ((f[q] + double(q) * q) - (f[v[k]] + double(v[k]) * v[k])) / (2.0 * (q - v[k]));
      if (s > z[k]) break;
      --k;
    }
    ++k;
    v[k] = q;
    z[k] = k == 0 ? -kInfinity : s;
    z[k + 1] = kInfinity;
  }
  nearest->assign(n, -1);
  if (k < 0) return;
  for (int q = 0, j = 0; q < n; ++q) {
    while (z[j + 1] < q) ++j;
    (*nearest)[q] = v[j];
  }
}

}  // namespace

std::vector<int64_t> NearestSources(int width, int height, const std::vector<int64_t>& sources) {
  const int64_t texels = static_cast<int64_t>(width) * height;
  if (width <= 0 || height <= 0) common::ThrowInvalidInput("nearest texels", "the grid is empty");
  if (sources.empty()) common::ThrowInvalidInput("nearest texels", "no source texel");
  std::vector<int64_t> source_at(texels, -1);
  for (size_t k = 0; k < sources.size(); ++k) {
    if (sources[k] < 0 || sources[k] >= texels) {
      common::ThrowInvalidInput("nearest texels", "source texel " + std::to_string(sources[k]) + " is outside the grid");
    }
    source_at[sources[k]] = static_cast<int64_t>(k);
  }
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  const int longest = std::max(width, height);
  std::vector<int> v(longest), line_nearest;
  std::vector<double> z(longest + 1), f;
  // Pass 1, down each column: the nearest source row in the texel's own column.
  std::vector<int> nearest_row(texels);
  f.resize(height);
  for (int x = 0; x < width; ++x) {
    for (int y = 0; y < height; ++y) f[y] = source_at[int64_t{y} * width + x] >= 0 ? 0.0 : kInfinity;
    NearestOnLine(f, &line_nearest, v, z);
    for (int y = 0; y < height; ++y) nearest_row[int64_t{y} * width + x] = line_nearest[y];
  }
  // Pass 2, along each row: the column whose nearest source (from pass 1) is nearest overall.
  std::vector<int64_t> nearest(texels);
  f.resize(width);
  for (int y = 0; y < height; ++y) {
    const int64_t row = int64_t{y} * width;
    for (int x = 0; x < width; ++x) {
      const int r = nearest_row[row + x];
      f[x] = r < 0 ? kInfinity : double(r - y) * (r - y);
    }
    NearestOnLine(f, &line_nearest, v, z);
    for (int x = 0; x < width; ++x) {
      const int column = line_nearest[x];
      nearest[row + x] = source_at[int64_t{nearest_row[row + column]} * width + column];
    }
  }
  return nearest;
}

std::vector<int> LendersOfFits(const std::vector<int64_t>& representatives, int width, int height,
                               const std::vector<uint8_t>& failed) {
  if (failed.size() != representatives.size()) {
    common::ThrowInvalidInput("representatives", "have " + std::to_string(failed.size()) + " outcomes for " +
                                                     std::to_string(representatives.size()) + " fits");
  }
  std::vector<int> lender(representatives.size());
  std::vector<int64_t> succeeded_texels;
  std::vector<int> succeeded;
  for (size_t r = 0; r < representatives.size(); ++r) {
    if (representatives[r] < 0 || representatives[r] >= int64_t{width} * height) {
      common::ThrowInvalidInput("representatives", "texel " + std::to_string(representatives[r]) + " is outside the grid");
    }
    lender[r] = static_cast<int>(r);
    if (failed[r]) continue;
    succeeded.push_back(static_cast<int>(r));
    succeeded_texels.push_back(representatives[r]);
  }
  if (succeeded.size() == representatives.size()) return lender;
  const std::vector<int64_t> nearest = NearestSources(width, height, succeeded_texels);  // throws for none
  for (size_t r = 0; r < representatives.size(); ++r) {
    if (failed[r]) lender[r] = succeeded[static_cast<size_t>(nearest[representatives[r]])];
  }
  return lender;
}

double ParseRepresentativeFraction(const std::string& text, const std::string& subject) {
  if (text == "all") return 1.0;
  try {
    size_t used = 0;
    const double fraction = std::stod(text, &used);
    if (used == text.size() && fraction > 0 && fraction <= 1) return fraction;
  } catch (const std::exception&) {
  }
  common::ThrowInvalidInput(subject, "must be a fraction in (0, 1] or 'all', got '" + text + "'");
}

}  // namespace svbtdf::fit
