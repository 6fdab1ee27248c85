// The pipeline's stages as Python functions: the library entry points the command line calls
// (process/pipeline.h, report/compare.h, render/), with its options as keyword arguments (bound
// in python/svbtdf/__init__.py), a progress callback and Ctrl-C that stops them resumably. Like
// the commands, a stage holds its output folder's lock (common/folder_lock.h) while it writes.
//
// While a stage runs, the GIL is released and svbtdf's own SIGINT/SIGTERM handler
// (common/interrupt.h) replaces Python's, so that Ctrl-C reaches the stage's safe points as on the
// command line; the stage then raises svbtdf.Interrupted (a KeyboardInterrupt) and the same call
// resumes. Python's handlers are put back afterwards.

#include <signal.h>

#include <chrono>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>

#include "bindings.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/folder_lock.h"
#include "svbtdf/common/image_io.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/process/pipeline.h"
#include "svbtdf/render/image_metrics.h"
#include "svbtdf/render/renderer.h"
#include "svbtdf/render/scene.h"
#include "svbtdf/render/surface.h"
#include "svbtdf/report/compare.h"
#include "svbtdf/simulate/truth.h"

namespace svbtdf::python {
namespace {
namespace fs = std::filesystem;

// The Python callbacks of one stage and the first exception one of them raised.
struct Callbacks {
  Callbacks(py::object progress_callback, py::object log_callback)
      : progress(std::move(progress_callback)), log(std::move(log_callback)) {}

  py::object progress;  // progress(label: str, done: int, total: int), or None
  py::object log;       // log(line: str), or None
  std::mutex mutex;
  std::optional<py::error_already_set> error;

  // Calls `callback` with the GIL; an exception it raises stops the stage at its next safe point
  // (as Ctrl-C does) and is re-raised when the stage has stopped.
  template <typename... Args>
  void Call(const py::object& callback, Args&&... args) {
    if (callback.is_none()) return;
    py::gil_scoped_acquire gil;
    try {
      callback(std::forward<Args>(args)...);
    } catch (py::error_already_set& e) {
      std::lock_guard<std::mutex> lock(mutex);
      if (!error) error.emplace(std::move(e));
      common::SetInterruptRequested(true);
    }
  }

  process::PipelineListener Listener() {
    return {[this](const std::string& line) { Call(log, line); },
            [this](const std::vector<fit::QualityWarning>& warnings) {
              for (const fit::QualityWarning& w : warnings) Call(log, w.Line());
            }};
  }
};

// svbtdf's interrupt handler for the duration of a stage, on the main thread only (signals are
// delivered to Python's handler there; other threads cannot change it).
class InterruptScope {
 public:
  InterruptScope() : active_(std::this_thread::get_id() == main_thread_) {
    common::SetInterruptRequested(false);
    if (!active_) return;
    sigaction(SIGINT, nullptr, &old_int_);
    sigaction(SIGTERM, nullptr, &old_term_);
    common::InstallInterruptHandler();
  }
  ~InterruptScope() {
    if (active_) {
      sigaction(SIGINT, &old_int_, nullptr);
      sigaction(SIGTERM, &old_term_, nullptr);
    }
    common::SetInterruptRequested(false);
  }
  static void RememberMainThread() { main_thread_ = std::this_thread::get_id(); }

