#pragma once
// `svbtdf render`: path-traces the planar sample (render/surface.h) in a scene (render/scene.h)
// seen by a pinhole camera, and writes linear RGB. The sample is the only surface: a camera ray
// that hits it continues along a direction drawn from the texel's BSDF (Bsdf::Sample, weighted
// by Eval |cos| / pdf) into the scene; one that misses it sees the scene directly.
//
// Deterministic: every pixel has its own random stream, seeded from (seed, pixel), so the image
// does not depend on the thread count or on how rows are spread over threads.

#include <cstdint>

#include "svbtdf/common/image_io.h"
#include "svbtdf/model/vec.h"
#include "svbtdf/render/scene.h"
#include "svbtdf/render/surface.h"

namespace svbtdf::render {

// A pinhole camera looking at the sample's centre from direction (theta, phi) (theta from the
// sample normal +z, phi from +x toward +y) at `distance_m`, with the sample's +y upward in the
// image and `fov_deg` the horizontal field of view.
struct CameraOptions {
  double theta_deg = 0.0, phi_deg = 0.0;
  double distance_m = 0.3;
  double fov_deg = 20.0;
  int width = 512, height = 512;
};

class Camera {
 public:
  // Throws svbtdf::Error(kInvalidInput) naming the option for a view behind or in the plane of
  // the sample (theta >= 90), a distance or field of view out of range, or an empty image.
  explicit Camera(const CameraOptions& options);
  const model::Vec3& eye() const { return eye_; }
  // The unit direction through image position (x, y) in pixels (0..width, 0..height; y down).
  model::Vec3 Direction(double x, double y) const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  model::Vec3 eye_, forward_, right_, up_;
  double tan_half_fov_;
  int width_, height_;
};

struct RenderOptions {
  CameraOptions camera;
  int samples_per_pixel = 64;
  uint64_t seed = 1;
  int threads = 0;  // 0: every hardware thread
  bool progress = true;
};

// Renders `surface` in `scene`: width x height x 3 linear radiance. Honours Ctrl-C
// (common/interrupt.h) between rows.
common::FloatImage Render(const Surface& surface, const Scene& scene, const RenderOptions& options);

// The radiance estimate of one camera ray, the renderer's inner step (for tests).
model::Rgb TraceCameraRay(const Surface& surface, const Scene& scene, const model::Vec3& origin,
                          const model::Vec3& direction, double u_lobe, const model::Vec2& u, BsdfScratch& scratch);

}  // namespace svbtdf::render
