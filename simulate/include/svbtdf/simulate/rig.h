#pragma once
// The virtual measurement rig of the simulator (docs/simulator.md): a calibrated pinhole camera
// with Brown-Conrady lens distortion looking down at a thin sample, a monitor behind the sample
// showing a grid of dots, and the camera's radiometric chain.
//
// World frame = the sample frame of docs/model.md: the sample lies in z = 0 centred on the origin,
// z points toward the camera, the monitor lies behind it near the plane z = -d (MonitorFrame).
// Lengths are in metres.
// Camera conventions are OpenCV's: x_cam = R x_world + t, the camera looks along +z_cam with
// x_cam to the right and y_cam down in the image, and pixel centres sit at integer coordinates
// (pixel (u, v) covers [u - 0.5, u + 0.5] x [v - 0.5, v + 0.5]).

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "svbtdf/session/rig.h"
#include "svbtdf/model/vec.h"

namespace svbtdf::simulate {

// Intrinsics and distortion exactly as cv::projectPoints uses them
// (distortion = k1, k2, p1, p2, k3).
struct CameraIntrinsics {
  int width = 1024;
  int height = 768;
  double fx = 11000.0;
  double fy = 11000.0;
  double cx = 511.5;
  double cy = 383.5;
  std::array<double, 5> distortion = {0.0, 0.0, 0.0, 0.0, 0.0};
};

// World-to-camera rigid transform: x_cam = rotation * x_world + translation.
struct CameraPose {
  model::Mat3 rotation = model::Mat3::Identity();
  model::Vec3 translation = model::Vec3::Zero();

  model::Vec3 Centre() const { return -rotation.transpose() * translation; }
  // A camera at `eye` looking at `target`; the image's right axis is the projection of
  // (forward x up_hint) so that `up_hint` appears upward in the image.
  static CameraPose LookAt(const model::Vec3& eye, const model::Vec3& target, const model::Vec3& up_hint);
};

class PinholeCamera {
 public:
  PinholeCamera(CameraIntrinsics intrinsics, CameraPose pose);

  const CameraIntrinsics& intrinsics() const { return intrinsics_; }
  const CameraPose& pose() const { return pose_; }
  model::Vec3 Centre() const { return centre_; }

  // Normalised undistorted image coordinates -> distorted ones (OpenCV's model).
  model::Vec2 Distort(const model::Vec2& undistorted) const;
  // Inverse of Distort by Newton's method; nullopt where it does not converge (far outside the
  // region where the polynomial model is invertible).
  // `start`: where Newton's method begins (the distorted point itself when not given); the
  // answer for a point a pixel away converges in two steps instead of four or five.
  std::optional<model::Vec2> Undistort(const model::Vec2& distorted, const model::Vec2* start = nullptr) const;

  // Pixel coordinates of a world point; nullopt when it is not in front of the camera.
  std::optional<model::Vec2> Project(const model::Vec3& world) const;
  // Unit world-frame direction of the ray through pixel coordinates `pixel`, nullopt where the
  // distortion cannot be inverted.
  std::optional<model::Vec3> PixelRay(const model::Vec2& pixel) const;
  // The two halves of PixelRay, for renderers that interpolate within a pixel: the undistorted
  // normalised coordinates of `pixel` (Newton started at `start`, see Undistort), and the unit
  // world-frame ray through normalised coordinates p.
  std::optional<model::Vec2> ImagePoint(const model::Vec2& pixel, const model::Vec2* start = nullptr) const;
  model::Vec3 RayThrough(const model::Vec2& p) const;

 private:
  CameraIntrinsics intrinsics_;
  CameraPose pose_;
  model::Vec3 centre_;
};

// How the radiant intensity of a small patch of the monitor depends on the angle theta_e between
// the emitted direction and the monitor's normal. I(theta_e) = I_0 P(theta_e):
//   isotropic   P = 1            the notes' isotropic point emitter (the paper's CRT assumption)
//   lambertian  P = cos          a constant-radiance emitter
//   lcd         P = cos^n        an LCD's fall-off, n = exponent
struct EmissionProfile {
  std::string kind = "isotropic";
  double exponent = 1.0;

