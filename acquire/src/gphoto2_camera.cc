#include "svbtdf/acquire/gphoto2_camera.h"

#include <gphoto2/gphoto2.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "svbtdf/acquire/frame_decode.h"
#include "svbtdf/common/error.h"

namespace svbtdf::acquire {
namespace {

std::string Lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

// Parses a whole decimal number; nullopt unless `text` is exactly one.
std::optional<double> ParseNumber(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::string HintForGphotoError(int result) {
  switch (result) {
    case GP_ERROR_IO_USB_CLAIM:
      return "another process holds the camera (often gvfs-gphoto2-volume-monitor); stop it";
    case GP_ERROR_CAMERA_BUSY:
      return "the camera is busy (still writing the last image?); retry";
    case GP_ERROR_IO:
    case GP_ERROR_IO_USB_FIND:
    case GP_ERROR_MODEL_NOT_FOUND:
      return "check the USB cable and that the camera is on and not asleep";
    default:
      return "see `gphoto2 --debug` for the camera's reason";
  }
}

[[noreturn]] void ThrowGphoto(const std::string& subject, const std::string& call, int result) {
  throw common::Error(common::ErrorKind::kHardware, subject, call + " failed: " + gp_result_as_string(result),
              HintForGphotoError(result));
}

class RealGphoto2Session : public Gphoto2Session {
 public:
  explicit RealGphoto2Session(const std::string& port) {
    context_ = gp_context_new();
    CameraList* detected = nullptr;
    gp_list_new(&detected);
    const int found = gp_camera_autodetect(detected, context_);
    for (int i = 0; i < std::max(found, 0); ++i) {
      const char* name = nullptr;
      const char* path = nullptr;
      gp_list_get_name(detected, i, &name);
      gp_list_get_value(detected, i, &path);
      if (port.empty() || port == path) {
        model_ = name;
        port_ = path;
        break;
      }
    }
    gp_list_free(detected);
    if (port_.empty()) {
      gp_context_unref(context_);
      throw common::Error(common::ErrorKind::kHardware, "gphoto2:" + port,
                  port.empty() ? "no camera detected" : "no camera on this port",
                  "connect the camera by USB, switch it on, and see `svbtdf devices`");
    }
    gp_camera_new(&camera_);
    try {
      SetAbilitiesAndPort();
      Check("gp_camera_init", gp_camera_init(camera_, context_));
    } catch (...) {
      gp_camera_free(camera_);
      gp_context_unref(context_);
      throw;
    }
  }

  ~RealGphoto2Session() override {
    gp_camera_exit(camera_, context_);
    gp_camera_free(camera_);
    gp_context_unref(context_);
  }

  std::string Model() const override { return model_; }
  std::string Port() const override { return port_; }

  bool HasWidget(const std::string& name) override {
    CameraWidget* widget = nullptr;
    if (gp_camera_get_single_config(camera_, name.c_str(), &widget, context_) < GP_OK) return false;
    gp_widget_free(widget);
    return true;
  }

  std::vector<std::string> Choices(const std::string& name) override {
    CameraWidget* widget = nullptr;
    std::vector<std::string> choices;
    if (gp_camera_get_single_config(camera_, name.c_str(), &widget, context_) < GP_OK) return choices;
    CameraWidgetType type;
    gp_widget_get_type(widget, &type);
    if (type == GP_WIDGET_RADIO || type == GP_WIDGET_MENU) {
      const int count = gp_widget_count_choices(widget);
      for (int i = 0; i < count; ++i) {
        const char* choice = nullptr;
        if (gp_widget_get_choice(widget, i, &choice) == GP_OK && choice) choices.push_back(choice);
      }
    }
    gp_widget_free(widget);
    return choices;
  }

  void SetWidget(const std::string& name, const std::string& value) override {
    CameraWidget* widget = nullptr;
    Check("gp_camera_get_single_config(" + name + ")",
          gp_camera_get_single_config(camera_, name.c_str(), &widget, context_));
    const int set = gp_widget_set_value(widget, value.c_str());
    const int applied =
        set < GP_OK ? set : gp_camera_set_single_config(camera_, name.c_str(), widget, context_);
    gp_widget_free(widget);
    Check("gp_camera_set_single_config(" + name + "=" + value + ")", applied);
  }

  std::vector<Gphoto2File> CaptureAndDownload(bool delete_from_card) override {
    CameraFilePath first{};
    Check("gp_camera_capture", gp_camera_capture(camera_, GP_CAPTURE_IMAGE, &first, context_));
    std::vector<CameraFilePath> paths = {first};
    // RAW+JPEG cameras announce the second file as an event after the capture returns.
    for (;;) {
      CameraEventType type;
      void* data = nullptr;
      if (gp_camera_wait_for_event(camera_, 1000, &type, &data, context_) < GP_OK) break;
      if (type == GP_EVENT_FILE_ADDED) paths.push_back(*static_cast<CameraFilePath*>(data));
      std::free(data);
      if (type == GP_EVENT_TIMEOUT || type == GP_EVENT_CAPTURE_COMPLETE) break;
    }
    std::vector<Gphoto2File> files;
    for (const CameraFilePath& path : paths) {
      files.push_back(Download(path));
      if (delete_from_card) {
        Check("gp_camera_file_delete",
              gp_camera_file_delete(camera_, path.folder, path.name, context_));
      }
    }
    return files;
  }

 private:
  void Check(const std::string& call, int result) const {
    if (result < GP_OK) ThrowGphoto("gphoto2:" + port_, call, result);
  }

  void SetAbilitiesAndPort() {
    CameraAbilitiesList* abilities_list = nullptr;
    gp_abilities_list_new(&abilities_list);
    gp_abilities_list_load(abilities_list, context_);
    const int model_index = gp_abilities_list_lookup_model(abilities_list, model_.c_str());
    CameraAbilities abilities{};
    const int got = model_index < GP_OK ? model_index
                                        : gp_abilities_list_get_abilities(abilities_list, model_index, &abilities);
    gp_abilities_list_free(abilities_list);
    Check("gp_abilities_list_lookup_model(" + model_ + ")", got);
    Check("gp_camera_set_abilities", gp_camera_set_abilities(camera_, abilities));

    GPPortInfoList* ports = nullptr;
    gp_port_info_list_new(&ports);
    gp_port_info_list_load(ports);
    const int port_index = gp_port_info_list_lookup_path(ports, port_.c_str());
    GPPortInfo info;
    const int got_port = port_index < GP_OK ? port_index : gp_port_info_list_get_info(ports, port_index, &info);
    const int set = got_port < GP_OK ? got_port : gp_camera_set_port_info(camera_, info);
    gp_port_info_list_free(ports);
    Check("gp_camera_set_port_info(" + port_ + ")", set);
  }

  Gphoto2File Download(const CameraFilePath& path) {
    CameraFile* file = nullptr;
    gp_file_new(&file);
    const int got =
        gp_camera_file_get(camera_, path.folder, path.name, GP_FILE_TYPE_NORMAL, file, context_);
    Gphoto2File result;
    result.name = path.name;
    if (got >= GP_OK) {
      const char* data = nullptr;
      unsigned long size = 0;
      const char* mime = nullptr;
      gp_file_get_data_and_size(file, &data, &size);
      gp_file_get_mime_type(file, &mime);
      result.data.assign(data, data + size);
      result.mime = mime ? mime : "";
    }
    gp_file_free(file);
    Check(std::string("gp_camera_file_get(") + path.folder + "/" + path.name + ")", got);
    return result;
  }

  GPContext* context_ = nullptr;
  ::Camera* camera_ = nullptr;  // libgphoto2's Camera, not ours
  std::string model_, port_;
};

bool IsJpeg(const Gphoto2File& file) {
  const std::string name = Lower(file.name);
  const auto ends_with = [&](const std::string& suffix) {
    return name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  return file.mime == "image/jpeg" || ends_with(".jpg") || ends_with(".jpeg");
}

const char* const kShutterWidgets[] = {"shutterspeed", "shutterspeed2"};
const char* const kImageFormatWidgets[] = {"imageformat", "imagequality"};

}  // namespace

std::optional<double> ParseShutterSpeed(const std::string& raw_text) {
  std::string text = Lower(raw_text);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
  if (!text.empty() && text.back() == 's') text.pop_back();
  if (const size_t quote = text.find('"'); quote != std::string::npos) {
    text[quote] = '.';  // Canon writes 1.3 s as 1"3
  }
  if (const size_t slash = text.find('/'); slash != std::string::npos) {
    const auto numerator = ParseNumber(text.substr(0, slash));
    const auto denominator = ParseNumber(text.substr(slash + 1));
    if (!numerator || !denominator || *denominator <= 0.0 || *numerator <= 0.0) return std::nullopt;
    return *numerator / *denominator;
  }
  const auto value = ParseNumber(text);
  if (!value || *value <= 0.0) return std::nullopt;
  return value;
}

std::optional<double> ParseIso(const std::string& text) {
  const auto value = ParseNumber(text);
  if (!value || *value <= 0.0) return std::nullopt;
  return value;
}

int NearestInLogSpace(const std::vector<std::optional<double>>& values, double target) {
  int best = -1;
  double best_distance = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < values.size(); ++i) {
    if (!values[i]) continue;
    const double distance = std::abs(std::log(*values[i] / target));
    if (distance < best_distance) {
      best_distance = distance;
      best = static_cast<int>(i);
    }
  }
  return best;
}

std::unique_ptr<Gphoto2Session> OpenGphoto2Session(const std::string& port) {
  return std::make_unique<RealGphoto2Session>(port);
}

std::vector<CameraInfo> ListGphoto2Cameras() {
  GPContext* context = gp_context_new();
  CameraList* detected = nullptr;
  gp_list_new(&detected);
  const int found = gp_camera_autodetect(detected, context);
  std::vector<std::pair<std::string, std::string>> entries;
  for (int i = 0; i < std::max(found, 0); ++i) {
    const char* name = nullptr;
    const char* port = nullptr;
    gp_list_get_name(detected, i, &name);
    gp_list_get_value(detected, i, &port);
    entries.emplace_back(name, port);
  }
  gp_list_free(detected);
  gp_context_unref(context);
  if (found < GP_OK) ThrowGphoto("gphoto2", "gp_camera_autodetect", found);

  std::vector<CameraInfo> cameras;
  for (const auto& [name, port] : entries) {
    try {
      cameras.push_back(Gphoto2Camera(OpenGphoto2Session(port), {false, false}).Info());
    } catch (const common::Error& error) {
      CameraInfo unavailable;
      unavailable.id = "gphoto2:" + port;
      unavailable.model = name + " (cannot open: " + error.problem() + ")";
      cameras.push_back(unavailable);
    }
  }
  return cameras;
}

std::unique_ptr<Camera> OpenGphoto2Camera(const std::string& port, const Gphoto2Options& options) {
  return std::make_unique<Gphoto2Camera>(OpenGphoto2Session(port), options);
}

Gphoto2Camera::Gphoto2Camera(std::unique_ptr<Gphoto2Session> session, Gphoto2Options options)
    : session_(std::move(session)), options_(options) {
  for (const char* name : kShutterWidgets) {
    shutter_choices_ = session_->Choices(name);
    if (!shutter_choices_.empty()) {
      shutter_widget_ = name;
      break;
    }
  }
  for (const std::string& choice : shutter_choices_) shutter_values_.push_back(ParseShutterSpeed(choice));
  iso_choices_ = session_->Choices("iso");
  if (!iso_choices_.empty()) iso_widget_ = "iso";
  for (const std::string& choice : iso_choices_) {
    iso_values_.push_back(ParseIso(choice));
    if (iso_values_.back() && (base_iso_ == 0.0 || *iso_values_.back() < base_iso_)) {
      base_iso_ = *iso_values_.back();
    }
  }
  if (options_.select_jpeg) SelectJpeg();

  info_.id = Subject();
  info_.model = session_->Model();
  info_.formats.push_back("JPEG (camera-processed, not linear)");
  bool any_shutter = false;
  for (const auto& value : shutter_values_) {
    if (!value) continue;
    info_.min_exposure_s = any_shutter ? std::min(info_.min_exposure_s, *value) : *value;
    info_.max_exposure_s = any_shutter ? std::max(info_.max_exposure_s, *value) : *value;
    any_shutter = true;
  }
  const auto join = [](const std::vector<std::string>& items) {
    std::string text;
    for (const auto& item : items) text += (text.empty() ? "" : ", ") + item;
    return text;
  };
  if (!shutter_widget_.empty()) info_.controls.push_back(shutter_widget_ + " {" + join(shutter_choices_) + "}");
  if (!iso_widget_.empty()) info_.controls.push_back("iso {" + join(iso_choices_) + "}");
}

void Gphoto2Camera::SelectJpeg() {
  for (const char* widget : kImageFormatWidgets) {
    const std::vector<std::string> choices = session_->Choices(widget);
    int best = -1, best_score = -1;
    for (size_t i = 0; i < choices.size(); ++i) {
      const std::string choice = Lower(choices[i]);
      const bool raw = choice.find("raw") != std::string::npos || choice.find('+') != std::string::npos;
      const bool jpeg = choice.find("jpeg") != std::string::npos || choice.find("jpg") != std::string::npos ||
                        choice.find("fine") != std::string::npos || choice.find("normal") != std::string::npos;
      if (raw || !jpeg) continue;
      // Largest, least compressed JPEG: "Large Fine JPEG" (Canon), "JPEG Fine" (Nikon).
      const int score = (choice.find("large") != std::string::npos ? 2 : 0) +
                        (choice.find("fine") != std::string::npos ? 1 : 0);
      if (score > best_score) {
        best_score = score;
        best = static_cast<int>(i);
      }
    }
    if (best >= 0) {
      session_->SetWidget(widget, choices[best]);
      return;
    }
  }
}

void Gphoto2Camera::SetExposure(const ExposureSettings& settings) {
  if (!std::isfinite(settings.exposure_s) || settings.exposure_s <= 0.0 ||
      !std::isfinite(settings.gain) || settings.gain <= 0.0) {
    common::ThrowInvalidInput(Subject(), "exposure and gain must be positive numbers");
  }
  const int shutter = NearestInLogSpace(shutter_values_, settings.exposure_s);
  if (shutter < 0) {
    throw common::Error(common::ErrorKind::kHardware, Subject(), "lists no numeric shutter speeds",
                "set the mode dial to M (manual)");
  }
  const double third_stop = std::pow(2.0, 1.0 / 3.0);
  if (settings.exposure_s < info_.min_exposure_s / third_stop ||
      settings.exposure_s > info_.max_exposure_s * third_stop) {
    common::ThrowInvalidInput(Subject(), "exposure " + std::to_string(settings.exposure_s) +
                                     " s is outside the listed shutter speeds [" +
                                     std::to_string(info_.min_exposure_s) + ", " +
                                     std::to_string(info_.max_exposure_s) + "] s");
  }
  std::string iso_choice;
  double gain = 1.0;
  if (!iso_widget_.empty() && base_iso_ > 0.0) {
    const int iso = NearestInLogSpace(iso_values_, base_iso_ * settings.gain);
    iso_choice = iso_choices_[iso];
    gain = *iso_values_[iso] / base_iso_;
  } else if (std::abs(settings.gain - 1.0) > 1e-9) {
    common::ThrowInvalidInput(Subject(), "has no numeric ISO setting; only gain 1.0 is possible");
  }
  if (shutter_choices_[shutter] != applied_shutter_) {
    session_->SetWidget(shutter_widget_, shutter_choices_[shutter]);
    applied_shutter_ = shutter_choices_[shutter];
  }
  if (!iso_choice.empty() && iso_choice != applied_iso_) {
    session_->SetWidget(iso_widget_, iso_choice);
    applied_iso_ = iso_choice;
  }
  exposure_s_ = *shutter_values_[shutter];
  gain_ = gain;
}

Frame Gphoto2Camera::Capture() {
  if (applied_shutter_.empty()) {
    // The camera's current shutter speed is unknown to us; a frame without it is useless.
    common::ThrowInvalidInput(Subject(), "Capture() before SetExposure()", "set an exposure first");
  }
  const std::vector<Gphoto2File> files = session_->CaptureAndDownload(options_.delete_from_card);
  const auto jpeg = std::find_if(files.begin(), files.end(), IsJpeg);
  if (jpeg == files.end()) {
    std::string names;
    for (const auto& file : files) names += (names.empty() ? "" : ", ") + file.name + " (" + file.mime + ")";
    throw common::Error(common::ErrorKind::kHardware, Subject(),
                "the capture produced no JPEG, only: " + (names.empty() ? "nothing" : names),
                "svbtdf does not decode raw files; set the camera's image quality to JPEG");
  }
  Frame frame = DecodeJpeg(jpeg->data.data(), jpeg->data.size(), Subject() + "/" + jpeg->name);
  frame.exposure_s = exposure_s_;
  frame.gain = gain_;
  return frame;
}

}  // namespace svbtdf::acquire
