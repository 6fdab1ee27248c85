#include "svbtdf/acquire/capture_session.h"

#include <spdlog/spdlog.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <future>
#include <iostream>
#include <memory>
#include <optional>
#include <regex>
#include <set>
#include <thread>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/session/session.h"

namespace svbtdf::acquire {
namespace fs = std::filesystem;
namespace {

std::string Megabytes(uint64_t bytes) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1f MB", bytes / 1e6);
  return buffer;
}

// A plan whose dots the display cannot show would fail late, after the calibration captures.
void RequireDotsOnDisplay(const CapturePlan& plan, const DisplayInfo& display) {
  if (display.width_px <= 0 || display.height_px <= 0) return;  // size unknown
  for (size_t q = 0; q < plan.dots_px.size(); ++q) {
    const auto [x, y] = plan.dots_px[q];
    const double r = plan.dot_radius_px;
    if (x - r < -0.5 || y - r < -0.5 || x + r > display.width_px - 0.5 || y + r > display.height_px - 0.5) {
      common::ThrowInvalidInput("plan", "dot " + std::to_string(q) + " at (" + std::to_string(x) + ", " + std::to_string(y) +
                                    ") px does not fit display " + display.id + " (" + std::to_string(display.width_px) +
                                    " x " + std::to_string(display.height_px) + " px)",
                        "move the dot grid's origin or shrink its pitch");
    }
  }
}

// An existing session must be this plan's, and intact: the journal is append-only, so a corrupt
// image cannot be re-captured under its key by resuming.
std::optional<session::Session> OpenExisting(const fs::path& folder, const CapturePlan& plan) {
  if (!fs::exists(folder / "session.json")) return std::nullopt;
  session::Session session = session::Session::Open(folder);
  const nlohmann::json& acquired_plan = session.rig().acquisition_plan;
  if (acquired_plan.is_null()) {
    common::ThrowInvalidInput(folder.string(), "holds a session that `svbtdf acquire` did not write; it will not be changed",
                      "choose a new --out folder");
  }
  if (acquired_plan != CapturePlanToJson(plan)) {
    common::ThrowInvalidInput(folder.string(), "holds a session of a different capture plan; it will not be changed",
                      "resume with the plan it was started with (its session.json records it), or choose a new --out");
  }
  const session::SessionVerification report = session.Verify(/*check_crc=*/true);
  if (!report.corrupt.empty() || !report.duplicated.empty()) {
    common::ThrowFormatError(folder.string(), "cannot be resumed: " + report.Summary(),
                     "run `svbtdf session verify " + folder.string() + "` for the list");
  }
  return session;
}

void RequireFreeSpace(const fs::path& folder, uint64_t needed, int64_t images, const AcquireOptions& options) {
  const uint64_t available = options.free_space ? options.free_space(folder) : common::FreeSpaceAt(folder);
  if (available < needed) {
    common::ThrowIoError(folder.string(), "has " + Megabytes(available) + " free but the " + std::to_string(images) +
                                      " images still to capture need about " + Megabytes(needed),
                 "free some space or choose an --out folder on another disk");
  }
}

common::CameraImage ToImage(const Frame& frame, const std::string& camera_id) {
  const size_t expected = static_cast<size_t>(frame.width) * frame.height * frame.channels;
  if (frame.width <= 0 || frame.height <= 0 || (frame.channels != 1 && frame.channels != 3) ||
      frame.pixels.size() != expected) {
    throw common::Error(common::ErrorKind::kHardware, camera_id, "delivered a malformed frame (" + std::to_string(frame.width) + "x" +
                                                     std::to_string(frame.height) + "x" + std::to_string(frame.channels) + ")");
  }
  common::CameraImage image;
  image.width = frame.width;
  image.height = frame.height;
  image.channels = frame.channels;
  image.bits_per_sample = frame.bits_per_sample;
  image.pixels = frame.pixels;
  return image;
}

// Stores each captured image (PNG encoding, fsync, journal: Session::AddImage) on a thread of its
// own while the loop takes the next one, so that the camera's exposure and transfer (or the
// simulator's rendering, which keeps both cores busy) overlap the writing instead of waiting for
// it. One image at a time and in order: the journal is the one a serial loop writes. The loop
// touches the session only after Finish, so the session is never used by two threads at once.
class BackgroundWriter {
 public:
  BackgroundWriter() = default;
  BackgroundWriter(const BackgroundWriter&) = delete;
  BackgroundWriter& operator=(const BackgroundWriter&) = delete;
  // A loop stopped by an error still journals the image it had handed over: nothing captured is
  // dropped. That write's own error, if any, can only be logged (another error is on its way).
  ~BackgroundWriter() {
    if (!pending_.valid()) return;
    try {
      pending_.get();
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
    }
  }