  double operator()(double cos_theta_e) const;

  // `isotropic`, `lambertian` or `lcd:N` (N in (0, 20]), as `svbtdf simulate --monitor-emission`
  // takes it; svbtdf::Error(kInvalidInput) naming `option` otherwise.
  static EmissionProfile Parse(const std::string& spec, const std::string& option);
};

struct MonitorFrame;

// The polarisation of the monitor's light (docs/simulator.md, "A polarised LCD"):
//   none        unpolarised (a CRT, an OLED; the default)
//   linear      linearly polarised, as an LCD's output polariser makes it: the electric field lies
//               along the screen's pixel x axis (u) turned by angle_deg toward its top (-v),
//               counter-clockwise as seen from the screen's front (from the sample)
// A ray leaving the screen at an angle carries the part of that field transverse to it.
struct Polarisation {
  std::string kind = "none";
  double angle_deg = 0.0;

  bool linear() const { return kind == "linear"; }
  // The field direction in the sample frame: cos(angle) right - sin(angle) down.
  model::Vec3 FieldDirection(const MonitorFrame& frame) const;
  // `none` or `linear:DEG` (any finite DEG), as `svbtdf simulate --monitor-polarization` takes
  // it; svbtdf::Error(kInvalidInput) naming `option` otherwise.
  static Polarisation Parse(const std::string& spec, const std::string& option);
  std::string ToString() const;
};

// The monitor is a physical screen (docs/calibration-format.md, "The monitor frame"): its pixel
// coordinates (u, v) run to the right and down as seen from its front, from the sample and the
// camera, so that u x v points into the screen, away from the sample. Monitor pixel (i, j) covers
// [i, i + 1) x [j, j + 1) of (u, v) and its centre is (i + 0.5, j + 0.5).
struct MonitorConfig {
  double distance = 0.04;        // d: the screen's centre lies on the plane z = -d
  double width = 0.30;           // active area (m), along u
  double height = 0.20;          // ... along v
  model::Vec2 centre = model::Vec2::Zero();    // centre of the active area in (x, y)
  // How the screen lies, as a lab puts it down. orientation_deg turns it about its normal,
  // counter-clockwise seen from the sample: at 0 its u axis runs along +x and v along -y (its
  // top edge toward +y), at 90 u runs along +y. tilt_deg then tilts it about the x axis through
  // its centre (the screen is not quite parallel to the sample).
  double orientation_deg = 0.0;
  double tilt_deg = 0.0;
  // A mirror image of the screen (v reversed, u x v toward the sample), which no monitor seen
  // from its front gives but a mirrored display mode does: for tests that calibration refuses it.
  bool mirrored = false;
  double pixel_pitch = 0.00025;  // m
  double gamma = 2.2;            // displayed level v -> luminance black + (1 - black) v^gamma
  double black_level = 0.0;      // luminance of level 0 as a fraction of white
  // Radiant intensity per unit emitting area along the monitor normal at level 1, in the
  // simulator's radiometric unit (the camera's `sensitivity` turns it into electrons).
  double white_exitance = 1.0;
  EmissionProfile emission;
  Polarisation polarisation;

  double Luminance(double level) const;
};

// The screen's orientation to the nearest quarter turn, in [0, 360): what a lab notes down as
// rig.monitor.orientation_deg.
double NominalOrientationDeg(const MonitorConfig& monitor);

// Where the screen is: monitor pixel coordinates (u, v) <-> points of the sample frame.
struct MonitorFrame {
  model::Vec3 origin;       // the corner (u, v) = (0, 0): the top-left corner seen from the front
  model::Vec3 right, down;  // unit vectors along u and v
  model::Vec3 normal;       // out of the screen's front, toward the sample
  double pixel_pitch = 0;
  double width_px = 0, height_px = 0;  // the active area in pixels

