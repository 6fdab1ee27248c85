#include "svbtdf/process/process_session.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/common/statistics.h"
#include "svbtdf/fit/slice_store.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/polarisation.h"
#include "svbtdf/process/slice_store_writer.h"
#include "svbtdf/session/capture_key.h"

namespace svbtdf::process {
namespace fs = std::filesystem;
using fit::SliceStore;
using fit::SliceStoreInfo;
using fit::TexelGeometry;
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// The captures the processing reads, from the session's plan (docs/session-format.md).
struct CapturePlan {
  std::map<int, std::vector<std::string>> dark_keys;  // bracket -> repeats
  std::string flat_key;
  std::vector<std::vector<std::pair<int, std::string>>> dot_keys;  // dot -> (bracket, key)
};

CapturePlan ParsePlan(const session::Session& session, int num_dots) {
  CapturePlan plan;
  plan.dot_keys.resize(num_dots);
  for (const std::string& key : session.planned_keys()) {
    const std::optional<session::CaptureKey> capture = session::CaptureKey::Parse(key);
    if (!capture) continue;
    if (capture->kind == session::CaptureKind::kDot) {
      if (capture->dot >= num_dots) {
        common::ThrowInvalidInput(session.folder().string(), "plans dot " + std::to_string(capture->dot) + " but the calibration has " +
                                                         std::to_string(num_dots) + " dots",
                          "re-run 'svbtdf calibrate' on this session");
      }
      plan.dot_keys[capture->dot].push_back({capture->bracket, key});
    } else if (capture->kind == session::CaptureKind::kDark) {
      plan.dark_keys[capture->bracket].push_back(key);
    } else if (capture->kind == session::CaptureKind::kFlatWhite && plan.flat_key.empty()) {
      plan.flat_key = key;
    }
  }
  if (plan.flat_key.empty()) {
    common::ThrowInvalidInput(session.folder().string(), "plans no flat_white capture", "the dots' intensity L_q is measured from it");
  }
  for (int q = 0; q < num_dots; ++q) {
    if (plan.dot_keys[q].empty()) common::ThrowInvalidInput(session.folder().string(), "plans no image of dot " + std::to_string(q));
  }
  return plan;
}

// The rectification: each texel's value is the mean of k x k points inset in the texel, each
// interpolated bilinearly in the image, so pixels straddling a texel edge barely contribute.
// A point is kept as its 2 x 2 pixel block and its position in it (12 bytes rather than four
// 12-byte taps): the rectification of every image streams these points, and at paper scale
// (360,000 texels, 9 points each) their size set its speed.
class Rectifier {
 public:
  Rectifier(const calib::SessionCalibration& calibration, const TexelGeometry& geometry, int samples)
      : points_per_texel_(samples * samples) {
    const int64_t texels = geometry.num_texels();
    const double pitch_x = geometry.width_m / geometry.texels_x, pitch_y = geometry.height_m / geometry.texels_y;
    std::vector<model::Vec3> points;
    points.reserve(texels * points_per_texel_);
    for (int64_t t = 0; t < texels; ++t) {
      const model::Vec3 centre = geometry.TexelCentre(t);
      for (int a = 0; a < samples; ++a) {
        for (int b = 0; b < samples; ++b) {
          // Points at 0.2 .. 0.8 of the texel: at least a fifth of a texel from its edges.
          const double u = samples == 1 ? 0.0 : -0.3 + 0.6 * a / (samples - 1);
          const double v = samples == 1 ? 0.0 : -0.3 + 0.6 * b / (samples - 1);
          points.push_back(centre + model::Vec3(u * pitch_x, v * pitch_y, 0.0));
        }
      }
    }
    const std::vector<Eigen::Vector2d> image = ProjectToImage(calibration, points);
    width_ = calibration.camera.camera.width;
    height_ = calibration.camera.camera.height;
    covered_.assign(texels, 0);
    points_.resize(image.size());
    for (int64_t t = 0; t < texels; ++t) {
      bool inside = true;
      for (int s = 0; s < points_per_texel_ && inside; ++s) {
        const Eigen::Vector2d& p = image[t * points_per_texel_ + s];
        inside = p.x() >= 0 && p.y() >= 0 && p.x() <= width_ - 1 && p.y() <= height_ - 1;
      }
      if (!inside) continue;
      covered_[t] = 1;
      for (int s = 0; s < points_per_texel_; ++s) points_[t * points_per_texel_ + s] = BilinearPoint(image[t * points_per_texel_ + s]);
    }
  }

