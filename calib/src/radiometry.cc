#include "svbtdf/calib/radiometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/photo.hpp>

#include "svbtdf/common/error.h"

namespace svbtdf::calib {
namespace {

int CameraValue(const cv::Mat& image, int y, int x, int c) {
  const int channels = image.channels();
  return image.depth() == CV_8U ? image.ptr<uint8_t>(y)[x * channels + c] : image.ptr<uint16_t>(y)[x * channels + c];
}

}  // namespace


Radiometry RecoverResponse(const std::vector<cv::Mat>& images, const std::vector<double>& exposures_s,
                           ResponseMethod method, const std::string& source) {
  if (images.size() < 2 || images.size() != exposures_s.size()) {
    common::ThrowInvalidInput(source, "a response needs at least 2 images, each with its exposure time");
  }
  std::vector<cv::Mat> colour;
  for (const cv::Mat& image : images) {
    if (image.depth() != CV_8U) {
      common::ThrowInvalidInput(source, "response recovery needs 8-bit images", "16-bit raw frames are linear already");
    }
    if (image.size() != images.front().size()) common::ThrowInvalidInput(source, "the images differ in size");
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
    if (!(t > 0)) common::ThrowInvalidInput(source, "exposure times must be > 0");
    times.push_back(static_cast<float>(t));
  }
  cv::Mat curve;  // 256 x 1, CV_32FC3: linear value for each 8-bit value
  if (method == ResponseMethod::kDebevec) {
    cv::createCalibrateDebevec()->process(colour, curve, times);
  } else {
    cv::createCalibrateRobertson()->process(colour, curve, times);
  }
  Radiometry radiometry;
  radiometry.response = "table";
  radiometry.bit_depth = 8;
  radiometry.saturation_dn = 255.0;
  radiometry.inverse_response.resize(256);
  // The channels' curves, each scaled so that mid-grey maps to itself (only ratios matter
  // downstream), averaged: one linearisation for the camera, as calibration.json records it.
  const cv::Vec3f mid = curve.at<cv::Vec3f>(128);
  for (int v = 0; v < 256; ++v) {
    const cv::Vec3f value = curve.at<cv::Vec3f>(v);
    double sum = 0.0;
    for (int c = 0; c < 3; ++c) sum += value[c] / mid[c] * 128.0;
    radiometry.inverse_response[v] = sum / 3.0;
  }
  return radiometry;
}

double Radiometry::Linearize(double raw_dn) const {
  const double value = raw_dn - black_offset_dn;
  if (response != "table" || inverse_response.size() < 2) return value;
  // The table samples the inverse response at evenly spaced raw values over [0, 2^bits - 1].
  const double max_dn = std::ldexp(1.0, bit_depth) - 1.0;
  const double u = std::clamp(value / max_dn, 0.0, 1.0) * (inverse_response.size() - 1);
  const size_t k = std::min(static_cast<size_t>(u), inverse_response.size() - 2);
  const double t = u - k;
  return (1 - t) * inverse_response[k] + t * inverse_response[k + 1];
}

std::vector<float> Radiometry::LinearTable(int levels) const {
  std::vector<float> table(levels);
  for (int v = 0; v < levels; ++v) table[v] = static_cast<float>(Linearize(v));
  return table;
}

HdrAccumulator::HdrAccumulator(int64_t samples, int channels)
    : samples_(samples), channels_(channels), sum_(samples * channels, 0.0), exposure_(samples, 0.0) {}

void HdrAccumulator::Add(const float* values, const uint8_t* saturated, double exposure_s) {
  for (int64_t s = 0; s < samples_; ++s) {
    const float* v = values + s * channels_;
    if (saturated[s] || !std::isfinite(v[0])) continue;
    for (int c = 0; c < channels_; ++c) sum_[s * channels_ + c] += v[c];
    exposure_[s] += exposure_s;
  }
}

std::vector<float> HdrAccumulator::Rates() const {
  std::vector<float> rates(sum_.size(), std::numeric_limits<float>::quiet_NaN());
  for (int64_t s = 0; s < samples_; ++s) {
    if (exposure_[s] <= 0) continue;
    for (int c = 0; c < channels_; ++c) rates[s * channels_ + c] = static_cast<float>(sum_[s * channels_ + c] / exposure_[s]);
  }
  return rates;
}


HdrResult MergeExposures(const std::vector<Exposure>& brackets, const cv::Mat& dark, const Radiometry& radiometry) {
  if (brackets.empty()) common::ThrowInvalidInput("exposure brackets", "no images to merge");
  const cv::Mat& first = brackets.front().image;
  for (const Exposure& e : brackets) {
    if (e.image.empty()) common::ThrowInvalidInput(e.source, "empty image");
    if (e.image.size() != first.size() || e.image.type() != first.type()) {
      common::ThrowInvalidInput(e.source, "size or type differs from " + brackets.front().source);
    }
    if (e.image.depth() != CV_8U && e.image.depth() != CV_16U) {
      common::ThrowInvalidInput(e.source, "camera frames must be 8- or 16-bit integers");
    }
    if (!(e.exposure_s > 0) || !(e.gain > 0)) common::ThrowInvalidInput(e.source, "exposure time and gain must be > 0");
  }
  if (!dark.empty() && (dark.size() != first.size() || dark.type() != first.type())) {
    common::ThrowInvalidInput("dark frame", "size or type differs from the exposures");
  }
  const int channels = first.channels();
  const int64_t pixels = static_cast<int64_t>(first.rows) * first.cols;
  const std::vector<float> table = radiometry.LinearTable(first.depth() == CV_8U ? 256 : 65536);
  HdrAccumulator merge(pixels, channels);
  // The dark frame in linear units, once for all brackets.
  std::vector<float> dark_linear(pixels * channels, 0.0f);
  if (!dark.empty()) {
    for (int64_t p = 0; p < pixels; ++p) {
      const int y = static_cast<int>(p / first.cols), x = static_cast<int>(p % first.cols);
      for (int c = 0; c < channels; ++c) dark_linear[p * channels + c] = table[CameraValue(dark, y, x, c)];
    }
  }
  std::vector<float> linear(pixels * channels);
  std::vector<uint8_t> saturated(pixels), saturated_everywhere(pixels, 1);
  for (const Exposure& e : brackets) {
    for (int64_t p = 0; p < pixels; ++p) {
      const int y = static_cast<int>(p / first.cols), x = static_cast<int>(p % first.cols);
      saturated[p] = 0;
      for (int c = 0; c < channels; ++c) {
        const int value = CameraValue(e.image, y, x, c);
        saturated[p] |= value >= radiometry.saturation_dn;
        linear[p * channels + c] = table[value] - dark_linear[p * channels + c];
      }
      saturated_everywhere[p] &= saturated[p];
    }
    merge.Add(linear.data(), saturated.data(), e.exposure_s * e.gain);
  }
  const std::vector<float> rates = merge.Rates();
  HdrResult result;
  result.radiance = cv::Mat::zeros(first.size(), CV_32FC(channels));
  result.valid = cv::Mat::zeros(first.size(), CV_8U);
  result.saturated = cv::Mat::zeros(first.size(), CV_8U);
  for (int64_t p = 0; p < pixels; ++p) {
    const int y = static_cast<int>(p / first.cols), x = static_cast<int>(p % first.cols);
    if (merge.AnyUsable(p)) {
      result.valid.at<uint8_t>(y, x) = 255;
      for (int c = 0; c < channels; ++c) result.radiance.ptr<float>(y)[x * channels + c] = rates[p * channels + c];
    }
    if (saturated_everywhere[p]) result.saturated.at<uint8_t>(y, x) = 255;
  }
  return result;
}

}  // namespace svbtdf::calib