  static MonitorFrame Of(const MonitorConfig& monitor);
  model::Vec3 PointAt(const model::Vec2& uv) const { return origin + pixel_pitch * (uv.x() * right + uv.y() * down); }
  // (u, v) of the foot of `point` on the screen's plane.
  model::Vec2 PixelCoordinates(const model::Vec3& point) const;
  bool InActiveArea(const model::Vec2& uv) const {
    return uv.x() >= 0 && uv.y() >= 0 && uv.x() < width_px && uv.y() < height_px;
  }
  // Where the ray from `from` along `direction` meets the screen's plane, when it does ahead.
  std::optional<model::Vec3> Intersect(const model::Vec3& from, const model::Vec3& direction) const;
  // cos(theta_e): the angle between the screen's normal and the direction from `emitter` to `x`.
  double CosEmission(const model::Vec3& emitter, const model::Vec3& x) const { return normal.dot((x - emitter).normalized()); }
};

// The grid of dots shown one at a time behind the sample.
struct DotGridConfig {
  int cols = 40;
  int rows = 40;
  double span_scale = 1.2;      // the grid spans this times the sample's extent
  // Shift of the grid's centre away from the camera (along the camera's azimuth), in metres;
  // negative: d cos(theta) with theta the camera's angle from vertical (the paper's choice).
  double shift = -1.0;
  // The grid runs along the screen's pixel axes: column c along u, row r along v (down the
  // screen), dot q = r * cols + c, as a lab lays dots out on its monitor.
  double radius_px = 2.0;       // dot radius in monitor pixels
  double level = 1.0;           // displayed level of a dot
  // A capture plan's dots (`svbtdf simulate --plan`), row-major over cols x rows, in the plan's
  // monitor pixel coordinates; empty: laid out by span_scale and shift.
  std::vector<std::pair<double, double>> positions_px;
};

struct SampleConfig {
  double width = 0.08;          // extent in x (m)
  int texels_x = 600;
  int texels_y = 600;           // the extent in y is width * texels_y / texels_x (square texels)

  double texel_pitch() const { return width / texels_x; }
  double height() const { return texel_pitch() * texels_y; }
  // Centre of texel (col, row) in the sample frame: x grows with col, y decreases with row.
  model::Vec3 TexelCentre(int col, int row) const {
    return {-0.5 * width + (col + 0.5) * texel_pitch(), 0.5 * height() - (row + 0.5) * texel_pitch(), 0.0};
  }
};

// The camera's radiometric chain: irradiance-weighted radiance -> electrons -> digital numbers.
struct SensorConfig {
  std::vector<double> exposures_s = {1.0};  // exposure bracket (seconds)
  double sensitivity = 2.0e4;    // electrons per (radiance unit x second) at the image centre
  double full_well = 40000.0;    // electrons at saturation
  double read_noise = 3.0;       // electrons RMS (Gaussian)
  bool shot_noise = true;        // Poisson photon noise
  double dark_current = 0.0;     // electrons per second (mean level of the dark frames)
  int bit_depth = 16;            // quantisation of the stored value
  std::string response = "linear";  // linear | srgb: the curve between exposure and value
  double vignetting = 0.0;       // fall-off strength: v(r) = 1 / (1 + vignetting r^2), r = distance
                                 // from (cx, cy) over the window's half diagonal
  double black_offset = 0.0;     // pedestal added to the digital value, as a fraction of full scale
};

// Where the stored images lie on the camera's sensor (session::SensorWindow). A lab crops its dot
// images to the region of interest around the sample, and calibrates the lens on the whole sensor
// with a board that fills it: only a wide view separates the principal point from the camera's
// rotation, and the focal length from the board's distance (docs/simulator.md, "Sensor window").
// The rig's `intrinsics` are the window's (principal point relative to the window's corner); the
// Zhang board views are whole-sensor images.
using session::SensorWindow;

// A chessboard: the one held up for Zhang calibration, or the one laid in the sample holder for
// the sample plane's pose.
struct BoardConfig {
  int inner_cols = 9;    // inner corners
  int inner_rows = 6;
  double square = 0.008; // m
  int views = 10;        // views at varied poses for the intrinsics (Zhang board only)
  double reflectance_white = 0.85;
  double reflectance_black = 0.04;
  double illumination = 1.0;  // radiance of a perfect white board, in the simulator's unit