  int64_t texels() const { return static_cast<int64_t>(covered_.size()); }
  bool Covers(int64_t texel) const { return covered_[texel] != 0; }

  // out[3 t + c] = rectified linear value; saturated[t] when any pixel with a non-zero weight in
  // one of the texel's points is saturated. A grey image gives c = 0, 1, 2 the same value.
  void Apply(const std::vector<float>& linear, const std::vector<uint8_t>& saturated_pixel, int channels, int threads,
             std::vector<float>* out, std::vector<uint8_t>* saturated) const {
    out->assign(3 * texels(), kNaN);
    saturated->assign(texels(), 0);
    // The first three channels of colour images (an alpha channel is ignored), the first of others.
    if (channels >= 3) {
      ApplyTo<3>(linear, saturated_pixel, channels, threads, out, saturated);
    } else {
      ApplyTo<1>(linear, saturated_pixel, channels, threads, out, saturated);
    }
  }

 private:
  // The top-left pixel of a point's 2 x 2 block and the point's position in it.
  struct BilinearPointTaps {
    int32_t pixel;  // y0 * width + x0; images are at most kMaxSamples pixels (image_io), so it fits
    float fx, fy;
  };

  BilinearPointTaps BilinearPoint(const Eigen::Vector2d& p) const {
    const int x0 = std::min(static_cast<int>(p.x()), width_ - 2), y0 = std::min(static_cast<int>(p.y()), height_ - 2);
    return {static_cast<int32_t>(y0 * width_ + x0), static_cast<float>(p.x() - x0), static_cast<float>(p.y() - y0)};
  }

  template <int Channels>
  void ApplyTo(const std::vector<float>& linear, const std::vector<uint8_t>& saturated_pixel, int stride, int threads,
               std::vector<float>* out, std::vector<uint8_t>* saturated) const {
    const float weight = 1.0f / static_cast<float>(points_per_texel_);
    const int64_t row = width_;
    common::ParallelFor(texels(), threads, 4096, [&](int64_t a, int64_t b) {
      for (int64_t t = a; t < b; ++t) {
        if (!Covers(t)) continue;
        float sum[Channels] = {};
        uint8_t any_saturated = 0;
        for (int s = 0; s < points_per_texel_; ++s) {
          const BilinearPointTaps& point = points_[t * points_per_texel_ + s];
          const int64_t corner[4] = {point.pixel, point.pixel + 1, point.pixel + row, point.pixel + row + 1};
          const float w[4] = {(1 - point.fx) * (1 - point.fy), point.fx * (1 - point.fy), (1 - point.fx) * point.fy,
                              point.fx * point.fy};
          for (int k = 0; k < 4; ++k) {
            // Without a branch: the block lies inside the image, and its values are finite. A
            // point on a pixel's edge does not reach past it, nor does its saturation.
            any_saturated |= static_cast<uint8_t>(w[k] > 0) & saturated_pixel[corner[k]];
            for (int c = 0; c < Channels; ++c) sum[c] += w[k] * linear[corner[k] * stride + c];
          }
        }
        for (int c = 0; c < 3; ++c) (*out)[3 * t + c] = weight * sum[std::min(c, Channels - 1)];
        (*saturated)[t] = any_saturated;
      }
    });
  }

