#include "svbtdf/calib/board_photos.h"

#include <algorithm>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/progress.h"

namespace svbtdf::calib {
namespace {

cv::Mat ReadGray(const std::string& file) {
  cv::Mat image = cv::imread(file, cv::IMREAD_GRAYSCALE | cv::IMREAD_ANYDEPTH);
  if (image.empty()) common::ThrowFormatError(file, "cannot be read as an image", "is it a PNG, JPEG or TIFF file?");
  if (image.depth() == CV_16U) {
    // Camera-native 16-bit files often hold fewer bits (12-bit values in 16-bit containers):
    // stretch to the image's own maximum so the detector sees the full contrast.
    double max_value = 0.0;
    cv::minMaxLoc(image, nullptr, &max_value);
    image.convertTo(image, CV_8U, 255.0 / std::max(max_value, 1.0));
  }
  return image;
}

}  // namespace

CalibrationReport CalibrateFromPhotos(const std::vector<std::string>& files, const BoardSpec& board,
                                      const CalibrationOptions& options, bool progress) {
  std::vector<BoardDetection> detections;
  cv::Size image_size;
  std::unique_ptr<common::ProgressBar> bar;
  if (progress) bar = std::make_unique<common::ProgressBar>("detecting board", static_cast<int64_t>(files.size()), "images");
  for (const std::string& file : files) {
    const cv::Mat image = ReadGray(file);
    if (image_size.empty()) image_size = image.size();
    if (image.size() != image_size) {
      common::ThrowInvalidInput(file, "is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                  " but the first image is " + std::to_string(image_size.width) + "x" +
                                  std::to_string(image_size.height),
                        "all views must come from one camera at one resolution");
    }
    detections.push_back(DetectBoard(image, board, file));
    if (bar) bar->Advance();
  }
  if (bar) bar->Finish();
  return CalibrateCamera(detections, image_size, options);
}

void WriteCameraCalibration(const std::filesystem::path& path, const BoardSpec& board, const CalibrationReport& report) {
  const nlohmann::json out = {{"format", kCameraCalibrationFormat},
                              {"version", kCameraCalibrationVersion},
                              {"board", board.ToString()},
                              {"camera", ToJson(report)}};
  common::WriteTextAtomically(path, out.dump(2) + "\n");
}

}  // namespace svbtdf::calib
