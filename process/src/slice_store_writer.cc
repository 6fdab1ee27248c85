#include "svbtdf/process/slice_store_writer.h"

#include <fcntl.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <set>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/durable_log.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/fit/slice_store_format.h"
#include "svbtdf/process/diffuse_separation.h"
#include "svbtdf/process/push_pull.h"

namespace svbtdf::process {
namespace fs = std::filesystem;
using namespace fit::store;
using fit::SliceStoreInfo;
using fit::TexelGeometry;

TexelGeometry MakeTexelGeometry(const calib::SessionCalibration& calibration, int texels_x, int texels_y) {
  TexelGeometry g;
  g.texels_x = texels_x;
  g.texels_y = texels_y;
  g.width_m = calibration.sample_plane.width_m;
  g.height_m = calibration.sample_plane.height_m;
  g.camera_centre = calibration.sample_plane.CameraCentre();
  for (const calib::DotPosition& dot : calibration.monitor.dots) g.dots.push_back(dot.position);
  if (calibration.monitor.normal.norm() > 0) g.monitor_normal = calibration.monitor.normal.normalized();
  return g;
}

namespace {

// 2-D cross product of (b - a) and (c - a).
double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

// Convex hull, counter-clockwise (Andrew's monotone chain); collinear points dropped.
std::vector<Eigen::Vector2d> ConvexHull(std::vector<Eigen::Vector2d> points) {
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (points.size() < 3) return points;
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  size_t k = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    while (k >= 2 && Cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  for (size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && Cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);
  return hull;
}

double SegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

// Distance from p to a convex polygon (counter-clockwise; 0 inside), or to a point or segment.
double HullDistance(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& hull) {
  if (hull.empty()) return std::numeric_limits<double>::infinity();
  if (hull.size() == 1) return (p - hull[0]).norm();
  bool inside = hull.size() >= 3;
  double distance = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < hull.size(); ++k) {
    const Eigen::Vector2d& a = hull[k];
    const Eigen::Vector2d& b = hull[(k + 1) % hull.size()];
    if (Cross(a, b, p) < 0) inside = false;
    distance = std::min(distance, SegmentDistance(p, a, b));
  }
  return inside ? 0.0 : distance;
}

}  // namespace

std::vector<uint8_t> TexelsWithDotBeneath(const TexelGeometry& geometry) {
  std::vector<uint8_t> reach(geometry.num_texels(), 0);
  if (geometry.dots.empty()) return reach;
  // The monitor plane: through the dots' centroid, with its normal; an in-plane basis.
  const model::Vec3 n = geometry.monitor_normal.normalized();
  model::Vec3 centroid = model::Vec3::Zero();
  for (const model::Vec3& p : geometry.dots) centroid += p;
  centroid /= static_cast<double>(geometry.dots.size());
  const model::Vec3 e1 = (std::abs(n.x()) < 0.9 ? model::Vec3::UnitX() : model::Vec3::UnitY()).cross(n).normalized();
  const model::Vec3 e2 = n.cross(e1);
  std::vector<Eigen::Vector2d> dots;
  for (const model::Vec3& p : geometry.dots) dots.emplace_back((p - centroid).dot(e1), (p - centroid).dot(e2));
  const double spacing = std::sqrt(geometry.DotCellArea());
  const std::vector<Eigen::Vector2d> hull = ConvexHull(dots);
  for (int64_t t = 0; t < geometry.num_texels(); ++t) {
    const model::Vec3 x = geometry.TexelCentre(t);
    const model::Vec3 o = geometry.View(t);
    // x - s o on the plane: (x - s o - centroid) . n = 0.
    const double along = o.dot(n);
    if (!(std::abs(along) > 1e-12)) continue;
    const double s = (x - centroid).dot(n) / along;
    if (!(s > 0)) continue;  // the continued ray never reaches the monitor
    const model::Vec3 hit = x - s * o - centroid;
    const Eigen::Vector2d m(hit.dot(e1), hit.dot(e2));
    if (HullDistance(m, hull) > 0.5 * spacing) continue;
    double nearest = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector2d& d : dots) nearest = std::min(nearest, (m - d).squaredNorm());
    reach[t] = std::sqrt(nearest) <= spacing / std::sqrt(2.0) ? 1 : 0;
  }
  return reach;
}