  int width_ = 0, height_ = 0;
  int points_per_texel_ = 1;
  std::vector<uint8_t> covered_;
  std::vector<BilinearPointTaps> points_;  // points_per_texel_ a texel, row-major over texels
};

// Reads session images and turns them into linear values (dark-subtracted) with saturation flags.
class ImageReader {
 public:
  ImageReader(const session::Session& session, const calib::SessionCalibration& calibration)
      : session_(session), calibration_(calibration), table_(calibration.radiometry.LinearTable()) {}

  struct Linear {
    std::vector<float> values;
    std::vector<uint8_t> saturated;
    int channels = 1;
    double exposure_s = 0.0;
  };

  Linear Read(const std::string& key, const std::vector<float>* dark) {
    const common::CameraImage image = session_.ReadImage(key);
    const calib::CameraModel& camera = calibration_.camera.camera;
    const std::string file = (session_.folder() / session_.Entry(key).file).string();
    if (image.width != camera.width || image.height != camera.height) {
      common::ThrowFormatError(file, "is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                 " pixels but the calibrated camera is " + std::to_string(camera.width) + "x" +
                                 std::to_string(camera.height));
    }
    Linear out;
    out.channels = image.channels;
    out.exposure_s = session_.Entry(key).exposure_s;
    if (!(out.exposure_s > 0) || !std::isfinite(out.exposure_s)) {
      common::ThrowFormatError((session_.folder() / "journal.jsonl").string(), "records no positive exposure for '" + key + "'");
    }
    const size_t values = image.pixels.size();
    if (dark && dark->size() != values) common::ThrowFormatError(file, "has a different number of channels than its dark frame");
    out.values.resize(values);
    out.saturated.assign(static_cast<size_t>(image.width) * image.height, 0);
    const double saturation = calibration_.radiometry.saturation_dn;
    for (size_t k = 0; k < values; ++k) {
      const uint16_t raw = image.pixels[k];
      out.values[k] = table_[raw] - (dark ? (*dark)[k] : 0.0f);
      if (raw >= saturation) out.saturated[k / image.channels] = 1;
    }
    ++images_read_;
    return out;
  }

  // The mean linear dark frame of one bracket (the response already removes the black offset).
  std::vector<float> MeanDark(const std::vector<std::string>& keys) {
    std::vector<float> mean;
    for (const std::string& key : keys) {
      const Linear dark = Read(key, nullptr);
      if (mean.empty()) mean.assign(dark.values.size(), 0.0f);
      if (dark.values.size() != mean.size()) {
        common::ThrowFormatError((session_.folder() / session_.Entry(key).file).string(), "differs in size from the other dark frames");
      }
      for (size_t k = 0; k < mean.size(); ++k) mean[k] += dark.values[k] / keys.size();
    }
    return mean;
  }

  int64_t images_read() const { return images_read_; }

 private:
  const session::Session& session_;
  const calib::SessionCalibration& calibration_;
  std::vector<float> table_;
  std::atomic<int64_t> images_read_{0};
};

// Reads the dot images in plan order ahead of their use, `depth` of them decoding at once, each
// on its own thread, while the current one is rectified. Decoding a PNG runs on one thread and
// is most of the work: with one image ahead, the dots of a paper-scale session went at the pace
// of one decoding thread and a second core stood idle a third of the time (docs/benchmarks.md,
// "process"). Read errors surface from Next(), in plan order.
class ReadAhead {
 public:
  ReadAhead(ImageReader& reader, const std::map<int, std::vector<float>>& darks,
            std::vector<std::pair<int, std::string>> order, int depth)
      : reader_(reader), darks_(darks), order_(std::move(order)), depth_(std::max(1, depth)) {}

  ImageReader::Linear Next() {
    Refill();
    if (pending_.empty()) throw std::logic_error("ReadAhead::Next past the last image");
    ImageReader::Linear image = pending_.front().get();
    pending_.pop_front();
    Refill();
    return image;
  }

