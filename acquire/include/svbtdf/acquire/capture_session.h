#pragma once
// The capture loop of `svbtdf acquire` (docs/capture.md): for every planned capture that the
// session does not hold yet, show its pattern, wait the settle time, set the exposure, capture
// and store the image (atomic, journalled). Hardware is reached only through the Camera and
// Display interfaces, and the person at the rig through Operator, so the loop runs the same on
// the lab rig and on the simulated one.
//
// Stopping is always clean: an interrupt (SIGINT, Escape on the display) or a camera that keeps
// failing ends the loop between captures with svbtdf::Error, leaving a session that the same
// command resumes.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>

#include <nlohmann/json.hpp>

#include "svbtdf/acquire/camera.h"
#include "svbtdf/acquire/capture_plan.h"
#include "svbtdf/acquire/display.h"
#include "svbtdf/session/session.h"

namespace svbtdf::acquire {

// The person at the rig, asked to arrange a scene (place the sample, hold the board ...).
class Operator {
 public:
  virtual ~Operator() = default;
  // Called before the first capture of a scene. Returns false to skip that scene's captures
  // (they stay missing; a later run can take them).
  virtual bool Prepare(Scene scene, int view, const std::string& instruction) = 0;
};

// Non-interactive operators: `kAsIs` captures whatever is in front of the camera (the set-up was
// arranged beforehand); `kSkip` takes only the captures that need nobody at the rig
// (Scene::kSample) and skips the others.
enum class UnattendedPolicy { kAsIs, kSkip };
class UnattendedOperator : public Operator {
 public:
  explicit UnattendedOperator(UnattendedPolicy policy) : policy_(policy) {}
  bool Prepare(Scene scene, int view, const std::string& instruction) override;

 private:
  UnattendedPolicy policy_;
};

// Asks on the terminal: Enter to capture, "s" to skip the scene; end of input skips.
class ConsoleOperator : public Operator {
 public:
  ConsoleOperator(std::istream& in, std::ostream& out) : in_(in), out_(out) {}
  bool Prepare(Scene scene, int view, const std::string& instruction) override;

 private:
  std::istream& in_;
  std::ostream& out_;
};

struct AcquireOptions {
  int retries = 3;                 // further attempts after a failed capture
  double retry_backoff_s = 0.5;    // wait before retry k: backoff * 2^k
  bool progress = true;
  std::string progress_label = "acquire";
  // Added to the manifest's rig beside what AcquisitionRig records (`svbtdf simulate` names its
  // preset, seed and truth there); must be an object.
  nlohmann::json rig_additions = nlohmann::json::object();
  // Called before every attempt at a capture, with what the plan asks for. A real rig has no use
  // for it; the simulated one learns which capture it renders (a resumed dark frame's number).
  std::function<void(const PlannedCapture&)> before_capture;
  // Free bytes at a folder (the first existing ancestor of the session); injectable for tests.
  std::function<uint64_t(const std::filesystem::path&)> free_space;
  // Sleeping (settle time, back-off) and the clock presentation times are on
  // (MonotonicSeconds); injectable so that tests do not wait.
  std::function<void(double seconds)> sleep;
  std::function<double()> now;
};

struct AcquireResult {
  int64_t planned = 0;
  int64_t already = 0;   // journalled before this run
  int64_t captured = 0;  // by this run
  int64_t skipped = 0;   // left missing because the operator skipped them
  int64_t retries = 0;   // failed attempts that a retry recovered
  double seconds = 0.0;
  bool complete() const { return already + captured == planned; }
};

// Bytes the plan's window-sized images need at most: the plan's bytes_per_image, else the
// camera's frame as 16-bit samples (PNG never stores more than that plus its headers), else the
// largest frame size the camera lists as 16-bit RGB.
uint64_t EstimatedBytesPerImage(const CapturePlan& plan, const CameraInfo& camera);

// Bytes `captures` need, each at its real size: board views of a camera that crops to a window
// are whole-sensor frames. Before anything is captured, as uncompressed 16-bit samples (PNG never
// stores more); when `captured` holds images of the same size class, as the largest of them plus
// 10% (PNG compresses a scene about equally from one capture to the next). A 5% margin on top.
uint64_t EstimatedBytes(const std::vector<PlannedCapture>& captures, const CapturePlan& plan, const CameraInfo& camera,
                        const session::Session* captured = nullptr);

// Runs (or resumes) the acquisition into `session_folder`. Throws svbtdf::Error:
//   kInvalidInput  the folder holds a session of another plan, or dots lie off the display;
//   kIo            not enough free space (naming the folder), unwritable folder;
//   kFormat        the existing session's journal names a corrupt image;
//   kHardware      the camera failed retries + 1 times in a row (the session is resumable);
//   kInterrupted   an interrupt was requested (the session is resumable).
AcquireResult Acquire(const CapturePlan& plan, Camera& camera, Display& display, Operator& op,
                      const std::filesystem::path& session_folder, const AcquireOptions& options);

// What session.json's `rig` records for an acquisition (docs/session-format.md).
nlohmann::json AcquisitionRig(const CapturePlan& plan, const CameraInfo& camera, const DisplayInfo& display);

}  // namespace svbtdf::acquire
