#include "svbtdf/render/renderer.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/common/random.h"

namespace svbtdf::render {

Camera::Camera(const CameraOptions& options) : width_(options.width), height_(options.height) {
  if (!(options.theta_deg >= 0 && options.theta_deg < 90)) {
    common::ThrowInvalidInput("--view-deg", "theta " + std::to_string(options.theta_deg) +
                                                " is not in front of the sample: give 0 <= theta < 90 degrees from its normal");
  }
  if (!std::isfinite(options.phi_deg)) common::ThrowInvalidInput("--view-deg", "phi must be finite");
  if (!(options.distance_m > 0 && std::isfinite(options.distance_m))) {
    common::ThrowInvalidInput("--distance", "must be a positive distance in metres");
  }
  if (!(options.fov_deg > 0 && options.fov_deg < 170)) common::ThrowInvalidInput("--fov-deg", "must lie in (0, 170) degrees");
  if (options.width <= 0 || options.height <= 0 || options.width > 16384 || options.height > 16384) {
    common::ThrowInvalidInput("--resolution", "must be between 1 and 16384 pixels on each side");
  }
  const double theta = options.theta_deg * model::kPi / 180, phi = options.phi_deg * model::kPi / 180;
  const model::Vec3 towards_camera(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
  eye_ = options.distance_m * towards_camera;
  forward_ = -towards_camera;
  // theta < 90 keeps forward away from +y, so the sample's +y always has an upward component.
  right_ = forward_.cross(model::Vec3::UnitY()).normalized();
  up_ = right_.cross(forward_);
  tan_half_fov_ = std::tan(0.5 * options.fov_deg * model::kPi / 180);
}

model::Vec3 Camera::Direction(double x, double y) const {
  const double sx = (2 * x / width_ - 1) * tan_half_fov_;
  const double sy = (1 - 2 * y / height_) * tan_half_fov_ * height_ / width_;
  return (forward_ + sx * right_ + sy * up_).normalized();
}

model::Rgb TraceCameraRay(const Surface& surface, const Scene& scene, const model::Vec3& origin,
                          const model::Vec3& direction, double u_lobe, const model::Vec2& u, BsdfScratch& scratch) {
  if (direction.z() < 0) {
    const double t = -origin.z() / direction.z();
    const model::Vec3 p = origin + t * direction;
    const double w = surface.width_m(), h = surface.height_m();
    if (std::abs(p.x()) <= 0.5 * w && std::abs(p.y()) <= 0.5 * h) {
      const int col = std::clamp(static_cast<int>((p.x() + 0.5 * w) / w * surface.texels_x()), 0, surface.texels_x() - 1);
      const int row = std::clamp(static_cast<int>((0.5 * h - p.y()) / h * surface.texels_y()), 0, surface.texels_y() - 1);
      const model::Bsdf& bsdf = surface.At(col, row, scratch);
      const std::optional<model::BsdfSample> s = bsdf.Sample(-direction, u_lobe, u);
      if (!s) return {0, 0, 0};
      const model::Rgb behind = scene.Radiance(p, s->wi);
      return {s->weight[0] * behind[0], s->weight[1] * behind[1], s->weight[2] * behind[2]};
    }
  }
  return scene.Radiance(origin, direction);
}

common::FloatImage Render(const Surface& surface, const Scene& scene, const RenderOptions& options) {
  const Camera camera(options.camera);
  if (options.samples_per_pixel <= 0 || options.samples_per_pixel > 1 << 20) {
    common::ThrowInvalidInput("--spp", "must be between 1 and 1048576 samples per pixel");
  }
  const int width = camera.width(), height = camera.height();
  common::FloatImage image(width, height, 3);
  std::optional<common::ProgressBar> progress;
  if (options.progress) progress.emplace("rendering", static_cast<int64_t>(width) * height, "pixels");
  common::ParallelFor(height, options.threads, 1, [&](int64_t begin, int64_t end) {
    BsdfScratch scratch;
    for (int64_t y = begin; y < end; ++y) {
      common::ThrowIfInterrupted("rendering");
      for (int x = 0; x < width; ++x) {
        common::Pcg32 rng(options.seed, static_cast<uint64_t>(y) * width + x);
        double sum[3] = {0, 0, 0};
        for (int s = 0; s < options.samples_per_pixel; ++s) {
          const double jx = rng.NextDouble(), jy = rng.NextDouble();
          const double u_lobe = rng.NextDouble(), u0 = rng.NextDouble(), u1 = rng.NextDouble();
          const model::Rgb value =
              TraceCameraRay(surface, scene, camera.eye(), camera.Direction(x + jx, y + jy), u_lobe, {u0, u1}, scratch);
          for (int c = 0; c < 3; ++c) sum[c] += value[c];
        }
        for (int c = 0; c < 3; ++c) image.at(x, static_cast<int>(y), c) = static_cast<float>(sum[c] / options.samples_per_pixel);
      }
      if (progress) progress->Advance(width);
    }
  });
  return image;
}

}  // namespace svbtdf::render
