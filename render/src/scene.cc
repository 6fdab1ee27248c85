#include "svbtdf/render/scene.h"

#include <algorithm>
#include <cmath>

#include "svbtdf/common/error.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::render {
namespace fs = std::filesystem;
namespace {

double SrgbToLinear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

// Any image ReadFloatImage decodes, as 3 linear channels.
common::FloatImage ReadPicture(const fs::path& path, bool decode_srgb) {
  common::FloatImage image = common::ReadFloatImage(path);
  if (image.width <= 0 || image.height <= 0) common::ThrowFormatError(path.string(), "has no pixels");
  if (image.channels != 1 && image.channels < 3) {
    common::ThrowFormatError(path.string(), "has " + std::to_string(image.channels) + " channels; expected 1, 3 or 4");
  }
  common::RequireFinite(image, path.string());
  common::FloatImage rgb(image.width, image.height, 3);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        const double v = image.at(x, y, image.channels == 1 ? 0 : c);
        if (v < 0) common::ThrowFormatError(path.string(), "holds a negative radiance");
        rgb.at(x, y, c) = static_cast<float>(decode_srgb ? SrgbToLinear(v) : v);
      }
    }
  }
  return rgb;
}

bool IsLinearFormat(const fs::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return std::tolower(c); });
  return extension == ".exr" || extension == ".hdr";
}

double Wrap(double v, double period) {
  const double r = std::fmod(v, period);
  return r < 0 ? r + period : r;
}

}  // namespace

model::Rgb Bilinear(const common::FloatImage& image, double x, double y, bool wrap_y) {
  const double fx = x - 0.5, fy = y - 0.5;
  const double x0f = std::floor(fx), y0f = std::floor(fy);
  const double tx = fx - x0f, ty = fy - y0f;
  const auto column = [&](double i) { return static_cast<int>(Wrap(i, image.width)); };
  const auto line = [&](double j) {
    return wrap_y ? static_cast<int>(Wrap(j, image.height)) : std::clamp(static_cast<int>(j), 0, image.height - 1);
  };
  const int x0 = column(x0f), x1 = column(x0f + 1), y0 = line(y0f), y1 = line(y0f + 1);
  model::Rgb value;
  for (int c = 0; c < 3; ++c) {
    value[c] = (1 - ty) * ((1 - tx) * image.at(x0, y0, c) + tx * image.at(x1, y0, c)) +
               ty * ((1 - tx) * image.at(x0, y1, c) + tx * image.at(x1, y1, c));
  }
  return value;
}

// ---------------------------------------------------------------------------------------------

BackgroundScene::BackgroundScene(common::FloatImage picture, double distance_m, double width_m, bool nearest)
    : picture_(std::move(picture)), distance_m_(distance_m), width_m_(width_m),
      height_m_(width_m * picture_.height / picture_.width), nearest_(nearest) {
  if (!(distance_m > 0 && std::isfinite(distance_m))) {
    common::ThrowInvalidInput("--background-distance", "must be a positive distance in metres");
  }
  if (!(width_m > 0 && std::isfinite(width_m))) common::ThrowInvalidInput("--background-width", "must be a positive width in metres");
}

BackgroundScene BackgroundScene::Checkerboard(double distance_m, double square_m) {
  common::FloatImage tile(2, 2, 3);
  for (int y = 0; y < 2; ++y) {
    for (int x = 0; x < 2; ++x) {
      for (int c = 0; c < 3; ++c) tile.at(x, y, c) = (x + y) % 2 == 0 ? 0.9f : 0.1f;
    }
  }
  return BackgroundScene(std::move(tile), distance_m, 2 * square_m, /*nearest=*/true);
}

BackgroundScene BackgroundScene::FromImage(const fs::path& path, double distance_m, double width_m) {
  return BackgroundScene(ReadPicture(path, !IsLinearFormat(path)), distance_m, width_m, /*nearest=*/false);
}

model::Rgb BackgroundScene::RadianceAt(double x, double y) const {
  const double px = (x + 0.5 * width_m_) / width_m_ * picture_.width;
  const double py = (0.5 * height_m_ - y) / height_m_ * picture_.height;
  if (!nearest_) return Bilinear(picture_, px, py, /*wrap_y=*/true);
  const int ix = static_cast<int>(Wrap(std::floor(px), picture_.width));
  const int iy = static_cast<int>(Wrap(std::floor(py), picture_.height));
  return {picture_.at(ix, iy, 0), picture_.at(ix, iy, 1), picture_.at(ix, iy, 2)};
}

model::Rgb BackgroundScene::Radiance(const model::Vec3& origin, const model::Vec3& direction) const {
  const double plane = -distance_m_;
  if (!(direction.z() < 0) || origin.z() <= plane) return {0, 0, 0};
  const double t = (plane - origin.z()) / direction.z();
  const model::Vec3 p = origin + t * direction;
  return RadianceAt(p.x(), p.y());
}

// ---------------------------------------------------------------------------------------------

EnvironmentScene::EnvironmentScene(common::FloatImage map) : map_(std::move(map)) {
  if (map_.channels != 3 || map_.width <= 0 || map_.height <= 0) {
    common::ThrowInvalidInput("environment", "must be a 3-channel image");
  }
}

EnvironmentScene EnvironmentScene::FromImage(const fs::path& path) {
  if (!IsLinearFormat(path)) {
    common::ThrowInvalidInput(path.string(), "is not an EXR or HDR file: an environment map holds linear radiance");
  }
  return EnvironmentScene(ReadPicture(path, /*decode_srgb=*/false));
}

model::Rgb EnvironmentScene::Radiance(const model::Vec3&, const model::Vec3& d) const {
  const double u = 0.5 + std::atan2(d.x(), -d.z()) / model::kTwoPi;
  const double v = std::acos(std::clamp(d.y(), -1.0, 1.0)) / model::kPi;
  return Bilinear(map_, u * map_.width, v * map_.height, /*wrap_y=*/false);
}

std::unique_ptr<Scene> MakeScene(const SceneOptions& options, double sample_width_m) {
  if (options.scene == "environment") {
    if (options.environment.empty()) common::ThrowInvalidInput("--environment", "is needed by --scene environment");
    return std::make_unique<EnvironmentScene>(EnvironmentScene::FromImage(options.environment));
  }
  if (options.scene != "background") common::ThrowInvalidInput("--scene", "must be background or environment, not " + options.scene);
  if (options.background.empty()) {
    return std::make_unique<BackgroundScene>(BackgroundScene::Checkerboard(options.background_distance_m, options.checker_size_m));
  }
  const double width = options.background_width_m > 0 ? options.background_width_m : 2.0 * sample_width_m;
  return std::make_unique<BackgroundScene>(BackgroundScene::FromImage(options.background, options.background_distance_m, width));
}

}  // namespace svbtdf::render