 private:
  void Refill() {
    while (static_cast<int>(pending_.size()) < depth_ && started_ < order_.size()) {
      pending_.push_back(std::async(std::launch::async, [this, k = started_++] {
        const auto& [bracket, key] = order_[k];
        const auto dark = darks_.find(bracket);
        return reader_.Read(key, dark == darks_.end() ? nullptr : &dark->second);
      }));
    }
  }

  ImageReader& reader_;
  const std::map<int, std::vector<float>>& darks_;
  std::vector<std::pair<int, std::string>> order_;  // (bracket, key)
  int depth_;
  size_t started_ = 0;
  std::deque<std::future<ImageReader::Linear>> pending_;
};

void ResolveTexelGrid(const session::Session& session, const calib::SessionCalibration& calibration, ProcessOptions* options) {
  if (options->texels_x > 0 && options->texels_y > 0) return;
  const session::RigSample& sample = session.rig().sample;
  if (sample.texels_x > 0 && sample.texels_y > 0) {
    options->texels_x = sample.texels_x;
    options->texels_y = sample.texels_y;
    return;
  }
  // About two camera pixels per texel along the sample's wider side.
  const double w = calibration.sample_plane.width_m, h = calibration.sample_plane.height_m;
  const std::vector<Eigen::Vector2d> corners =
      ProjectToImage(calibration, {model::Vec3(-w / 2, 0, 0), model::Vec3(w / 2, 0, 0)});
  const double pixels = (corners[1] - corners[0]).norm();
  options->texels_x = std::max(1, static_cast<int>(pixels / 2));
  options->texels_y = std::max(1, static_cast<int>(std::lround(options->texels_x * h / w)));
}

// Per texel and channel, the monitor's white exitance times the camera's sensitivity and
// vignetting at the pixels that see the texel, from the flat white image (sample removed):
// a monitor point seen directly has radiance exitance * P(theta_e) / cos(theta_e).
std::vector<float> WhiteExitance(ImageReader& reader, const std::string& flat_key, const Rectifier& rectifier,
                                 const TexelGeometry& geometry, const calib::MonitorCalibration& monitor,
                                 int threads) {
  const ImageReader::Linear flat = reader.Read(flat_key, nullptr);
  std::vector<float> exitance;
  std::vector<uint8_t> saturated;
  rectifier.Apply(flat.values, flat.saturated, flat.channels, threads, &exitance, &saturated);
  for (int64_t t = 0; t < geometry.num_texels(); ++t) {
    const double cos_e = std::max(1e-6, geometry.View(t).dot(monitor.normal));
    const double scale = cos_e / (flat.exposure_s * monitor.Emission(cos_e));
    for (int c = 0; c < 3; ++c) {
      float& e = exitance[3 * t + c];
      e = saturated[t] || !(e > 0) ? kNaN : static_cast<float>(e * scale);
    }
  }
  return exitance;
}

// One dot's HDR values per texel: its brackets rectified, then merged by calibration's HDR merge.
std::vector<float> MergeBrackets(ReadAhead& images, int brackets, const Rectifier& rectifier, int threads) {
  calib::HdrAccumulator merge(rectifier.texels(), 3);
  std::vector<float> rectified;
  std::vector<uint8_t> saturated;
  for (int b = 0; b < brackets; ++b) {
    const ImageReader::Linear image = images.Next();
    rectifier.Apply(image.values, image.saturated, image.channels, threads, &rectified, &saturated);
    merge.Add(rectified.data(), saturated.data(), image.exposure_s);
  }
  return merge.Rates();
}

// A linearly polarised screen (docs/capture.md, "A polarised monitor"): the slab transmits the
// dot's light with its polarised Fresnel factors, not the unpolarised ones the model assumes.
// The correction divides each sample by the ratio of the two for the model's configurations,
// each with its own facet (model::DualMicrofacetModel's `field`), blended with alpha = 1/2 in
// log space as the model blends them (the texel's alpha is not known before the fit; the
// configurations' ratios agree near the lobe's peak, where the samples carry most weight).
class PolarisationCorrection {
 public:
  PolarisationCorrection(const session::PolarisationNote& note, const calib::MonitorCalibration& monitor, double eta)
      : linear_(note.linear), model_(eta > 1.0 ? eta : 1.5) {
    if (!linear_) return;
    const model::Vec3 n = monitor.normal.normalized();
    const double o = monitor.orientation_deg * model::kPi / 180.0;
    const model::Vec3 u0(std::cos(o), std::sin(o), 0.0);
    const model::Vec3 right = (u0 - u0.dot(n) * n).normalized();
    const model::Vec3 up = n.cross(right);  // -down: a physical screen has right x down = -normal
    const double a = note.angle_deg * model::kPi / 180.0;
    field_ = std::cos(a) * right + std::sin(a) * up;
  }
  bool linear() const { return linear_; }
  // Measured R over the unpolarised R of the same texel (to first order in alpha's spread).
  double Ratio(const model::Vec3& i, const model::Vec3& o) const {
    const model::Vec3 field = model::TransverseField(field_, -i);
    double log_sum = 0.0;
    int terms = 0;
    for (int config = 0; config < 2; ++config) {
      const model::VirtualConfiguration plain = config ? model_.RoughExit(i, o) : model_.RoughEntry(i, o);
      if (!plain.valid || !(plain.factor > 0)) continue;
      const model::VirtualConfiguration polarised = config ? model_.RoughExit(i, o, &field) : model_.RoughEntry(i, o, &field);
      if (!(polarised.factor > 0)) continue;
      log_sum += std::log(polarised.factor / plain.factor);
      ++terms;
    }
    return terms > 0 ? std::exp(log_sum / terms) : 1.0;
  }