  // Waits for the previous image (rethrowing its error) and starts writing the next.
  void Start(std::function<void()> write) {
    Finish();
    pending_ = std::async(std::launch::async, std::move(write));
  }

  // Waits until the image handed over last is journalled; rethrows its error. True when one was.
  bool Finish() {
    if (!pending_.valid()) return false;
    pending_.get();
    return true;
  }

 private:
  std::future<void> pending_;
};

// One run over the missing captures. Keeps what the hardware currently shows and uses, so that a
// pattern is shown (and settled) once for all its brackets and repeats.
class CaptureRun {
 public:
  CaptureRun(const CapturePlan& plan, Camera& camera, Display& display, Operator& op, session::Session& session,
             const AcquireOptions& options, AcquireResult& result)
      : plan_(plan), camera_(camera), display_(display), op_(op), session_(session), options_(options),
        result_(result), info_(camera.Info()), camera_id_(info_.id), windowed_(!info_.window.whole_sensor()) {}

  void Run(const std::vector<PlannedCapture>& captures) {
    std::unique_ptr<common::ProgressBar> progress;
    if (options_.progress) {
      progress = std::make_unique<common::ProgressBar>(options_.progress_label, static_cast<int64_t>(captures.size()), "images");
      progress->SkipAlreadyDone(result_.already);
    }
    // Chosen before the first write: the writer thread changes what Contains sees.
    std::vector<const PlannedCapture*> missing;
    for (const PlannedCapture& capture : captures) {
      if (!session_.Contains(capture.key)) missing.push_back(&capture);
    }
    const auto journalled = [&] {
      if (!writer_.Finish()) return;
      ++result_.captured;
      if (progress) progress->Advance(1);
    };
    for (const PlannedCapture* capture : missing) {
      StopIfInterrupted();
      if (!SceneReady(*capture)) {
        ++result_.skipped;
        continue;
      }
      const Frame frame = CaptureWithRetries(*capture);  // while the previous image is written
      journalled();
      CheckFrame(*capture, frame);
      writer_.Start([this, key = capture->key, image = ToImage(frame, camera_id_), exposure_s = frame.exposure_s,
                     gain = frame.gain, presented_s = presented_s_] {
        session_.AddImage(key, image, exposure_s, gain, presented_s);
      });
    }
    journalled();
  }

 private:
  void StopIfInterrupted() {
    if (!common::InterruptRequested()) return;
    writer_.Finish();  // the image captured last is kept
    throw common::Error(common::ErrorKind::kInterrupted, session_.folder().string(),
                "acquisition interrupted with " + std::to_string(session_.entries().size()) + " of " +
                    std::to_string(session_.planned_keys().size()) + " images captured",
                "the session is resumable: run the same command again");
  }

