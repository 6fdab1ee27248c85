#include "svbtdf/simulate/session_writer.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/fiducials.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/session/session.h"
#include "svbtdf/model/ndf_factory.h"
#include "svbtdf/simulate/capture_render.h"
#include "svbtdf/simulate/capture_simulator.h"
#include "svbtdf/simulate/montecarlo_truth.h"
#include "svbtdf/simulate/truth_material.h"
#include "svbtdf/simulate/truth_io.h"

namespace svbtdf {
namespace fs = std::filesystem;
namespace {

// The sink that stores each rendered capture in the session, journalled.
class SessionSink final : public CaptureSink {
 public:
  explicit SessionSink(session::Session* session) : session_(session) {}
  bool Contains(const CaptureId& id) const override { return session_->Contains(id.key.Format()); }
  void Write(const CaptureId& id, const CameraImage& image) override {
    session_->AddImage(id.key.Format(), image, id.exposure_s, 1.0);
  }

 private:
  session::Session* session_;
};

// What the capture knew about its set-up: nominal values a lab would write down.
nlohmann::json NominalRig(const Rig& rig, const SimulationPreset& preset, const CaptureTruth& capture) {
  const RigConfig& c = rig.config();
  nlohmann::json dots = nlohmann::json::array();
  for (const Dot& dot : rig.dots()) dots.push_back({dot.monitor_x, dot.monitor_y});
  nlohmann::json nominal = {
      {"camera", {{"model", "svbtdf simulated camera"},
                  {"width", c.intrinsics.width},
                  {"height", c.intrinsics.height},
                  {"channels", 3},
                  {"bit_depth", c.sensor.bit_depth},
                  {"response", c.sensor.response}}},
      // Zhang views are whole-sensor images, the rest the window around the sample.
      {"board", {{"spec", c.board.Spec()}, {"views", c.board.views}}},
      {"sample_plane_board", {{"spec", c.holder_board.Spec()}}},
      {"monitor", {{"width_px", static_cast<int>(std::lround(c.monitor.width / c.monitor.pixel_pitch))},
                   {"height_px", static_cast<int>(std::lround(c.monitor.height / c.monitor.pixel_pitch))},
                   {"pixel_pitch_m", c.monitor.pixel_pitch},
                   {"gamma", c.monitor.gamma},
                   {"black_level", c.monitor.black_level},
                   {"distance_m", c.monitor.distance},
                   // Which way the screen lies, to the nearest quarter turn, as a lab notes it.
                   {"orientation_deg", NominalOrientationDeg(c.monitor)},
                   {"emission", c.monitor.emission.kind}}},
      {"dots", {{"cols", c.dots.cols}, {"rows", c.dots.rows}, {"radius_px", c.dots.radius_px},
                {"positions_px", dots}, {"fiducials", session::FiducialDots(c.dots.cols, c.dots.rows)}}},
      // The texel grid and eta a lab would choose for processing and fitting (defaults there).
      {"sample", {{"width_m", c.sample.width}, {"height_m", c.sample.height()},
                  {"texels_x", c.sample.texels_x}, {"texels_y", c.sample.texels_y}, {"eta", preset.eta}}},
      {"exposures_s", capture.dot_exposures_s},
      {"simulated", {{"preset", preset.name}, {"seed", capture.seed}, {"truth", capture.truth_kind}}},
  };
  const SensorWindow& window = c.window;
  if (!window.whole_sensor()) {
    nominal["camera"]["sensor"] = {{"width", window.sensor_width}, {"height", window.sensor_height},
                                   {"window_offset", {window.offset_x, window.offset_y}}};
  }
  return nominal;
}

// The ground-truth material as EXR maps plus a manifest (docs/truth-format.md).
void WriteMaterialTruth(const fs::path& folder, const TruthMaterial& material) {
  const int w = material.texels_x(), h = material.texels_y();
  FloatImage ndf(w, h, 5), alpha(w, h, 1), shadowing(w, h, 1), k_s(w, h, 3), rho_d(w, h, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const TruthTexel& t = material.texel(x, y);
      const double ndf_params[5] = {t.ndf.alpha_x, t.ndf.alpha_y, t.ndf.theta_x, t.ndf.theta_y, t.ndf.theta_z};
      for (int c = 0; c < 5; ++c) ndf.at(x, y, c) = static_cast<float>(ndf_params[c]);
      alpha.at(x, y) = static_cast<float>(t.alpha);
      shadowing.at(x, y) = static_cast<float>(t.shadowing_roughness);
      for (int c = 0; c < 3; ++c) {
        k_s.at(x, y, c) = static_cast<float>(t.k_s[c]);
        rho_d.at(x, y, c) = static_cast<float>(t.rho_d[c]);
      }
    }
  }
  WriteFloatImage(folder / "ndf_params.exr", ndf, /*half_precision=*/false, false);
  WriteFloatImage(folder / "alpha.exr", alpha, false, false);
  WriteFloatImage(folder / "shadowing_roughness.exr", shadowing, false, false);
  WriteFloatImage(folder / "k_s.exr", k_s, false, false);
  WriteFloatImage(folder / "rho_d.exr", rho_d, false, false);
  const nlohmann::json manifest = {
      {"format", "svbtdf-truth-material"},
      {"version", kTruthFormatVersion},
      {"eta", material.eta()},
      {"width", w},
      {"height", h},
      {"ndf", {{"kind", "analytic"}, {"name", material.ndf_name()}, {"map", "ndf_params.exr"},
               {"channels", {"alpha_x", "alpha_y", "theta_x", "theta_y", "theta_z"}}}},
      {"maps", {{"alpha", "alpha.exr"}, {"shadowing_roughness", "shadowing_roughness.exr"},
                {"k_s", "k_s.exr"}, {"rho_d", "rho_d.exr"}}},
      {"shadowing", "smith-ggx; 0 = none"},
  };
  WriteTextAtomically(folder / "material.json", manifest.dump(2) + "\n", false);
}

}  // namespace