 private:
  bool linear_;
  model::DualMicrofacetModel model_;
  model::Vec3 field_ = model::Vec3::Zero();
};

// The measurement equation (notes, "Measurement to BTDF"): R = I |p - x|^2 / (|i.z| L_q P(theta_q)),
// with L_q = exitance * pi r^2 in the same camera units as I.
void ToBtdf(const TexelGeometry& geometry, const calib::MonitorCalibration& monitor, int dot,
            const std::vector<float>& exitance, const PolarisationCorrection& polarisation,
            std::vector<float>* values) {
  const double dot_area = std::numbers::pi * monitor.dot_radius_m * monitor.dot_radius_m;
  for (int64_t t = 0; t < geometry.num_texels(); ++t) {
    const model::Vec3 to_dot = geometry.dots[dot] - geometry.TexelCentre(t);
    const double r2 = to_dot.squaredNorm();
    const model::Vec3 i = to_dot / std::sqrt(r2);
    double emission = monitor.Emission(-i.dot(monitor.normal));
    if (polarisation.linear()) emission *= polarisation.Ratio(i, geometry.View(t));
    for (int c = 0; c < 3; ++c) {
      const double l_q = exitance[3 * t + c] * dot_area * emission;
      float& v = (*values)[3 * t + c];
      v = std::isfinite(v) && l_q > 0 ? static_cast<float>(v * r2 / (std::abs(i.z()) * l_q)) : kNaN;
    }
  }
}

std::string Gigabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f GB", bytes / 1e9);
  return text;
}