// ---------------------------------------------------------------------------------------------
// Writer

struct SliceStoreWriter::State {
  fs::path folder;
  SliceStoreInfo info;
  calib::SessionCalibration calibration;
  TexelGeometry geometry;
  std::unique_ptr<File> samples;
  std::set<int> dots_done;                     // written, durably or not yet
  std::optional<common::DurableLog> progress;  // progress.jsonl: one line per dot made durable
  std::vector<int> uncommitted;                // written since the last commit
  std::chrono::steady_clock::time_point last_commit = std::chrono::steady_clock::now();
  bool finished = false;
};

namespace {

// How often written dots are made durable. One fsync of the samples and one of the journal per
// commit cost about 20 ms on this project's machines, as much as processing a tenth of a dot
// at paper scale; a commit a second bounds that below 3% and what a crash loses to a second's work.
constexpr std::chrono::milliseconds kCommitInterval{1000};

bool FolderIsEmpty(const fs::path& folder) { return fs::is_directory(folder) && fs::is_empty(folder); }

// The dots whose samples are on disk. A line torn by a crash is left out and cut off before the
// next append; a damaged line (glued to a torn one by a version that did not cut it off) names
// no dot. Either way that dot is processed again, which rewrites its samples in place.
std::set<int> ReadProgress(const common::DurableLog& log) {
  std::set<int> done;
  for (const std::string& line : log.lines()) {
    try {
      done.insert(common::IntegerAt(common::ParseJson(line, log.path().string()), "dot", log.path().string()));
    } catch (const std::exception&) {  // common::Error or a json type error
    }
  }
  return done;
}

}  // namespace

SliceStoreWriter::SliceStoreWriter(const fs::path& folder, const SliceStoreInfo& info,
                                   const calib::SessionCalibration& calibration)
    : state_(std::make_unique<State>()) {
  CheckInfo(info, folder.string());
  if (static_cast<int>(calibration.monitor.dots.size()) != info.num_dots) {
    common::ThrowInvalidInput(folder.string(), "the calibration lists " + std::to_string(calibration.monitor.dots.size()) +
                                           " dots but the store is for " + std::to_string(info.num_dots));
  }
  State& s = *state_;
  s.folder = folder;
  s.info = info;
  s.calibration = calibration;
  s.geometry = MakeTexelGeometry(calibration, info.texels_x, info.texels_y);
  const uint64_t bytes = NumTiles(info) * TileBytes(info);
  if (fs::exists(folder / kManifest)) {
    const nlohmann::json manifest = ReadManifest(folder);
    const bool complete = CompleteFromManifest(manifest, (folder / kManifest).string());
    const nlohmann::json calibration_on_disk = common::ReadJsonFile(folder / kCalibration);
    if (manifest.at("texels_x") != info.texels_x || manifest.at("texels_y") != info.texels_y ||
        manifest.at("num_dots") != info.num_dots || manifest.at("light_resolution") != info.light_resolution ||
        manifest.at("tile_texels") != info.tile_texels || calibration_on_disk != calib::ToJson(calibration)) {
      if (complete) {
        common::ThrowInvalidInput(folder.string(), "already holds a finished processing of other settings or another "
                                                   "calibration; it is never overwritten", "choose a new output folder");
      }
      common::ThrowInvalidInput(folder.string(), "holds an unfinished processing with other settings or another calibration",
                        "finish it with the same options, or choose a new output folder");
    }
    if (complete) {  // the same processing, done already: nothing to write
      s.finished = true;
      return;
    }
    // What a kill mid-write left; the command holds the folder's lock, so no other writer owns them.
    common::RemoveStaleTemporaryFiles(folder);
    s.samples = std::make_unique<File>(folder / kSamples, O_RDWR);
    if (s.samples->Size() != bytes) common::ThrowFormatError((folder / kSamples).string(), "has the wrong size to resume");
    s.progress = common::DurableLog::Open(folder / kProgress);
    s.dots_done = ReadProgress(*s.progress);
    return;
  }
  if (fs::exists(folder) && !FolderIsEmpty(folder)) {
    common::ThrowInvalidInput(folder.string(), "is not empty and holds no unfinished processing", "choose a new output folder");
  }
  // Made whole under a temporary name, so that a kill or a full disk leaves either nothing or a
  // store that the same command resumes (its manifest is what marks a store).
  common::CreateFolderAtomically(folder, [&](const fs::path& staging) {
    calib::WriteSessionCalibration(staging / kCalibration, calibration);
    File(staging / kSamples, O_RDWR | O_CREAT | O_TRUNC).Resize(bytes);  // sparse until written
    WriteManifest(staging, info, s.geometry, /*complete=*/false, nlohmann::json::object());
  });
  s.samples = std::make_unique<File>(folder / kSamples, O_RDWR);
}

