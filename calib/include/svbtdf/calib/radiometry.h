#pragma once
// Radiometry, the one room for it: the camera's linearisation (Radiometry, what calibration.json
// records), the response recovery that produces one from an exposure stack, and the one HDR merge
// (HdrAccumulator) that processing runs over texels and MergeExposures over pixels.

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace svbtdf::calib {

// The camera's radiometric chain, inverted: raw digital number -> value linear in exposure.
struct Radiometry {
  std::string response = "linear";      // "linear" | "table"
  std::vector<double> inverse_response;  // "table": relative exposure at raw = k / (size - 1) * max
  int bit_depth = 16;
  double saturation_dn = 65535.0;        // raw values at or above this are saturated
  double black_offset_dn = 0.0;          // subtracted before the response (dark frames carry the rest)

  // Linear value of a raw digital number (before dividing by the exposure time).
  double Linearize(double raw_dn) const;
  // Linearize at every code 0 .. levels - 1, for lookups in the inner loops.
  std::vector<float> LinearTable(int levels = 65536) const;
};

// Recovers the linearisation of an 8-bit camera from an exposure stack of a static scene
// (Debevec and Malik 1997 via OpenCV, or Robertson et al. 2003): response "table" with 256
// entries (the mean of the channels' curves, scaled so that code 128 maps to 128), bit depth 8.
// Throws svbtdf::Error(kInvalidInput) naming `source` when the stack is not 8-bit, has fewer than
// 2 images or images of different sizes.
enum class ResponseMethod { kDebevec, kRobertson };
Radiometry RecoverResponse(const std::vector<cv::Mat>& images, const std::vector<double>& exposures_s,
                           ResponseMethod method, const std::string& source);

// The HDR merge: per sample (a pixel or a texel) and channel, the sum of the usable brackets'
// linear, dark-subtracted values over the sum of their exposures (times gain), the
// maximum-likelihood rate under shot noise. A bracket is unusable at a sample that is saturated
// there or whose value is not finite.
class HdrAccumulator {
 public:
  HdrAccumulator(int64_t samples, int channels);
  // `values`: samples x channels values of one bracket; `saturated`: one flag per sample.
  void Add(const float* values, const uint8_t* saturated, double exposure_s);
  // samples x channels rates; NaN where no bracket was usable.
  std::vector<float> Rates() const;
  bool AnyUsable(int64_t sample) const { return exposure_[sample] > 0; }

 private:
  int64_t samples_;
  int channels_;
  std::vector<double> sum_, exposure_;
};

struct Exposure {
  cv::Mat image;        // camera values, CV_8U or CV_16U, 1 or 3 channels
  double exposure_s = 0.0;
  double gain = 1.0;
  std::string source;   // file or capture key, for error messages
};

struct HdrResult {
  cv::Mat radiance;  // CV_32FC(channels): linear units per second at unit gain
  cv::Mat valid;     // CV_8U: 255 where at least one exposure was usable
  cv::Mat saturated; // CV_8U: 255 where even the shortest exposure saturated
};

// Merges whole images with HdrAccumulator: each bracket linearised by `radiometry`, the
// linearised `dark` (same type as the images, or empty) subtracted, pixels at or above
// radiometry.saturation_dn in any channel unusable. Throws svbtdf::Error naming the offending
// source for mismatched sizes or types and for non-positive exposures or gains.
HdrResult MergeExposures(const std::vector<Exposure>& brackets, const cv::Mat& dark, const Radiometry& radiometry);

}  // namespace svbtdf::calib