  // One session holds one sensor mode (calibration assumes it), also across resumes with
  // another camera; and a camera that snaps the exposure is worth knowing about. A camera that
  // crops to a window takes its board views on the whole sensor: those share a size of their own.
  void CheckFrame(const PlannedCapture& capture, const Frame& frame) {
    const bool whole_sensor = windowed_ && capture.scene == Scene::kBoardView;
    std::optional<std::array<int, 3>>& expected = size_[whole_sensor ? 1 : 0];
    const std::array<int, 3> size = {frame.width, frame.height, frame.channels};
    std::string source = "the session holds";
    if (!expected && whole_sensor) {  // the camera told us its sensor
      expected = {info_.window.sensor_width, info_.window.sensor_height, frame.channels};
      source = "the camera's sensor is";
    }
    for (size_t n = 0; !expected && n < session_.entries().size(); ++n) {
      const std::string& key = session_.entries()[n].key;
      if (windowed_ && (key.rfind("board/", 0) == 0) != whole_sensor) continue;
      const common::CameraImage first = session_.ReadImage(key);
      expected = {first.width, first.height, first.channels};
    }
    if (expected && *expected != size) {
      const auto text = [](const std::array<int, 3>& s) {
        return std::to_string(s[0]) + "x" + std::to_string(s[1]) + "x" + std::to_string(s[2]);
      };
      throw common::Error(common::ErrorKind::kInvalidInput, camera_id_,
                  "delivers " + text(size) + " frames but " + source + " " + text(*expected),
                  "resume with the camera and format the session was started with");
    }
    expected = size;
    if (std::abs(frame.exposure_s - capture.exposure_s) > 0.05 * capture.exposure_s &&
        warned_exposures_.insert(capture.exposure_s).second) {
      spdlog::warn("{}: asked for {} s, the camera used {} s (journalled as used)", camera_id_, capture.exposure_s,
                   frame.exposure_s);
    }
  }

  // Asks the operator once per scene change; a skipped scene skips all its captures.
  bool SceneReady(const PlannedCapture& capture) {
    const std::pair<Scene, int> scene{capture.scene, capture.view};
    if (scene_ != scene) {
      scene_ = scene;
      scene_ready_ = op_.Prepare(capture.scene, capture.view, SceneInstruction(capture.scene, capture.view));
      StopIfInterrupted();  // the operator may have pressed Ctrl-C while asked
    }
    return scene_ready_;
  }

  Frame CaptureWithRetries(const PlannedCapture& capture) {
    for (int attempt = 0;; ++attempt) {
      try {
        return CaptureOnce(capture, /*reset=*/attempt > 0);
      } catch (const common::Error& e) {
        if (e.kind() != common::ErrorKind::kHardware) throw;
        if (attempt >= options_.retries) {
          writer_.Finish();  // the images captured so far are kept, and counted below
          throw common::Error(common::ErrorKind::kHardware, camera_id_,
                      "failed " + std::to_string(attempt + 1) + " times in a row at " + capture.key + " (" + e.what() +
                          "); stopped with " + std::to_string(session_.entries().size()) + " of " +
                          std::to_string(session_.planned_keys().size()) + " images captured",
                      "the session is resumable: check the camera and its cable, then run the same command again");
        }
        const double wait = options_.retry_backoff_s * std::pow(2.0, attempt);
        spdlog::warn("{}: capture of {} failed ({}); retry {} of {} in {:.1f} s", camera_id_, capture.key, e.what(),
                     attempt + 1, options_.retries, wait);
        ++result_.retries;
        Sleep(wait);
        StopIfInterrupted();
      }
    }
  }

  // After a failure everything is set again: the camera or display may have been reset.
  Frame CaptureOnce(const PlannedCapture& capture, bool reset) {
    if (options_.before_capture) options_.before_capture(capture);
    if (reset || !shown_ || !SamePattern(*shown_, capture.pattern)) {
      shown_.reset();
      const Presentation presentation = display_.Show(capture.pattern);
      shown_ = capture.pattern;
      presented_s_ = presentation.presented_s;
      if (presentation.missed_frames > 0) {
        spdlog::warn("{}: the display presented {} refreshes late", capture.key, presentation.missed_frames);
      }
    }
    // Never before the frame carrying the pattern is on screen plus the monitor's response time
    // (and its glow after a bright pattern), whenever the display says it was presented.
    Sleep(presented_s_ + plan_.settle_s - Now());
    if (reset || exposure_ != capture.exposure_s) {
      exposure_.reset();
      camera_.SetExposure({capture.exposure_s, plan_.gain});
      exposure_ = capture.exposure_s;
    }
    return camera_.Capture();
  }

  double Now() const { return options_.now ? options_.now() : MonotonicSeconds(); }

  void Sleep(double seconds) const {
    if (seconds <= 0) return;
    if (options_.sleep) {
      options_.sleep(seconds);
    } else {
      std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    }
  }