// A typo (--texels 99999x99999, --light-resolution 4096) must be refused by name before the
// store is sized, not end in "out of memory" or a full disk hours later.
void RequireSaneSizes(const ProcessOptions& options, int num_dots, const fs::path& out) {
  if (options.texels_x > session::kMaxTexelsPerSide || options.texels_y > session::kMaxTexelsPerSide) {
    common::ThrowInvalidInput("--texels", std::to_string(options.texels_x) + "x" + std::to_string(options.texels_y) +
                                              " texels: at most " + std::to_string(session::kMaxTexelsPerSide) +
                                              " on a side");
  }
  const int resolution = options.light_resolution;
  if (resolution < 2 || resolution > 128 || (resolution & (resolution - 1)) != 0) {
    common::ThrowInvalidInput("--light-resolution", "must be a power of two from 2 to 128, got " + std::to_string(resolution));
  }
  if (fs::exists(out) && !fs::is_empty(out)) return;  // a resume: the store's files hold their space already
  const double texels = static_cast<double>(options.texels_x) * options.texels_y;
  const double store_bytes = texels * (3.0 * num_dots + 5.0 * resolution * resolution) * 2.0;
  const uint64_t available = common::FreeSpaceAt(out);
  if (store_bytes > static_cast<double>(available)) {
    common::ThrowIoError(out.string(), "the slice store of " + std::to_string(options.texels_x) + "x" +
                                           std::to_string(options.texels_y) + " texels, " + std::to_string(num_dots) +
                                           " dots and light resolution " + std::to_string(resolution) + " needs " +
                                           Gigabytes(store_bytes) + "; " + Gigabytes(available) + " are free",
                         "choose fewer --texels, a lower --light-resolution, or another disk");
  }
}