SliceStoreWriter::~SliceStoreWriter() {
  // Keep what was written before an error or an interrupt, if the disk still takes it (the dots
  // are whole: WriteDot queues a dot only after writing all of it). A kill loses them instead,
  // and the next run processes them again.
  if (!state_) return;
  try {
    Commit();
  } catch (const std::exception&) {
  }
}
SliceStoreWriter::SliceStoreWriter(SliceStoreWriter&&) noexcept = default;

bool SliceStoreWriter::finished() const { return state_->finished; }

bool SliceStoreWriter::HasDot(int dot) const { return state_->dots_done.count(dot) > 0; }

void SliceStoreWriter::WriteDot(int dot, const std::vector<float>& rgb) {
  State& s = *state_;
  const int64_t texels = s.geometry.num_texels();
  if (dot < 0 || dot >= s.info.num_dots) common::ThrowInvalidInput("dot", std::to_string(dot) + " is outside the store");
  if (static_cast<int64_t>(rgb.size()) != 3 * texels) {
    common::ThrowInvalidInput("dot " + std::to_string(dot), "has " + std::to_string(rgb.size()) + " values for " +
                                                        std::to_string(texels) + " RGB texels");
  }
  const int64_t tile_values = static_cast<int64_t>(s.info.tile_texels) * 3;
  std::vector<Half> run(tile_values);
  for (int64_t tile = 0; tile < NumTiles(s.info); ++tile) {
    const int64_t begin = tile * tile_values, end = std::min<int64_t>(3 * texels, begin + tile_values);
    std::fill(run.begin(), run.end(), Half(kNaN));
    for (int64_t k = begin; k < end; ++k) run[k - begin] = Half(rgb[k]);
    const uint64_t offset = tile * TileBytes(s.info) + static_cast<uint64_t>(dot) * tile_values * sizeof(Half);
    s.samples->WriteAt(run.data(), run.size() * sizeof(Half), offset);
  }
  s.dots_done.insert(dot);
  s.uncommitted.push_back(dot);
  if (std::chrono::steady_clock::now() - s.last_commit >= kCommitInterval) Commit();
}

void SliceStoreWriter::Commit() {
  State& s = *state_;
  if (s.uncommitted.empty()) return;
  s.samples->Sync();  // the values first, so that the journal never names a dot the disk lacks
  std::vector<std::string> lines;
  for (int dot : s.uncommitted) lines.push_back(nlohmann::json{{"dot", dot}}.dump());
  if (!s.progress) s.progress = common::DurableLog::Open(s.folder / kProgress);
  s.progress->Append(lines);
  s.uncommitted.clear();
  s.last_commit = std::chrono::steady_clock::now();
}