MaterialTruth ReadMaterialTruth(const fs::path& folder) {
  const fs::path manifest_path = folder / "material.json";
  MaterialTruth truth;
  try {
    const nlohmann::json manifest = nlohmann::json::parse(ReadTextFile(manifest_path));
    if (manifest.at("format") != "svbtdf-truth-material") ThrowFormatError(manifest_path.string(), "is not a truth material");
    if (manifest.at("ndf").at("kind") != "analytic") {
      ThrowFormatError(manifest_path.string(), "is not an analytic truth (see its ndf.kind)");
    }
    truth.eta = manifest.at("eta").get<double>();
    truth.ndf_name = manifest.at("ndf").at("name").get<std::string>();
  } catch (const nlohmann::json::exception& e) {
    ThrowFormatError(manifest_path.string(), std::string("is malformed: ") + e.what());
  }
  const auto read = [&](const char* file, int channels) {
    FloatImage image = ReadFloatImage(folder / file);
    RequireFinite(image, (folder / file).string());
    if (image.channels != channels) ThrowFormatError((folder / file).string(), "has the wrong number of channels");
    return image;
  };
  truth.ndf_params = read("ndf_params.exr", 5);
  truth.alpha = read("alpha.exr", 1);
  truth.shadowing_roughness = read("shadowing_roughness.exr", 1);
  truth.k_s = read("k_s.exr", 3);
  truth.rho_d = read("rho_d.exr", 3);
  for (const FloatImage* image : {&truth.ndf_params, &truth.shadowing_roughness, &truth.k_s, &truth.rho_d}) {
    if (image->width != truth.alpha.width || image->height != truth.alpha.height) {
      ThrowFormatError(folder.string(), "holds maps of different sizes");
    }
  }
  return truth;
}