  // "chessboard:COLSxROWS:SQUARE_MM", as sessions name boards (calib::BoardSpec).
  std::string Spec() const;
};

struct RigConfig {
  CameraIntrinsics intrinsics;  // of the stored images (the window)
  SensorWindow window;
  CameraPose pose;
  MonitorConfig monitor;
  DotGridConfig dots;
  SampleConfig sample;
  SensorConfig sensor;
  BoardConfig board;         // Zhang views, whole sensor
  BoardConfig holder_board;  // in the sample holder, seen through the window
  int pixel_samples = 2;   // supersampling per pixel axis for dot images (n x n stratified)
  int board_samples = 4;   // ... for board images (anti-aliasing of the squares)
  int dark_frames = 4;

  // The paper's geometry: camera `distance` from the sample centre at `theta` from vertical,
  // on the -y side, looking at the centre.
  static CameraPose PaperPose(double distance = 1.0, double theta = model::kPi / 4.0);
};

// One dot of the grid: where it is and how much it emits.
struct Dot {
  int col = 0;
  int row = 0;
  model::Vec3 position;        // on the screen, at a monitor pixel centre
  int monitor_x = 0;    // monitor pixel coordinates of its centre
  int monitor_y = 0;
  // The monitor coordinates it was drawn at, as a capture plan names them (monitor_x, monitor_y
  // for a laid-out grid; a plan's may lie between pixels).
  double drawn_x = 0.0, drawn_y = 0.0;
  double intensity = 0; // L_q: radiant intensity along the monitor normal (P(0) = 1)
  double radius = 0;    // m
};

// A validated rig with everything derived from the configuration.
class Rig {
 public:
  // Throws svbtdf::Error(kInvalidInput) for impossible geometry (camera below the sample plane or
  // looking away from it, the sample not fully in view, the monitor not behind the sample, dots
  // off the monitor, bad intrinsics or sensor values), naming the offending setting.
  explicit Rig(RigConfig config);

  const RigConfig& config() const { return config_; }
  // The camera of the stored images (the window), and of the whole sensor (the same lens and
  // pose, the principal point moved by the window's offset).
  const PinholeCamera& camera() const { return camera_; }
  const PinholeCamera& sensor_camera() const { return sensor_camera_; }
  const std::vector<Dot>& dots() const { return dots_; }
  const MonitorFrame& monitor_frame() const { return monitor_frame_; }

  // The dot drawn centred on monitor coordinate (x_px, y_px) with a radius of `radius_px` monitor
  // pixels at `luminance` (a fraction of white, black level included: MonitorConfig::Luminance).
  // Monitor pixel (i, j) is centred on (u, v) = (i + 0.5, j + 0.5), as the grid's dots are. For the simulated camera of `svbtdf acquire`, which renders whatever
  // dot a capture plan shows; col = row = -1.
  Dot DotAt(double x_px, double y_px, double radius_px, double luminance) const;

  // Angle of the camera from vertical, as seen from the sample centre.
  double CameraTheta() const;

  // Radiant intensity the dot sends toward world point x (the profile included), i.e. L_q(x)
  // of the measurement equation I = R |i.z| L_q / |p - x|^2.
  double DotIntensityToward(const Dot& dot, const model::Vec3& x) const;

  // Where the ray through `pixel` meets the sample plane, when it does inside the sample.
  std::optional<model::Vec3> SampleHit(const model::Vec2& pixel) const;
  // Texel (col, row) containing a point of the sample plane, or nullopt outside the sample.
  std::optional<std::array<int, 2>> TexelAt(const model::Vec3& x) const;
  // Centre of texel (col, row): x grows with col, y decreases with row (row 0 at +y).
  model::Vec3 TexelCentre(int col, int row) const;

 private:
  void Validate() const;
  void LayOutDots();

  RigConfig config_;
  PinholeCamera camera_;
  PinholeCamera sensor_camera_;
  MonitorFrame monitor_frame_;
  std::vector<Dot> dots_;
};

}  // namespace svbtdf::simulate
