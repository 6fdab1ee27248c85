#pragma once
// libgphoto2 driver for tethered still cameras (the paper's rig used a Canon EOS 30D).
// Exposure is the nearest shutter speed the camera lists; gain is ISO / base ISO. Each capture
// is downloaded and decoded from the camera's JPEG: svbtdf does not decode raw files (CR2, NEF),
// so the driver switches the image format to a JPEG setting when the camera offers one, and
// fails with a clear message when a capture produces only a raw file. Note that the JPEG is
// tone-mapped (Frame::linear = false); a radiometric response calibration is then required.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "svbtdf/acquire/camera.h"

namespace svbtdf::acquire {

struct Gphoto2File {
  std::string name;  // e.g. "IMG_0001.JPG"
  std::string mime;  // e.g. "image/jpeg", "image/x-canon-cr2"
  std::vector<uint8_t> data;
};

// The thin seam over one opened libgphoto2 camera. Methods throw Error(kHardware).
class Gphoto2Session {
 public:
  virtual ~Gphoto2Session() = default;
  virtual std::string Model() const = 0;
  virtual std::string Port() const = 0;
  virtual bool HasWidget(const std::string& name) = 0;
  // The choices of a radio / menu configuration widget; empty when it has none.
  virtual std::vector<std::string> Choices(const std::string& name) = 0;
  virtual void SetWidget(const std::string& name, const std::string& value) = 0;
  // Triggers one capture and downloads every file it produced (RAW+JPEG gives two).
  virtual std::vector<Gphoto2File> CaptureAndDownload(bool delete_from_card) = 0;
};

// Opens the camera on `port` (e.g. "usb:001,007"); an empty port takes the first camera found.
std::unique_ptr<Gphoto2Session> OpenGphoto2Session(const std::string& port);

struct Gphoto2Options {
  bool delete_from_card = true;  // the paper's sessions take thousands of shots
  bool select_jpeg = true;       // switch imageformat / imagequality to a JPEG setting
};

// "1/250", "0.3", "30", "2.5s", "1\"3" (Canon's 1.3 s), "10/10" -> seconds; "bulb" -> nullopt.
std::optional<double> ParseShutterSpeed(const std::string& text);
// "100" -> 100; "Auto" / "Auto ISO" -> nullopt.
std::optional<double> ParseIso(const std::string& text);
// The index of the numerically parsed choice nearest to `target` in log space, or -1.
int NearestInLogSpace(const std::vector<std::optional<double>>& values, double target);

std::vector<CameraInfo> ListGphoto2Cameras();
std::unique_ptr<Camera> OpenGphoto2Camera(const std::string& port,
                                          const Gphoto2Options& options = {});

class Gphoto2Camera : public Camera {
 public:
  Gphoto2Camera(std::unique_ptr<Gphoto2Session> session, Gphoto2Options options = {});

  CameraInfo Info() const override { return info_; }
  // Picks the listed shutter speed nearest in log space (rejecting requests more than a third
  // of a stop outside the listed range) and the ISO nearest to base ISO x gain. The frame
  // reports the chosen values, not the requested ones.
  void SetExposure(const ExposureSettings& settings) override;
  Frame Capture() override;

 private:
  std::string Subject() const { return "gphoto2:" + session_->Port(); }
  void SelectJpeg();

  std::unique_ptr<Gphoto2Session> session_;
  Gphoto2Options options_;
  CameraInfo info_;
  std::string shutter_widget_, iso_widget_;
  std::vector<std::string> shutter_choices_, iso_choices_;
  std::vector<std::optional<double>> shutter_values_, iso_values_;
  double base_iso_ = 0.0;
  std::string applied_shutter_, applied_iso_;
  double exposure_s_ = 0.0, gain_ = 1.0;
};

}  // namespace svbtdf::acquire