namespace {

struct TexelSummary {
  model::Rgb rho_d = {0, 0, 0};
  bool valid = false;
  int samples = 0;
};

// One texel's valid samples, with their light directions and noise scales.
struct TexelSamples {
  std::vector<model::Vec3> light;
  std::vector<model::Rgb> rgb;
  std::vector<double> noise_scale;  // s_q = |p_q - x|^2 / (|i_q.z| P(theta_q)): R per unit camera rate
  std::vector<int> dot;              // which dot each sample is
};

TexelSamples GatherSamples(const TexelGeometry& geometry, const calib::MonitorCalibration& monitor, int64_t texel,
                           const float* tile, int tile_texels, int64_t k, int num_dots) {
  const model::Vec3 x = geometry.TexelCentre(texel);
  TexelSamples out;
  for (int q = 0; q < num_dots; ++q) {
    const float* r = tile + (static_cast<int64_t>(q) * tile_texels + k) * 3;
    if (!std::isfinite(r[0]) || !std::isfinite(r[1]) || !std::isfinite(r[2])) continue;
    const model::Vec3 to_dot = geometry.dots[q] - x;
    const model::Vec3 i = to_dot.normalized();
    const double emission = std::max(1e-6, monitor.Emission(std::max(0.0, -i.dot(geometry.monitor_normal))));
    out.light.push_back(i);
    out.rgb.push_back({r[0], r[1], r[2]});
    out.noise_scale.push_back(to_dot.squaredNorm() / (std::max(1e-9, std::abs(i.z())) * emission));
    out.dot.push_back(q);
  }
  return out;
}

// Diffuse separation: the floor of the samples (EstimateDiffuse) whose dot is not too dim in the
// image for a uniform R (1 / s_q at least `diffuse_threshold` of the texel's largest): a choice
// made on the geometry, not on the measured values, so that it does not bias the floor.
model::Rgb SeparateDiffuse(int64_t texel, const TexelSamples& samples, const std::vector<std::array<int, 2>>& neighbours,
                           const SliceStoreWriter::FinishOptions& options) {
  if (samples.rgb.empty()) return {0, 0, 0};
  double brightest = 0;
  for (double s : samples.noise_scale) brightest = std::max(brightest, 1.0 / s);
  std::vector<int> index(neighbours.size(), -1);  // dot -> position among the kept samples
  std::vector<model::Rgb> kept;
  std::vector<double> scale;
  std::vector<int> kept_dots;
  for (size_t s = 0; s < samples.rgb.size(); ++s) {
    if (1.0 / samples.noise_scale[s] < options.diffuse_threshold * brightest) continue;
    index[samples.dot[s]] = static_cast<int>(kept.size());
    // Back to what the camera saw: the floor was not polarised (FinishOptions::polarisation_ratio).
    const double ratio = options.polarisation_ratio ? options.polarisation_ratio(samples.light[s], texel) : 1.0;
    kept.push_back({samples.rgb[s][0] * ratio, samples.rgb[s][1] * ratio, samples.rgb[s][2] * ratio});
    scale.push_back(samples.noise_scale[s]);
    kept_dots.push_back(samples.dot[s]);
  }
  if (kept.empty()) return {0, 0, 0};
  std::vector<std::array<int, 2>> neighbour(kept.size(), {-1, -1});
  for (size_t k = 0; k < kept.size(); ++k) {
    const auto [a, b] = neighbours[kept_dots[k]];
    if (a >= 0 && b >= 0 && index[a] >= 0 && index[b] >= 0) neighbour[k] = {index[a], index[b]};
  }
  model::Rgb rho_d = EstimateDiffuse(kept, scale, neighbour).rho_d;
  for (double& d : rho_d) d = std::max(0.0, d);
  return rho_d;
}

// The resampled refractive slice of one texel given its diffuse term.
TexelSummary Resample(const TexelSamples& samples, const model::Rgb& rho_d, const PushPullResampler& resampler,
                      const SliceStoreWriter::FinishOptions& options, std::vector<float>* cells) {
  TexelSummary summary;
  summary.samples = static_cast<int>(samples.light.size());
  summary.rho_d = rho_d;
  cells->assign(resampler.grid().num_cells(), 0.0f);
  if (summary.samples == 0) return summary;
  std::vector<float> values(samples.rgb.size()), weights(samples.rgb.size(), 1.0f);
  double peak = 0;
  for (size_t s = 0; s < samples.rgb.size(); ++s) {
    values[s] = static_cast<float>(std::max(0.0, model::Luminance(samples.rgb[s]) - model::Luminance(rho_d)));
    peak = std::max(peak, static_cast<double>(values[s]));
  }
  std::vector<float> confidence;
  resampler.Resample(samples.light, values, weights, cells, &confidence);
  summary.valid = summary.samples >= options.min_valid_dots && peak > 0;
  return summary;
}

// For every texel without a dot beneath it, the nearest texel on the grid that has one (breadth
// first over the 4-neighbourhood, ties to the first reached); -1 when no texel has a dot beneath.
std::vector<int64_t> NearestReachedTexel(const std::vector<uint8_t>& reach, int texels_x, int texels_y) {
  const int64_t texels = static_cast<int64_t>(texels_x) * texels_y;
  std::vector<int64_t> source(texels, -1), queue;
  for (int64_t t = 0; t < texels; ++t) {
    if (reach[t]) source[t] = t, queue.push_back(t);
  }
  for (size_t head = 0; head < queue.size(); ++head) {
    const int64_t t = queue[head];
    const int col = static_cast<int>(t % texels_x), row = static_cast<int>(t / texels_x);
    const int64_t neighbours[4] = {col > 0 ? t - 1 : -1, col + 1 < texels_x ? t + 1 : -1,
                                   row > 0 ? t - texels_x : -1, row + 1 < texels_y ? t + texels_x : -1};
    for (int64_t u : neighbours) {
      if (u >= 0 && source[u] < 0) source[u] = source[t], queue.push_back(u);
    }
  }
  return source;
}

}  // namespace