  const CapturePlan& plan_;
  Camera& camera_;
  Display& display_;
  Operator& op_;
  session::Session& session_;
  const AcquireOptions& options_;
  AcquireResult& result_;
  CameraInfo info_;
  std::string camera_id_;
  std::optional<Pattern> shown_;
  double presented_s_ = 0.0;  // when the pattern shown now was presented (MonotonicSeconds)
  std::optional<double> exposure_;
  std::optional<std::pair<Scene, int>> scene_;
  bool windowed_ = false;  // the camera crops to a window; board views are whole-sensor
  std::array<std::optional<std::array<int, 3>>, 2> size_;  // window frames, whole-sensor frames
  std::set<double> warned_exposures_;
  bool scene_ready_ = false;
  BackgroundWriter writer_;  // last: destroyed (and so waited for) before anything it uses
};

}  // namespace

bool UnattendedOperator::Prepare(Scene scene, int view, const std::string& instruction) {
  if (policy_ == UnattendedPolicy::kSkip && scene != Scene::kSample) {
    spdlog::info("skipping captures that need the operator: {}", instruction);
    return false;
  }
  spdlog::info("capturing as set up (not prompted): {}", instruction);
  return true;
}

bool ConsoleOperator::Prepare(Scene scene, int view, const std::string& instruction) {
  out_ << "\n>>> " << instruction << "\n    Enter: capture, s + Enter: skip these captures > " << std::flush;
  std::string line;
  if (!std::getline(in_, line)) return false;  // no operator after all
  return line.empty() || (line[0] != 's' && line[0] != 'S');
}

uint64_t EstimatedBytesPerImage(const CapturePlan& plan, const CameraInfo& camera) {
  if (plan.bytes_per_image > 0) return plan.bytes_per_image;
  constexpr uint64_t kPngOverhead = 64 * 1024;
  if (camera.frame_width > 0 && camera.frame_height > 0) {
    const uint64_t channels = camera.frame_channels > 0 ? camera.frame_channels : 3;
    return static_cast<uint64_t>(camera.frame_width) * camera.frame_height * channels * 2 + kPngOverhead;
  }
  const std::regex size(R"((\d+)x(\d+))");
  uint64_t largest = 0;
  for (const std::string& format : camera.formats) {
    std::smatch match;
    if (std::regex_search(format, match, size)) {
      largest = std::max<uint64_t>(largest, std::stoull(match[1]) * std::stoull(match[2]));
    }
  }
  if (largest == 0) return 64ull * 1024 * 1024;  // unknown: a 10 MP RGB image, generously
  return largest * 3 * 2 + kPngOverhead;
}

uint64_t EstimatedBytes(const std::vector<PlannedCapture>& captures, const CapturePlan& plan, const CameraInfo& camera,
                        const session::Session* captured) {
  const uint64_t channels = camera.frame_channels > 0 ? camera.frame_channels : 3;
  const bool windowed = !camera.window.whole_sensor();
  // [0]: window-sized images, [1]: whole-sensor board views of a windowed camera.
  std::array<uint64_t, 2> per_image = {EstimatedBytesPerImage(plan, camera), 0};
  per_image[1] = windowed ? std::max(per_image[0], static_cast<uint64_t>(camera.window.sensor_width) *
                                                       camera.window.sensor_height * channels * 2)
                          : per_image[0];
  if (captured) {
    std::array<uint64_t, 2> largest = {0, 0};
    for (const session::SessionEntry& entry : captured->entries()) {
      const size_t size_class = windowed && entry.key.rfind("board/", 0) == 0 ? 1 : 0;
      largest[size_class] = std::max(largest[size_class], entry.bytes);
    }
    for (size_t c = 0; c < 2; ++c) {
      if (largest[c] > 0) per_image[c] = largest[c] + largest[c] / 10;
    }
  }
  uint64_t bytes = 0;
  for (const PlannedCapture& capture : captures) {
    bytes += per_image[windowed && capture.scene == Scene::kBoardView ? 1 : 0];
  }
  return bytes + bytes / 20;
}