DualMicrofacetParams MaterialTruth::Params(int x, int y) const {
  DualMicrofacetParams p;
  p.eta = eta;
  p.alpha = alpha.at(x, y);
  const double roughness = shadowing_roughness.at(x, y);
  p.shadowing = roughness > 0 ? SmithShadowing::Ggx(roughness) : SmithShadowing::None();
  for (int c = 0; c < 3; ++c) {
    p.k_s[c] = k_s.at(x, y, c);
    p.rho_d[c] = rho_d.at(x, y, c);
  }
  return p;
}

std::unique_ptr<Ndf> MaterialTruth::TexelNdf(int x, int y) const {
  AnalyticNdfParams p;
  p.alpha_x = ndf_params.at(x, y, 0);
  p.alpha_y = ndf_params.at(x, y, 1);
  p.theta_x = ndf_params.at(x, y, 2);
  p.theta_y = ndf_params.at(x, y, 3);
  p.theta_z = ndf_params.at(x, y, 4);
  return MakeAnalyticNdf(ndf_name, p);
}

TruthMaterial MaterialTruth::ToTruthMaterial() const {
  std::vector<TruthTexel> texels;
  texels.reserve(static_cast<size_t>(width()) * height());
  for (int y = 0; y < height(); ++y) {
    for (int x = 0; x < width(); ++x) {
      const DualMicrofacetParams p = Params(x, y);
      TruthTexel t;
      t.ndf = {ndf_params.at(x, y, 0), ndf_params.at(x, y, 1), ndf_params.at(x, y, 2), ndf_params.at(x, y, 3),
               ndf_params.at(x, y, 4)};
      t.alpha = p.alpha;
      t.shadowing_roughness = shadowing_roughness.at(x, y);
      t.k_s = p.k_s;
      t.rho_d = p.rho_d;
      texels.push_back(t);
    }
  }
  return TruthMaterial(width(), height(), eta, ndf_name, std::move(texels));
}

namespace {

// The truth the renderer shows the camera. The analytic material is cheap to regenerate; the
// Monte Carlo one is traced once, written to OUT/truth at once (so that an interrupted capture
// keeps it), and read back when a simulation is resumed: the file's float values are exactly the
// ones the first run rendered, so resumed images are byte-identical.
std::unique_ptr<SpatialBtdf> MakeTruth(const SimulationPreset& preset, const Rig& rig, const SimulationOptions& options,
                                       const fs::path& truth_folder) {
  const SampleConfig& sample = preset.rig.sample;
  if (options.truth == "model") {
    auto material = std::make_unique<TruthMaterial>(
        TruthMaterial::FromPattern(preset.pattern, sample.texels_x, sample.texels_y, preset.eta, options.seed));
    if (!fs::exists(truth_folder / "material.json")) WriteMaterialTruth(truth_folder, *material);
    return material;
  }
  if (fs::exists(truth_folder / "material.json")) {
    auto truth = std::make_unique<MonteCarloTruth>(ReadMonteCarloTruth(truth_folder));
    if (truth->texels_x() != sample.texels_x || truth->texels_y() != sample.texels_y || truth->eta() != preset.eta ||
        truth->seed != options.seed) {
      ThrowInvalidInput(truth_folder.string(), "holds the truth of other settings", "choose a new output folder");
    }
    return truth;
  }
  std::vector<SlabMaterial> materials = DefaultSlabMaterials();
  std::vector<int> index = SlabIndexMap(sample.texels_x, sample.texels_y, static_cast<int>(materials.size()), options.seed);
  const ViewGrid views = ViewGrid::Spanning(rig.camera().Centre(), sample, preset.view_nodes_per_axis);
  auto truth = std::make_unique<MonteCarloTruth>(MonteCarloTruth::Trace(sample.texels_x, sample.texels_y, preset.eta,
                                                                        std::move(materials), std::move(index), views,
                                                                        preset.montecarlo, options.seed,
                                                                        options.threads, options.progress));
  WriteMonteCarloTruth(truth_folder, *truth);
  return truth;
}

SimulationPreset PresetWithOptions(const SimulationOptions& options) {
  if (options.truth != "model" && options.truth != "montecarlo") {
    ThrowInvalidInput("--truth", "must be model or montecarlo, got '" + options.truth + "'");
  }
  SimulationPreset preset = MakePreset(options.preset);
  if (!options.noise) {
    preset.rig.sensor.shot_noise = false;
    preset.rig.sensor.read_noise = 0.0;
  }
  if (!std::isnan(options.monitor_orientation_deg)) preset.rig.monitor.orientation_deg = options.monitor_orientation_deg;
  if (!std::isnan(options.monitor_tilt_deg)) preset.rig.monitor.tilt_deg = options.monitor_tilt_deg;
  if (options.mirror_monitor) preset.rig.monitor.mirrored = true;
  if (options.eta != 0.0) {
    if (!(options.eta > 1.0) || !std::isfinite(options.eta)) {
      ThrowInvalidInput("--eta", "must be > 1, got " + std::to_string(options.eta));
    }
    preset.eta = options.eta;
  }
  return preset;
}

// OUT must be new, empty, or an unfinished simulation (session/ and truth/ only).
void CheckOutputFolder(const fs::path& out) {
  if (!fs::exists(out)) return;
  if (!fs::is_directory(out)) ThrowIoError(out.string(), "exists and is not a folder");
  for (const auto& entry : fs::directory_iterator(out)) {
    const std::string name = entry.path().filename().string();
    if (name != "session" && name != "truth") {
      ThrowInvalidInput(out.string(), "is not empty (it holds '" + name + "')", "choose a new output folder");
    }
  }
}

}  // namespace