void SliceStoreWriter::Finish(const FinishOptions& options) {
  State& s = *state_;
  Commit();
  for (int q = 0; q < s.info.num_dots; ++q) {
    if (!HasDot(q)) common::ThrowInvalidInput(s.folder.string(), "is missing dot " + std::to_string(q), "process every dot first");
  }
  const model::Hemicube light_grid(s.info.light_resolution);
  const PushPullResampler resampler(light_grid);
  const int64_t texels = s.geometry.num_texels();
  const calib::MonitorCalibration& monitor = s.calibration.monitor;
  const File slices(s.folder / kSlices, O_RDWR | O_CREAT | O_TRUNC);
  common::FloatImage rho_d(s.info.texels_x, s.info.texels_y, 3), mask(s.info.texels_x, s.info.texels_y, 1),
      reach_map(s.info.texels_x, s.info.texels_y, 1);
  const std::vector<uint8_t> reach = TexelsWithDotBeneath(s.geometry);
  const std::vector<std::array<int, 2>> neighbours = OppositeNeighbours(s.geometry.dots);
  int64_t valid_texels = 0, without_dot_beneath = 0;
  for (uint8_t r : reach) without_dot_beneath += r ? 0 : 1;
  std::unique_ptr<common::ProgressBar> progress;
  if (options.progress) progress = std::make_unique<common::ProgressBar>("separate and resample", texels, "texels");
  std::vector<Half> tile_raw(TileBytes(s.info) / sizeof(Half));
  std::vector<float> tile(tile_raw.size());
  const auto read_tile = [&](int64_t t) {
    s.samples->ReadAt(tile_raw.data(), TileBytes(s.info), t * TileBytes(s.info));
    for (size_t k = 0; k < tile.size(); ++k) tile[k] = static_cast<float>(tile_raw[k]);
  };
  const auto store_summary = [&](int64_t texel, const TexelSummary& summary) {
    const int col = static_cast<int>(texel % s.info.texels_x), row = static_cast<int>(texel / s.info.texels_x);
    for (int c = 0; c < 3; ++c) rho_d.at(col, row, c) = static_cast<float>(summary.rho_d[c]);
    mask.at(col, row) = summary.valid ? 1.0f : 0.0f;
    reach_map.at(col, row) = reach[texel] ? 1.0f : 0.0f;
  };
  // Writes the slices of the tile's texels whose reach is `reached`, in contiguous runs.
  const auto write_slices = [&](int64_t begin, int64_t end, const std::vector<Half>& slice_out, bool reached) {
    const size_t cells = light_grid.num_cells();
    for (int64_t k = 0; k < end - begin;) {
      if ((reach[begin + k] != 0) != reached) {
        ++k;
        continue;
      }
      int64_t run = k;
      while (run < end - begin && (reach[begin + run] != 0) == reached) ++run;
      slices.WriteAt(&slice_out[k * cells], (run - k) * SliceBytes(light_grid), (begin + k) * SliceBytes(light_grid));
      k = run;
    }
  };
  // Resamples the texels of tile t that have a dot beneath them (`reached`) or that have none,
  // with the diffuse term diffuse_of(texel, samples); writes their slices and records their
  // summaries. Returns whether the tile also holds texels of the other kind.
  const auto resample_tile = [&](int64_t t, bool reached, const auto& diffuse_of) {
    read_tile(t);
    const int64_t begin = t * s.info.tile_texels, end = std::min(texels, begin + s.info.tile_texels);
    const auto selected = [&](int64_t k) { return (reach[begin + k] != 0) == reached; };
    std::vector<Half> slice_out((end - begin) * light_grid.num_cells());
    std::vector<TexelSummary> summaries(end - begin);
    common::ParallelFor(end - begin, options.threads, 16, [&](int64_t a, int64_t b) {
      std::vector<float> cells;
      for (int64_t k = a; k < b; ++k) {
        if (!selected(k)) continue;
        const TexelSamples samples =
            GatherSamples(s.geometry, monitor, begin + k, tile.data(), s.info.tile_texels, k, s.info.num_dots);
        summaries[k] = Resample(samples, diffuse_of(begin + k, samples), resampler, options, &cells);
        for (size_t c = 0; c < cells.size(); ++c) slice_out[k * cells.size() + c] = Half(cells[c]);
      }
    });
    write_slices(begin, end, slice_out, reached);
    int64_t done = 0;
    for (int64_t k = 0; k < end - begin; ++k) {
      if (!selected(k)) continue;
      store_summary(begin + k, summaries[k]);
      valid_texels += summaries[k].valid;
      ++done;
    }
    if (progress) progress->Advance(done);
    return done < end - begin;
  };
  // Pass 1: every texel with a dot beneath it (the others' slices wait for their diffuse term).
  std::vector<uint8_t> tile_has_unreached(NumTiles(s.info), 0);
  const auto own_floor = [&](int64_t texel, const TexelSamples& samples) {
    return SeparateDiffuse(texel, samples, neighbours, options);
  };
  for (int64_t t = 0; t < NumTiles(s.info); ++t) tile_has_unreached[t] = resample_tile(t, /*reached=*/true, own_floor);
  // Pass 2: a texel without a dot beneath it sees only the lobe's tails, whose floor is not its
  // diffuse term: it takes the diffuse term of the nearest texel that has a dot beneath it (0 when
  // none has).
  if (without_dot_beneath > 0) {
    const std::vector<int64_t> source = NearestReachedTexel(reach, s.info.texels_x, s.info.texels_y);
    const auto nearest_reached = [&](int64_t texel, const TexelSamples&) {
      const int64_t from = source[texel];
      if (from < 0) return model::Rgb{0, 0, 0};
      const int col = static_cast<int>(from % s.info.texels_x), row = static_cast<int>(from / s.info.texels_x);
      return model::Rgb{rho_d.at(col, row, 0), rho_d.at(col, row, 1), rho_d.at(col, row, 2)};
    };
    for (int64_t t = 0; t < NumTiles(s.info); ++t) {
      if (tile_has_unreached[t]) resample_tile(t, /*reached=*/false, nearest_reached);
    }
  }
  if (progress) progress->Finish();
  slices.Sync();
  common::WriteFloatImage(s.folder / "rho_d.exr", rho_d, /*half_precision=*/false, /*overwrite=*/true);
  common::WriteFloatImage(s.folder / "mask.exr", mask, false, true);
  common::WriteFloatImage(s.folder / "reach.exr", reach_map, false, true);
  const nlohmann::json statistics = {
      {"texels", texels}, {"valid_texels", valid_texels}, {"texels_without_dot_beneath", without_dot_beneath}};
  s.info.white_exitance_noise = options.white_exitance_noise;
  WriteManifest(s.folder, s.info, s.geometry, /*complete=*/true, statistics);
}


}  // namespace svbtdf::process
