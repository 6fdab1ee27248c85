#pragma once
// Radiometric calibration: dark frames, the camera response, and merging exposure brackets into
// one linear (HDR) image with masks for saturated and noise-dominated pixels.

#include <array>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace svbtdf::calib {

// The inverse camera response: camera value -> linear exposure units (one table per channel,
// indexed by the camera value). A linear camera has table[v] = v.
struct InverseResponse {
  int levels = 65536;                       // number of camera values (256 for 8-bit)
  std::vector<std::array<float, 3>> table;  // levels entries
  bool linear = true;

  static InverseResponse Linear(int levels);
  float Apply(int value, int channel) const { return table[value][channel]; }
};

// Recovers the inverse response from an 8-bit exposure stack of a static scene (Debevec and
// Malik 1997 via OpenCV, or Robertson et al. 2003). Throws svbtdf::Error(kInvalidInput) when the
// stack is not 8-bit, has fewer than 2 images or images of different sizes (naming `source`).
enum class ResponseMethod { kDebevec, kRobertson };
InverseResponse RecoverResponse(const std::vector<cv::Mat>& images, const std::vector<double>& exposures_s,
                                ResponseMethod method, const std::string& source);

struct Exposure {
  cv::Mat image;        // camera values, CV_8U or CV_16U, 1 or 3 channels
  double exposure_s = 0.0;
  double gain = 1.0;
  std::string source;   // file or capture key, for error messages
};

struct HdrOptions {
  double saturation_fraction = 0.95;  // values above this fraction of full scale are unusable
  double noise_floor = 4.0;           // values (after the dark frame) below this many counts are unusable
};

struct HdrResult {
  cv::Mat radiance;  // CV_32FC(channels): linear units per second at unit gain
  cv::Mat valid;     // CV_8U: 255 where at least one exposure was usable
  cv::Mat saturated; // CV_8U: 255 where even the shortest exposure saturated
};

// Merges the brackets: each pixel is the weighted mean of (response^-1(value) - dark) / (t * gain)
// over the exposures where it is neither saturated nor below the noise floor, with a hat weight
// favouring mid-range values. `dark` (same type as the images, or empty) is subtracted in linear
// units first. Throws svbtdf::Error naming the offending source for mismatched sizes or types and
// for non-positive exposures.
HdrResult MergeExposures(const std::vector<Exposure>& brackets, const cv::Mat& dark, const InverseResponse& response,
                         const HdrOptions& options = {});

}  // namespace svbtdf::calib
