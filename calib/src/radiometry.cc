#include "svbtdf/calib/radiometry.h"

#include <algorithm>
#include <cmath>
#include <opencv2/photo.hpp>

#include "svbtdf/common/error.h"

namespace svbtdf::calib {

InverseResponse InverseResponse::Linear(int levels) {
  InverseResponse response;
  response.levels = levels;
  response.linear = true;
  response.table.resize(levels);
  for (int v = 0; v < levels; ++v) response.table[v] = {float(v), float(v), float(v)};
  return response;
}

InverseResponse RecoverResponse(const std::vector<cv::Mat>& images, const std::vector<double>& exposures_s,
                                ResponseMethod method, const std::string& source) {
  if (images.size() < 2 || images.size() != exposures_s.size()) {
    ThrowInvalidInput(source, "a response needs at least 2 images, each with its exposure time");
  }
  std::vector<cv::Mat> colour;
  for (const cv::Mat& image : images) {
    if (image.depth() != CV_8U) {
      ThrowInvalidInput(source, "response recovery needs 8-bit images", "16-bit raw frames are linear already");
    }
    if (image.size() != images.front().size()) ThrowInvalidInput(source, "the images differ in size");
    cv::Mat bgr;
    if (image.channels() == 1) {
      cv::Mat planes[] = {image, image, image};
      cv::merge(planes, 3, bgr);
    } else {
      bgr = image;
    }
    colour.push_back(bgr);
  }
  std::vector<float> times;
  for (double t : exposures_s) {
    if (!(t > 0)) ThrowInvalidInput(source, "exposure times must be > 0");
    times.push_back(static_cast<float>(t));
  }
  cv::Mat curve;  // 256 x 1, CV_32FC3: linear value for each 8-bit value
  if (method == ResponseMethod::kDebevec) {
    cv::createCalibrateDebevec()->process(colour, curve, times);
  } else {
    cv::createCalibrateRobertson()->process(colour, curve, times);
  }
  InverseResponse response;
  response.levels = 256;
  response.linear = false;
  response.table.resize(256);
  // Scale so that the mid-grey value maps to itself: only ratios matter downstream.
  const cv::Vec3f mid = curve.at<cv::Vec3f>(128);
  for (int v = 0; v < 256; ++v) {
    const cv::Vec3f value = curve.at<cv::Vec3f>(v);
    for (int c = 0; c < 3; ++c) response.table[v][c] = value[c] / mid[c] * 128.0f;
  }
  return response;
}

namespace {

int FullScale(const cv::Mat& image) { return image.depth() == CV_8U ? 255 : 65535; }

double CameraValue(const cv::Mat& image, int y, int x, int c) {
  const int channels = image.channels();
  return image.depth() == CV_8U ? image.ptr<uint8_t>(y)[x * channels + c] : image.ptr<uint16_t>(y)[x * channels + c];
}

}  // namespace

HdrResult MergeExposures(const std::vector<Exposure>& brackets, const cv::Mat& dark, const InverseResponse& response,
                         const HdrOptions& options) {
  if (brackets.empty()) ThrowInvalidInput("exposure brackets", "no images to merge");
  const cv::Mat& first = brackets.front().image;
  for (const Exposure& e : brackets) {
    if (e.image.empty()) ThrowInvalidInput(e.source, "empty image");
    if (e.image.size() != first.size() || e.image.type() != first.type()) {
      ThrowInvalidInput(e.source, "size or type differs from " + brackets.front().source);
    }
    if (e.image.depth() != CV_8U && e.image.depth() != CV_16U) {
      ThrowInvalidInput(e.source, "camera frames must be 8- or 16-bit integers");
    }
    if (!(e.exposure_s > 0) || !(e.gain > 0)) ThrowInvalidInput(e.source, "exposure time and gain must be > 0");
    if (FullScale(e.image) > response.levels) ThrowInvalidInput(e.source, "more camera levels than the response table has");
  }
  if (!dark.empty() && (dark.size() != first.size() || dark.type() != first.type())) {
    ThrowInvalidInput("dark frame", "size or type differs from the exposures");
  }
  const int channels = first.channels();
  const double saturation = options.saturation_fraction * FullScale(first);
  HdrResult result;
  result.radiance = cv::Mat::zeros(first.size(), CV_32FC(channels));
  result.valid = cv::Mat::zeros(first.size(), CV_8U);
  result.saturated = cv::Mat::zeros(first.size(), CV_8U);
  const double mid = 0.5 * saturation;
  for (int y = 0; y < first.rows; ++y) {
    float* out = result.radiance.ptr<float>(y);
    for (int x = 0; x < first.cols; ++x) {
      bool any_valid = false, all_saturated = true;
      for (int c = 0; c < channels; ++c) {
        double weighted = 0, weights = 0;
        for (const Exposure& e : brackets) {
          const double value = CameraValue(e.image, y, x, c);
          if (value < saturation) all_saturated = false;
          const double linear = response.Apply(static_cast<int>(value), c) -
                                (dark.empty() ? 0.0 : response.Apply(static_cast<int>(CameraValue(dark, y, x, c)), c));
          if (value >= saturation || linear < options.noise_floor) continue;
          // Hat weight on the camera value, times the exposure: longer exposures have more signal
          // for the same value, so their relative shot noise is lower.
          const double w = (1.0 - std::abs(value - mid) / mid + 1e-3) * e.exposure_s * e.gain;
          weighted += w * linear / (e.exposure_s * e.gain);
          weights += w;
        }
        if (weights > 0) {
          out[x * channels + c] = static_cast<float>(weighted / weights);
          any_valid = true;
        }
      }
      if (any_valid) result.valid.at<uint8_t>(y, x) = 255;
      if (all_saturated) result.saturated.at<uint8_t>(y, x) = 255;
    }
  }
  return result;
}

}  // namespace svbtdf::calib