nlohmann::json AcquisitionRig(const CapturePlan& plan, const CameraInfo& camera, const DisplayInfo& display) {
  const RigNotes& notes = plan.rig;
  session::RigDescription rig;
  // What the camera backend and the plan's notes know; the rest stays unset (docs/session-format.md).
  rig.camera.id = camera.id;
  rig.camera.model = camera.model;
  rig.camera.width = camera.frame_width;
  rig.camera.height = camera.frame_width > 0 ? camera.frame_height : 0;
  rig.camera.channels = camera.frame_channels;
  rig.camera.bit_depth = camera.frame_bits;
  rig.camera.response = notes.camera_response;
  rig.camera.sensor = camera.window;
  rig.monitor.id = display.id;
  rig.monitor.width_px = display.width_px;
  rig.monitor.height_px = display.height_px;
  rig.monitor.gamma = display.gamma;
  const double pitch_mm = plan.pixel_pitch_mm > 0 ? plan.pixel_pitch_mm : display.pixel_pitch_mm;
  if (pitch_mm > 0) rig.monitor.pixel_pitch_m = pitch_mm / 1000.0;
  if (notes.monitor_distance_mm > 0) rig.monitor.distance_m = notes.monitor_distance_mm / 1000.0;
  rig.monitor.emission = notes.emission;
  rig.monitor.polarisation = notes.monitor_polarisation;
  rig.monitor.orientation_deg = notes.monitor_orientation_deg;
  rig.dots.cols = plan.dot_cols;
  rig.dots.rows = plan.dot_rows;
  rig.dots.radius_px = plan.dot_radius_px;
  rig.dots.positions_px = plan.dots_px;
  if (plan.fiducials) rig.dots.fiducials = plan.fiducial_dots;
  if (!notes.board.empty()) rig.board = {notes.board, plan.board_views};
  rig.sample_plane_board.spec = notes.sample_plane_board;
  if (notes.sample_width_mm > 0) rig.sample.width_m = notes.sample_width_mm / 1000.0;
  if (notes.sample_height_mm > 0) rig.sample.height_m = notes.sample_height_mm / 1000.0;
  if (notes.texels_x > 0) rig.sample.texels_x = notes.texels_x, rig.sample.texels_y = notes.texels_y;
  rig.sample.eta = notes.eta;
  rig.exposures_s = plan.exposures_s;
  rig.acquisition_plan = CapturePlanToJson(plan);
  return session::ToJson(rig);
}

AcquireResult Acquire(const CapturePlan& plan, Camera& camera, Display& display, Operator& op,
                      const fs::path& session_folder, const AcquireOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<PlannedCapture> captures = ExpandPlan(plan);
  const std::vector<std::string> keys = PlanKeys(captures);
  const CameraInfo camera_info = camera.Info();
  const DisplayInfo display_info = display.Info();
  RequireDotsOnDisplay(plan, display_info);
  std::optional<session::Session> session = OpenExisting(session_folder, plan);

  AcquireResult result;
  result.planned = static_cast<int64_t>(keys.size());
  result.already = session ? static_cast<int64_t>(session->entries().size()) : 0;
  const int64_t missing = result.planned - result.already;
  std::vector<PlannedCapture> to_capture;
  for (const PlannedCapture& capture : captures) {
    if (!session || !session->Contains(capture.key)) to_capture.push_back(capture);
  }
  constexpr uint64_t kManifestAndJournal = 1 << 20;
  RequireFreeSpace(session_folder,
                   EstimatedBytes(to_capture, plan, camera_info, session ? &*session : nullptr) + kManifestAndJournal, missing,
                   options);
  if (session) {
    // Left by a kill mid-write; the lock (held by the command) says no other writer owns them.
    const int removed = common::RemoveStaleTemporaryFiles(session_folder);
    if (removed > 0) spdlog::info("{}: removed {} temporary files left by an interrupted run", session_folder.string(), removed);
  }
  if (!session) {
    nlohmann::json rig = AcquisitionRig(plan, camera_info, display_info);
    rig.merge_patch(options.rig_additions);
    session = session::Session::Create(session_folder, rig, keys);
  }

  CaptureRun(plan, camera, display, op, *session, options, result).Run(captures);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace svbtdf::acquire