 private:
  static inline std::thread::id main_thread_;
  bool active_;
  struct sigaction old_int_ {}, old_term_ {};
};

// Runs `work` as a stage: GIL released, interrupts and progress routed, errors re-raised.
template <typename Work>
auto RunStage(Callbacks& callbacks, Work&& work) -> decltype(work()) {
  const bool observed = !callbacks.progress.is_none();
  if (observed) {
    common::ProgressBar::SetEnabled(false);  // the callback reports instead of the bars on stderr
    common::ProgressBar::SetObserver([&callbacks](const std::string& label, int64_t done, int64_t total) {
      callbacks.Call(callbacks.progress, label, done, total);
    });
  }
  std::exception_ptr failure;
  std::optional<decltype(work())> result;
  {
    InterruptScope interrupts;
    py::gil_scoped_release release;
    try {
      result.emplace(work());
    } catch (...) {
      failure = std::current_exception();
    }
  }
  if (observed) {
    common::ProgressBar::SetObserver({});
    common::ProgressBar::SetEnabled(true);
  }
  if (callbacks.error) {
    py::error_already_set error = std::move(*callbacks.error);
    callbacks.error.reset();
    throw error;
  }
  if (failure) std::rethrow_exception(failure);
  return std::move(*result);
}

fit::FitMaterialOptions FitOptions(const std::string& model, double eta, const std::string& representatives,
                                   double holdout, bool refine, bool fixed_horizon, int ndf_resolution, uint64_t seed,
                                   int threads) {
  fit::FitMaterialOptions options;
  if (model == "dual") options.model = fit::MaterialModel::kDualMicrofacet;
  else if (model == "ggx") options.model = fit::MaterialModel::kWalterGgx;
  else if (model == "slab") options.model = fit::MaterialModel::kSlab;
  else common::ThrowInvalidInput("model", "must be 'dual', 'ggx' or 'slab', not '" + model + "'");
  options.eta = eta;
  options.representative_fraction = fit::ParseRepresentativeFraction(representatives, "representatives");
  options.holdout = holdout;
  options.refine_texels = refine;
  options.free_horizon = !fixed_horizon;
  options.ndf_resolution = ndf_resolution;
  options.seed = seed;
  options.threads = threads;
  return options;
}

py::dict Calibrate(const std::string& session, bool fix_k3, bool full_lens_model, py::object progress, py::object log) {
  calib::CalibrateSessionOptions options;
  options.camera.fix_k3 = fix_k3;
  if (full_lens_model) options.camera.max_principal_point_std_fraction = 0;
  Callbacks callbacks{progress, log};
  const process::CalibrationStage stage = RunStage(callbacks, [&] { return process::CalibrateAndCheck(session, options); });
  callbacks.Listener().warn(stage.warnings);
  py::dict out;
  out["file"] = stage.file.string();
  out["calibration"] = ToPython(calib::ToJson(stage.calibration));
  out["warnings"] = ToPython(stage.warnings);
  return out;
}

py::dict Process(const std::string& session, const std::string& out_folder, std::pair<int, int> texels,
                 int light_resolution, int threads, py::object progress, py::object log) {
  process::ProcessOptions options;
  options.texels_x = texels.first;
  options.texels_y = texels.second;
  options.light_resolution = light_resolution;
  options.threads = threads;
  Callbacks callbacks{progress, log};
  const process::ProcessStage stage = RunStage(callbacks, [&] {
    const common::FolderLock lock = common::FolderLock::Acquire(out_folder, "svbtdf.process (Python)");
    return process::ProcessAndCheck(session, out_folder, options);
  });
  callbacks.Listener().warn(stage.warnings);
  py::dict out;
  out["store"] = out_folder;
  out["texels"] = stage.report.texels;
  out["valid_texels"] = stage.report.valid_texels;
  out["dots"] = stage.report.dots;
  out["dots_resumed"] = stage.report.dots_resumed;
  out["images_read"] = stage.report.images_read;
  out["seconds"] = stage.report.seconds;
  out["warnings"] = ToPython(stage.warnings);
  return out;
}

py::dict Fit(const std::string& processed, const std::string& out_folder, const std::string& model, double eta,
             const std::string& representatives, double holdout, bool refine, bool fixed_horizon, int ndf_resolution,
             uint64_t seed, int threads, py::object progress, py::object log) {
  const fit::FitMaterialOptions options =
      FitOptions(model, eta, representatives, holdout, refine, fixed_horizon, ndf_resolution, seed, threads);
  Callbacks callbacks{progress, log};
  const std::vector<fit::QualityWarning> warnings = RunStage(callbacks, [&] {
    const common::FolderLock lock = common::FolderLock::Acquire(out_folder, "svbtdf.fit (Python)");
    return process::FitAndWriteMaterial(processed, out_folder, options, callbacks.Listener());
  });
  py::dict out;
  out["material"] = out_folder;
  out["warnings"] = ToPython(warnings);
  return out;
}

py::dict Run(const std::string& session, const std::string& out_folder, const std::string& work, int light_resolution,
             const std::string& model, double eta, const std::string& representatives, double holdout, bool refine,
             bool fixed_horizon, int ndf_resolution, uint64_t seed, int threads, py::object progress, py::object log) {
  process::PipelineOptions options;
  options.session = session;
  options.out = out_folder;
  options.work = work;
  options.process.light_resolution = light_resolution;
  options.process.threads = threads;
  options.fit = FitOptions(model, eta, representatives, holdout, refine, fixed_horizon, ndf_resolution, seed, threads);
  Callbacks callbacks{progress, log};
  const process::PipelineOutcome outcome = RunStage(callbacks, [&] {
    // As `svbtdf run`: the material names the run; its work folder is only ever written under it.
    const common::FolderLock lock = common::FolderLock::Acquire(out_folder, "svbtdf.run (Python)");
    return process::RunPipeline(options, callbacks.Listener());
  });
  py::dict out;
  out["material"] = out_folder;
  out["work"] = outcome.work.string();
  out["warnings"] = ToPython(outcome.warnings);
  return out;
}

py::object Compare(const std::string& material_folder, const std::string& truth_folder, int texels, uint64_t seed) {
  report::CompareOptions options;
  options.material_folder = material_folder;
  options.max_texels = texels;
  options.seed = seed;
  Callbacks callbacks{py::none(), py::none()};
  const nlohmann::json metrics = RunStage(callbacks, [&] {
    const fit::Material material = fit::ReadMaterial(material_folder);
    const simulate::Truth truth = simulate::ReadTruth(truth_folder);
    return report::ToJson(report::Compare(material, truth, options));
  });
  return ToPython(metrics);
}

struct RenderArguments {
  render::RenderOptions render;
  render::SceneOptions scene;
  std::optional<std::pair<double, double>> sample_size;
  std::string out, png;
  double exposure = 1.0;
};

py::array_t<float> Render(const std::string& material_folder, const RenderArguments& arguments, py::object progress) {
  Callbacks callbacks{progress, py::none()};
  const common::FloatImage image = RunStage(callbacks, [&] {
    const render::Camera camera(arguments.render.camera);  // bad views fail before the material is read
    const render::LoadedSurface loaded = render::LoadSurface(material_folder, arguments.sample_size);
    const std::unique_ptr<render::Scene> scene = render::MakeScene(arguments.scene, loaded.surface().width_m());
    common::FloatImage rendered = render::Render(loaded.surface(), *scene, arguments.render);
    if (!arguments.out.empty()) common::WriteFloatImage(arguments.out, rendered, /*half_precision=*/false, /*overwrite=*/true);
    if (!arguments.png.empty()) {
      common::WriteRgb8Png(arguments.png, render::ToSrgb8(rendered, arguments.exposure), rendered.width, rendered.height,
                           /*overwrite=*/true);
    }
    return rendered;
  });
  return ToArray(image, /*squeeze=*/false);
}

}  // namespace

void BindStages(py::module_& m) {
  InterruptScope::RememberMainThread();  // the module is imported on the main thread
  const char* callbacks_doc =
      " progress(label, done, total) is called about 10 times a second per progress bar (the bars on stderr are "
      "then off); log(line) gets the stage's lines and its quality warnings. Ctrl-C (or an exception raised by a "
      "callback) stops the stage at its next safe point, keeping its work: svbtdf.Interrupted is raised and the "
      "same call resumes.";
  m.def("_calibrate", &Calibrate, py::arg("session"), py::arg("fix_k3"), py::arg("full_lens_model"), py::arg("progress"),
        py::arg("log"));
  m.def("_process", &Process, py::arg("session"), py::arg("out"), py::arg("texels"), py::arg("light_resolution"),
        py::arg("threads"), py::arg("progress"), py::arg("log"));
  m.def("_fit", &Fit, py::arg("processed"), py::arg("out"), py::arg("model"), py::arg("eta"), py::arg("representatives"),
        py::arg("holdout"), py::arg("refine"), py::arg("fixed_horizon"), py::arg("ndf_resolution"), py::arg("seed"),
        py::arg("threads"), py::arg("progress"), py::arg("log"));
  m.def("_run", &Run, py::arg("session"), py::arg("out"), py::arg("work"), py::arg("light_resolution"), py::arg("model"),
        py::arg("eta"), py::arg("representatives"), py::arg("holdout"), py::arg("refine"), py::arg("fixed_horizon"),
        py::arg("ndf_resolution"), py::arg("seed"), py::arg("threads"), py::arg("progress"), py::arg("log"));
  m.def("_compare", &Compare, py::arg("material"), py::arg("truth"), py::arg("texels"), py::arg("seed"));
  m.def(
      "_render",
      [](const std::string& material, const std::string& out, const std::string& png, double exposure,
         const std::string& scene, std::pair<double, double> view_deg, double distance, double fov_deg,
         std::pair<int, int> resolution, int spp, uint64_t seed, int threads, const std::string& background,
         double background_distance, double background_width, double checker_size, const std::string& environment,
         std::optional<std::pair<double, double>> sample_size, py::object progress) {
        RenderArguments a;
        a.out = out;
        a.png = png;
        a.exposure = exposure;
        a.scene.scene = scene;
        a.scene.background = background;
        a.scene.environment = environment;
        a.scene.background_distance_m = background_distance;
        a.scene.background_width_m = background_width;
        a.scene.checker_size_m = checker_size;
        a.render.camera.theta_deg = view_deg.first;
        a.render.camera.phi_deg = view_deg.second;
        a.render.camera.distance_m = distance;
        a.render.camera.fov_deg = fov_deg;
        a.render.camera.width = resolution.first;
        a.render.camera.height = resolution.second;
        a.render.samples_per_pixel = spp;
        a.render.seed = seed;
        a.render.threads = threads;
        a.render.progress = true;
        a.sample_size = sample_size;
        return Render(material, a, progress);
      });
  m.attr("_CALLBACKS_DOC") = callbacks_doc;
}

}  // namespace svbtdf::python