// What a rerun of a finished processing reports: the store as it is, nothing read or written.
ProcessReport FinishedReport(const fs::path& out, int num_dots, std::chrono::steady_clock::time_point start) {
  const SliceStore store = SliceStore::Open(out);
  ProcessReport report;
  report.already_complete = true;
  report.texels = static_cast<int64_t>(store.mask().pixels.size());
  for (float m : store.mask().pixels) report.valid_texels += m > 0;
  report.dots = report.dots_resumed = num_dots;
  report.white_exitance_noise = store.info().white_exitance_noise;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace

std::array<double, 3> WhiteExitanceNoise(const std::vector<float>& exitance, int texels_x, int texels_y) {
  constexpr size_t kMinTriples = 16;
  const auto log_at = [&](int x, int y, int c) {
    const float e = exitance[(static_cast<size_t>(y) * texels_x + x) * 3 + c];
    return e > 0 && std::isfinite(e) ? std::log(static_cast<double>(e)) : kNaN;
  };
  std::array<double, 3> noise = {0.0, 0.0, 0.0};
  std::vector<double> deviations;
  for (int c = 0; c < 3; ++c) {
    deviations.clear();
    const auto add = [&](double a, double t, double b) {
      if (std::isfinite(a) && std::isfinite(t) && std::isfinite(b)) deviations.push_back(std::abs(t - 0.5 * (a + b)));
    };
    for (int y = 0; y < texels_y; ++y) {
      for (int x = 0; x < texels_x; ++x) {
        if (x > 0 && x + 1 < texels_x) add(log_at(x - 1, y, c), log_at(x, y, c), log_at(x + 1, y, c));
        if (y > 0 && y + 1 < texels_y) add(log_at(x, y - 1, c), log_at(x, y, c), log_at(x, y + 1, c));
      }
    }
    if (deviations.size() >= kMinTriples) noise[c] = common::Median(deviations) / 0.6745 / std::sqrt(1.5);
  }
  return noise;
}

ProcessReport ProcessSession(const session::Session& session, const calib::SessionCalibration& given,
                             const fs::path& out, const ProcessOptions& requested) {
  const auto start = std::chrono::steady_clock::now();
  ProcessOptions options = requested;
  calib::SessionCalibration calibration = given;
  if (options.emission) calibration.monitor.emission = *options.emission;
  ResolveTexelGrid(session, calibration, &options);
  const int num_dots = static_cast<int>(calibration.monitor.dots.size());
  const CapturePlan plan = ParsePlan(session, num_dots);
  RequireSaneSizes(options, num_dots, out);

  SliceStoreInfo info;
  info.texels_x = options.texels_x;
  info.texels_y = options.texels_y;
  info.num_dots = num_dots;
  info.light_resolution = options.light_resolution;
  info.tile_texels = options.tile_texels;
  info.eta = session.rig().sample.eta;
  info.provenance = {{"session", fs::absolute(session.folder()).string()},
                     {"rectify_samples", options.rectify_samples},
                     {"diffuse_threshold", options.diffuse_threshold}};
  const std::string polarisation_spec = options.polarisation ? *options.polarisation : session.rig().monitor.polarisation;
  const session::PolarisationNote polarisation_note = session::ParsePolarisationNote(
      polarisation_spec, options.polarisation ? "--monitor-polarisation" : "session.json rig.monitor.polarisation");
  if (polarisation_note.linear) {
    if (!(info.eta > 1.0)) {
      common::ThrowInvalidInput("session.json rig.sample.eta", "is needed to correct for the monitor's polarisation",
                                "note the sample's eta, or process with --monitor-polarisation none");
    }
    info.provenance["polarisation_corrected"] = polarisation_spec;  // only when corrected: stores stay as they were
  }
  SliceStoreWriter writer(out, info, calibration);
  if (writer.finished()) return FinishedReport(out, num_dots, start);
  const TexelGeometry geometry = MakeTexelGeometry(calibration, info.texels_x, info.texels_y);
  const Rectifier rectifier(calibration, geometry, options.rectify_samples);
  const PolarisationCorrection polarisation(polarisation_note, calibration.monitor, info.eta);

  ImageReader reader(session, calibration);
  std::map<int, std::vector<float>> darks;
  for (const auto& [bracket, keys] : plan.dark_keys) darks[bracket] = reader.MeanDark(keys);
  const std::vector<float> exitance =
      WhiteExitance(reader, plan.flat_key, rectifier, geometry, calibration.monitor, options.threads);
  const std::array<double, 3> exitance_noise = WhiteExitanceNoise(exitance, geometry.texels_x, geometry.texels_y);

  std::vector<std::pair<int, std::string>> order;
  for (int q = 0; q < num_dots; ++q) {
    if (!writer.HasDot(q)) order.insert(order.end(), plan.dot_keys[q].begin(), plan.dot_keys[q].end());
  }
  // As many images decoding as there are threads: two on a 2-core machine.
  ReadAhead images(reader, darks, std::move(order), common::ThreadCount(options.threads));
  ProcessReport report;
  std::unique_ptr<common::ProgressBar> progress;
  if (options.progress) progress = std::make_unique<common::ProgressBar>("process", num_dots, "dots");
  for (int q = 0; q < num_dots; ++q) {
    if (writer.HasDot(q)) {
      ++report.dots_resumed;
      if (progress) progress->SkipAlreadyDone(1);
      continue;
    }
    common::ThrowIfInterrupted("processing");
    std::vector<float> values =
        MergeBrackets(images, static_cast<int>(plan.dot_keys[q].size()), rectifier, options.threads);
    ToBtdf(geometry, calibration.monitor, q, exitance, polarisation, &values);
    writer.WriteDot(q, values);
    if (progress) progress->Advance();
  }
  if (progress) progress->Finish();
  SliceStoreWriter::FinishOptions finish;
  finish.diffuse_threshold = options.diffuse_threshold;
  finish.white_exitance_noise = exitance_noise;
  finish.threads = options.threads;
  finish.progress = options.progress;
  if (polarisation.linear()) {
    finish.polarisation_ratio = [&](const model::Vec3& light, int64_t texel) { return polarisation.Ratio(light, geometry.View(texel)); };
  }
  writer.Finish(finish);

  const SliceStore store = SliceStore::Open(out);
  report.texels = geometry.num_texels();
  for (float m : store.mask().pixels) report.valid_texels += m > 0;
  report.dots = num_dots;
  report.images_read = reader.images_read();
  report.white_exitance_noise = store.info().white_exitance_noise;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace svbtdf::process
