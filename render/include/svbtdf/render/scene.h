#pragma once
// What lights the sample in `svbtdf render` (docs/render.md, "Scenes"), in the sample frame of
// docs/model.md: the sample lies in z = 0 centred on the origin, +y up, the camera at z > 0 and
// the light coming from z < 0 (i.z < 0, as in the rig).
//
//   background   a self-lit plane at z = -distance behind the sample (the paper's Fig. 7):
//                a checkerboard, or a user's image repeated over the plane at a physical width;
//   environment  an equirectangular map at infinity, +y up, its centre column straight behind
//                the sample (direction -z).

#include <filesystem>
#include <memory>
#include <string>

#include "svbtdf/common/image_io.h"
#include "svbtdf/model/dual_microfacet.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::render {

class Scene {
 public:
  virtual ~Scene() = default;
  // Radiance arriving along the ray from `origin` in unit direction `direction` from anything but
  // the sample (the sample is the renderer's business).
  virtual model::Rgb Radiance(const model::Vec3& origin, const model::Vec3& direction) const = 0;
};

// A plane at z = -distance emitting the radiance of a picture tiled over it. The picture's
// top-left corner sits at (-width / 2, +height / 2), so a tile is centred behind the sample.
class BackgroundScene final : public Scene {
 public:
  // The default picture: a checkerboard of `square_m` squares, radiance 0.9 and 0.1.
  static BackgroundScene Checkerboard(double distance_m, double square_m);
  // A picture read from `path`: EXR as linear radiance; 8- and 16-bit images decoded from sRGB.
  // Throws svbtdf::Error naming the file for anything unreadable or of no size.
  static BackgroundScene FromImage(const std::filesystem::path& path, double distance_m, double width_m);

  model::Rgb Radiance(const model::Vec3& origin, const model::Vec3& direction) const override;
  // The picture's radiance at (x, y) on the plane.
  model::Rgb RadianceAt(double x, double y) const;

 private:
  BackgroundScene(common::FloatImage picture, double distance_m, double width_m, bool nearest);

  common::FloatImage picture_;  // 3 channels, linear
  double distance_m_, width_m_, height_m_;
  bool nearest_;  // the checkerboard keeps sharp edges; pictures are interpolated bilinearly
};

// An equirectangular environment at infinity (linear RGB, any size): direction d maps to
// u = 1/2 + atan2(d.x, -d.z) / 2 pi (columns) and v = acos(d.y) / pi (rows).
class EnvironmentScene final : public Scene {
 public:
  static EnvironmentScene FromImage(const std::filesystem::path& path);
  explicit EnvironmentScene(common::FloatImage map);

  model::Rgb Radiance(const model::Vec3& origin, const model::Vec3& direction) const override;

 private:
  common::FloatImage map_;
};

// The scene of `svbtdf render` as its options name it (docs/render.md, "Scenes").
struct SceneOptions {
  std::string scene = "background";   // background | environment
  std::filesystem::path background;   // picture behind the sample; empty: the checkerboard
  std::filesystem::path environment;  // equirectangular EXR of the environment scene
  double background_distance_m = 0.05;
  double background_width_m = 0.0;    // 0: twice the sample's width
  double checker_size_m = 0.01;
};

// Builds that scene behind a sample `sample_width_m` wide. Throws svbtdf::Error(kInvalidInput)
// naming the option (--scene, --environment) for an unknown scene or a missing picture, and the
// file for one that cannot be read.
std::unique_ptr<Scene> MakeScene(const SceneOptions& options, double sample_width_m);

// Bilinear lookup of a 3-channel image at continuous pixel coordinates (x, y) (pixel centres at
// +0.5), wrapping horizontally and clamping vertically when `wrap_y` is false.
model::Rgb Bilinear(const common::FloatImage& image, double x, double y, bool wrap_y);

}  // namespace svbtdf::render