SimulationOutput SimulateSession(const fs::path& out, const SimulationOptions& options) {
  const SimulationPreset preset = PresetWithOptions(options);
  SimulationOutput output{out / "session", out / "truth"};
  CheckOutputFolder(out);
  std::error_code error;
  fs::create_directories(output.truth, error);
  if (error) ThrowIoError(output.truth.string(), "cannot create: " + error.message(), "is the folder writable?");

  const Rig rig(preset.rig);
  if (fs::exists(output.session / "session.json")) {
    // Resuming: the journal is append-only, so a damaged image could not be rendered again under
    // its key, and the run would end with it still damaged.
    const session::SessionVerification check = session::Session::Open(output.session).Verify(/*check_crc=*/true);
    if (check.complete()) {
      ThrowInvalidInput(output.session.string(), "holds a complete simulated session already; it is never overwritten",
                        "choose a new output folder");
    }
    if (!check.corrupt.empty() || !check.duplicated.empty()) {
      ThrowFormatError(output.session.string(), "cannot be resumed: " + check.Summary(),
                       "simulate into a new output folder");
    }
  }
  const std::unique_ptr<SpatialBtdf> material = MakeTruth(preset, rig, options, output.truth);
  const RigRenderer renderer(rig, material.get(), options.threads);
  CaptureTruth plan = PlanCapture(preset, renderer, options.seed);
  plan.truth_kind = options.truth;
  std::vector<std::string> keys;
  for (const CaptureId& id : CaptureList(rig, plan)) keys.push_back(id.key.Format());

  session::Session session = session::Session::CreateOrResume(output.session, NominalRig(rig, preset, plan), keys);
  if (!fs::exists(output.truth / "rig.json")) WriteRigTruth(output.truth / "rig.json", rig, plan);

  output.resumed = static_cast<int64_t>(session.entries().size());
  SessionSink sink(&session);
  CaptureOptions capture_options;
  capture_options.seed = options.seed;
  capture_options.threads = options.threads;
  capture_options.progress = options.progress;
  RunCapture(renderer, plan, sink, capture_options);
  output.images = static_cast<int64_t>(session.entries().size());
  return output;
}

}  // namespace svbtdf
