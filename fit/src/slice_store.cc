#include "svbtdf/fit/slice_store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Core>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/parallel.h"
#include "svbtdf/common/progress.h"
#include "svbtdf/fit/push_pull.h"

namespace svbtdf::fit {
namespace fs = std::filesystem;
namespace {

constexpr char kManifest[] = "processed.json";
constexpr char kCalibration[] = "calibration.json";
constexpr char kSamples[] = "samples.f16";
constexpr char kSlices[] = "slices.f16";
constexpr char kProgress[] = "progress.jsonl";
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

using Half = Eigen::half;

// A file descriptor that closes itself.
class File {
 public:
  File() = default;
  File(const fs::path& path, int flags) : path_(path), fd_(::open(path.c_str(), flags | O_CLOEXEC, 0644)) {
    if (fd_ < 0) ThrowIoError(path.string(), std::string("cannot open: ") + std::strerror(errno));
  }
  ~File() {
    if (fd_ >= 0) ::close(fd_);
  }
  File(const File&) = delete;
  File& operator=(const File&) = delete;

  void ReadAt(void* data, size_t bytes, uint64_t offset) const {
    auto* p = static_cast<char*>(data);
    while (bytes > 0) {
      const ssize_t n = ::pread(fd_, p, bytes, static_cast<off_t>(offset));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) ThrowIoError(path_.string(), n == 0 ? "is shorter than its manifest says" : std::strerror(errno));
      p += n, bytes -= n, offset += n;
    }
  }
  void WriteAt(const void* data, size_t bytes, uint64_t offset) const {
    const auto* p = static_cast<const char*>(data);
    while (bytes > 0) {
      const ssize_t n = ::pwrite(fd_, p, bytes, static_cast<off_t>(offset));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) ThrowIoError(path_.string(), std::string("cannot write: ") + std::strerror(errno), "is the disk full?");
      p += n, bytes -= n, offset += n;
    }
  }
  void Resize(uint64_t bytes) const {
    if (::ftruncate(fd_, static_cast<off_t>(bytes)) != 0) {
      ThrowIoError(path_.string(), std::string("cannot allocate: ") + std::strerror(errno), "is the disk full?");
    }
  }
  void Sync() const {
    if (::fdatasync(fd_) != 0) ThrowIoError(path_.string(), std::string("cannot sync: ") + std::strerror(errno));
  }
  uint64_t Size() const {
    struct stat st {};
    if (::fstat(fd_, &st) != 0) ThrowIoError(path_.string(), std::strerror(errno));
    return static_cast<uint64_t>(st.st_size);
  }

 private:
  fs::path path_;
  int fd_ = -1;
};

int64_t NumTiles(const SliceStoreInfo& info) {
  const int64_t texels = static_cast<int64_t>(info.texels_x) * info.texels_y;
  return (texels + info.tile_texels - 1) / info.tile_texels;
}

// Bytes of one tile of samples.f16: [dot][texel in tile][RGB].
uint64_t TileBytes(const SliceStoreInfo& info) {
  return static_cast<uint64_t>(info.num_dots) * info.tile_texels * 3 * sizeof(Half);
}

uint64_t SliceBytes(const Hemicube& grid) { return static_cast<uint64_t>(grid.num_cells()) * sizeof(Half); }

nlohmann::json InfoToJson(const SliceStoreInfo& info) {
  return {{"texels_x", info.texels_x},     {"texels_y", info.texels_y},
          {"num_dots", info.num_dots},     {"light_resolution", info.light_resolution},
          {"tile_texels", info.tile_texels}, {"eta", info.eta}};
}

SliceStoreInfo InfoFromJson(const nlohmann::json& j) {
  SliceStoreInfo info;
  info.texels_x = j.at("texels_x").get<int>();
  info.texels_y = j.at("texels_y").get<int>();
  info.num_dots = j.at("num_dots").get<int>();
  info.light_resolution = j.at("light_resolution").get<int>();
  info.tile_texels = j.at("tile_texels").get<int>();
  info.eta = j.value("eta", 0.0);
  info.provenance = j.value("provenance", nlohmann::json::object());
  return info;
}

void CheckInfo(const SliceStoreInfo& info, const std::string& source) {
  if (info.texels_x <= 0 || info.texels_y <= 0 || info.num_dots <= 0 || info.tile_texels <= 0) {
    ThrowInvalidInput(source, "needs a positive texel grid, dot count and tile size");
  }
  const int r = info.light_resolution;
  if (r < 2 || (r & (r - 1)) != 0) {
    ThrowInvalidInput(source, "light hemicube resolution " + std::to_string(r) + " is not a power of two >= 2");
  }
}

void WriteManifest(const fs::path& folder, const SliceStoreInfo& info, bool complete, const nlohmann::json& statistics) {
  nlohmann::json manifest = InfoToJson(info);
  manifest["format"] = "svbtdf-processed";
  manifest["version"] = kSliceStoreFormatVersion;
  manifest["complete"] = complete;
  manifest["provenance"] = info.provenance;
  manifest["statistics"] = statistics;
  manifest["files"] = {{"samples", kSamples}, {"slices", kSlices}, {"calibration", kCalibration},
                       {"rho_d", "rho_d.exr"}, {"mask", "mask.exr"}};
  WriteTextAtomically(folder / kManifest, manifest.dump(2) + "\n");
}

nlohmann::json ReadManifest(const fs::path& folder) {
  const fs::path path = folder / kManifest;
  try {
    nlohmann::json manifest = nlohmann::json::parse(ReadTextFile(path));
    if (manifest.at("format") != "svbtdf-processed") ThrowFormatError(path.string(), "is not a processed session");
    if (manifest.at("version") != kSliceStoreFormatVersion) {
      ThrowFormatError(path.string(), "has version " + manifest.at("version").dump() + "; this svbtdf reads version " +
                                          std::to_string(kSliceStoreFormatVersion), "re-run 'svbtdf process'");
    }
    return manifest;
  } catch (const nlohmann::json::exception& e) {
    ThrowFormatError(path.string(), std::string("is malformed: ") + e.what());
  }
}

// Typical solid angle of the monitor area one dot stands for, seen from x: the dot grid's cell
// area (median nearest-neighbour spacing squared) foreshortened and over distance squared.
double DotCellArea(const std::vector<Vec3>& dots) {
  if (dots.size() < 2) return 1e-4;
  std::vector<double> nearest;
  for (size_t a = 0; a < dots.size(); ++a) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t b = 0; b < dots.size(); ++b) {
      if (a != b) best = std::min(best, (dots[a] - dots[b]).squaredNorm());
    }
    nearest.push_back(best);
  }
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  return nearest[nearest.size() / 2];
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Geometry

Vec3 TexelGeometry::TexelCentre(int64_t texel) const {
  const int64_t col = texel % texels_x, row = texel / texels_x;
  return {-0.5 * width_m + (col + 0.5) * width_m / texels_x, 0.5 * height_m - (row + 0.5) * height_m / texels_y, 0.0};
}

Vec3 TexelGeometry::View(int64_t texel) const { return (camera_centre - TexelCentre(texel)).normalized(); }

Vec3 TexelGeometry::Light(int64_t texel, int dot) const { return (dots[dot] - TexelCentre(texel)).normalized(); }

TexelGeometry MakeTexelGeometry(const calib::SessionCalibration& calibration, int texels_x, int texels_y) {
  TexelGeometry g;
  g.texels_x = texels_x;
  g.texels_y = texels_y;
  g.width_m = calibration.sample_plane.width_m;
  g.height_m = calibration.sample_plane.height_m;
  g.camera_centre = calibration.sample_plane.CameraCentre();
  for (const calib::DotPosition& dot : calibration.monitor.dots) g.dots.push_back(dot.position);
  return g;
}

// ---------------------------------------------------------------------------------------------
// Reader

struct SliceStore::Files {
  File samples, slices;
  double dot_cell_area = 1e-4;
  Files(const fs::path& folder) : samples(folder / kSamples, O_RDONLY), slices(folder / kSlices, O_RDONLY) {}
};

SliceStore SliceStore::Open(const fs::path& folder) {
  if (!fs::is_directory(folder)) {
    ThrowInvalidInput(folder.string(), "is not a folder", "give the output folder of 'svbtdf process'");
  }
  const nlohmann::json manifest = ReadManifest(folder);
  SliceStore store;
  store.folder_ = folder;
  try {
    store.info_ = InfoFromJson(manifest);
  } catch (const nlohmann::json::exception& e) {
    ThrowFormatError((folder / kManifest).string(), std::string("is malformed: ") + e.what());
  }
  CheckInfo(store.info_, (folder / kManifest).string());
  if (!manifest.value("complete", false)) {
    ThrowInvalidInput(folder.string(), "holds an unfinished processing", "re-run 'svbtdf process' to finish it");
  }
  store.calibration_ = calib::ReadSessionCalibration(folder / kCalibration);
  if (static_cast<int>(store.calibration_.monitor.dots.size()) != store.info_.num_dots) {
    ThrowFormatError((folder / kCalibration).string(), "lists a different number of dots than processed.json");
  }
  store.geometry_ = MakeTexelGeometry(store.calibration_, store.info_.texels_x, store.info_.texels_y);
  store.light_grid_ = Hemicube(store.info_.light_resolution);
  store.files_ = std::make_shared<Files>(folder);
  store.files_->dot_cell_area = DotCellArea(store.geometry_.dots);
  if (store.files_->samples.Size() != NumTiles(store.info_) * TileBytes(store.info_)) {
    ThrowFormatError((folder / kSamples).string(), "has the wrong size for its manifest");
  }
  if (store.files_->slices.Size() != store.geometry_.num_texels() * SliceBytes(store.light_grid_)) {
    ThrowFormatError((folder / kSlices).string(), "has the wrong size for its manifest");
  }
  const auto read_map = [&](const char* name, int channels) {
    FloatImage map = ReadFloatImage(folder / name);
    if (map.width != store.info_.texels_x || map.height != store.info_.texels_y || map.channels != channels) {
      ThrowFormatError((folder / name).string(), "does not match the texel grid of processed.json");
    }
    return map;
  };
  store.rho_d_ = read_map("rho_d.exr", 3);
  store.mask_ = read_map("mask.exr", 1);
  return store;
}

void SliceStore::ReadTile(int64_t tile, std::vector<float>* out) const {
  if (tile < 0 || tile >= NumTiles(info_)) ThrowInvalidInput("tile", std::to_string(tile) + " is outside the store");
  std::vector<Half> raw(TileBytes(info_) / sizeof(Half));
  files_->samples.ReadAt(raw.data(), TileBytes(info_), static_cast<uint64_t>(tile) * TileBytes(info_));
  out->resize(raw.size());
  for (size_t k = 0; k < raw.size(); ++k) (*out)[k] = static_cast<float>(raw[k]);
}

void SliceStore::ReadSamples(int64_t texel, std::vector<float>* out) const {
  if (texel < 0 || texel >= geometry_.num_texels()) {
    ThrowInvalidInput("texel", std::to_string(texel) + " is outside the store");
  }
  const int64_t tile = texel / info_.tile_texels, k = texel % info_.tile_texels;
  const uint64_t base = static_cast<uint64_t>(tile) * TileBytes(info_);
  const uint64_t dot_stride = static_cast<uint64_t>(info_.tile_texels) * 3 * sizeof(Half);
  out->resize(static_cast<size_t>(info_.num_dots) * 3);
  Half rgb[3];
  for (int q = 0; q < info_.num_dots; ++q) {
    files_->samples.ReadAt(rgb, sizeof(rgb), base + q * dot_stride + k * 3 * sizeof(Half));
    for (int c = 0; c < 3; ++c) (*out)[3 * q + c] = static_cast<float>(rgb[c]);
  }
}

void SliceStore::ReadSlice(int64_t texel, float* out) const {
  if (texel < 0 || texel >= geometry_.num_texels()) {
    ThrowInvalidInput("texel", std::to_string(texel) + " is outside the store");
  }
  std::vector<Half> raw(light_grid_.num_cells());
  files_->slices.ReadAt(raw.data(), SliceBytes(light_grid_), static_cast<uint64_t>(texel) * SliceBytes(light_grid_));
  for (size_t k = 0; k < raw.size(); ++k) out[k] = static_cast<float>(raw[k]);
}

TexelSlice SliceStore::MakeTexelSlice(int64_t texel, const std::vector<bool>& use_dot) const {
  std::vector<float> samples;
  ReadSamples(texel, &samples);
  return SliceFromSamples(texel, samples.data(), 3, use_dot);
}

TexelSlice SliceStore::MakeTexelSlice(int64_t texel, const std::vector<float>& tile_samples,
                                      const std::vector<bool>& use_dot) const {
  if (texel < 0 || texel >= geometry_.num_texels()) {
    ThrowInvalidInput("texel", std::to_string(texel) + " is outside the store");
  }
  const size_t tile_values = static_cast<size_t>(info_.num_dots) * info_.tile_texels * 3;
  if (tile_samples.size() != tile_values) {
    ThrowInvalidInput("tile samples", std::to_string(tile_samples.size()) + " values where a tile has " +
                                          std::to_string(tile_values));
  }
  const size_t k = static_cast<size_t>(texel % info_.tile_texels);
  return SliceFromSamples(texel, &tile_samples[3 * k], static_cast<size_t>(info_.tile_texels) * 3, use_dot);
}

TexelSlice SliceStore::SliceFromSamples(int64_t texel, const float* rgb, size_t dot_stride,
                                        const std::vector<bool>& use_dot) const {
  const Vec3 x = geometry_.TexelCentre(texel);
  const int col = static_cast<int>(texel % info_.texels_x), row = static_cast<int>(texel / info_.texels_x);
  const Rgb rho_d = {rho_d_.at(col, row, 0), rho_d_.at(col, row, 1), rho_d_.at(col, row, 2)};
  TexelSlice slice;
  slice.view = geometry_.View(texel);
  for (int q = 0; q < info_.num_dots; ++q) {
    if (!use_dot.empty() && !use_dot[q]) continue;
    const float* r = rgb + q * dot_stride;
    if (!std::isfinite(r[0]) || !std::isfinite(r[1]) || !std::isfinite(r[2])) continue;
    const Vec3 to_dot = geometry_.dots[q] - x;
    const Vec3 i = to_dot.normalized();
    const Rgb refractive = {std::max(0.0, r[0] - rho_d[0]), std::max(0.0, r[1] - rho_d[1]),
                            std::max(0.0, r[2] - rho_d[2])};
    slice.light.push_back(i);
    slice.rho.push_back(Luminance(refractive));
    slice.rho_rgb.push_back(refractive);
    slice.solid_angle.push_back(files_->dot_cell_area * std::abs(i.z()) / to_dot.squaredNorm());
  }
  return slice;
}

// ---------------------------------------------------------------------------------------------
// Writer

struct SliceStoreWriter::State {
  fs::path folder;
  SliceStoreInfo info;
  calib::SessionCalibration calibration;
  TexelGeometry geometry;
  std::unique_ptr<File> samples;
  std::set<int> dots_done;
};

namespace {

bool FolderIsEmpty(const fs::path& folder) { return fs::is_directory(folder) && fs::is_empty(folder); }

std::set<int> ReadProgress(const fs::path& path) {
  std::set<int> done;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    // A crash can cut the last line short: only complete lines count.
    try {
      done.insert(nlohmann::json::parse(line).at("dot").get<int>());
    } catch (const nlohmann::json::exception&) {
    }
  }
  return done;
}

void AppendLineSynced(const fs::path& path, const std::string& line) {
  const File file(path, O_WRONLY | O_CREAT | O_APPEND);
  const std::string text = line + "\n";
  file.WriteAt(text.data(), text.size(), 0);  // O_APPEND: the offset is ignored
  file.Sync();
}

}  // namespace

SliceStoreWriter::SliceStoreWriter(const fs::path& folder, const SliceStoreInfo& info,
                                   const calib::SessionCalibration& calibration)
    : state_(std::make_unique<State>()) {
  CheckInfo(info, folder.string());
  if (static_cast<int>(calibration.monitor.dots.size()) != info.num_dots) {
    ThrowInvalidInput(folder.string(), "the calibration lists " + std::to_string(calibration.monitor.dots.size()) +
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
    if (manifest.value("complete", false)) {
      ThrowInvalidInput(folder.string(), "already holds a finished processing", "choose a new output folder");
    }
    const nlohmann::json calibration_on_disk = nlohmann::json::parse(ReadTextFile(folder / kCalibration));
    if (manifest.at("texels_x") != info.texels_x || manifest.at("texels_y") != info.texels_y ||
        manifest.at("num_dots") != info.num_dots || manifest.at("light_resolution") != info.light_resolution ||
        manifest.at("tile_texels") != info.tile_texels || calibration_on_disk != calib::ToJson(calibration)) {
      ThrowInvalidInput(folder.string(), "holds an unfinished processing with other settings or another calibration",
                        "finish it with the same options, or choose a new output folder");
    }
    s.samples = std::make_unique<File>(folder / kSamples, O_RDWR);
    if (s.samples->Size() != bytes) ThrowFormatError((folder / kSamples).string(), "has the wrong size to resume");
    s.dots_done = ReadProgress(folder / kProgress);
    return;
  }
  if (fs::exists(folder) && !FolderIsEmpty(folder)) {
    ThrowInvalidInput(folder.string(), "is not empty and holds no unfinished processing", "choose a new output folder");
  }
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) ThrowIoError(folder.string(), "cannot create: " + error.message(), "is the folder writable?");
  calib::WriteSessionCalibration(folder / kCalibration, calibration);
  s.samples = std::make_unique<File>(folder / kSamples, O_RDWR | O_CREAT | O_TRUNC);
  s.samples->Resize(bytes);  // sparse until written
  WriteManifest(folder, info, /*complete=*/false, nlohmann::json::object());
}

SliceStoreWriter::~SliceStoreWriter() = default;
SliceStoreWriter::SliceStoreWriter(SliceStoreWriter&&) noexcept = default;

bool SliceStoreWriter::HasDot(int dot) const { return state_->dots_done.count(dot) > 0; }

void SliceStoreWriter::WriteDot(int dot, const std::vector<float>& rgb) {
  State& s = *state_;
  const int64_t texels = s.geometry.num_texels();
  if (dot < 0 || dot >= s.info.num_dots) ThrowInvalidInput("dot", std::to_string(dot) + " is outside the store");
  if (static_cast<int64_t>(rgb.size()) != 3 * texels) {
    ThrowInvalidInput("dot " + std::to_string(dot), "has " + std::to_string(rgb.size()) + " values for " +
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
  s.samples->Sync();
  AppendLineSynced(s.folder / kProgress, nlohmann::json{{"dot", dot}}.dump());
  s.dots_done.insert(dot);
}

namespace {

struct TexelSummary {
  Rgb rho_d = {0, 0, 0};
  bool valid = false;
  int samples = 0;
};

// Diffuse separation (paper eq. 14) and the resampled refractive slice of one texel.
TexelSummary SummariseTexel(const TexelGeometry& geometry, int64_t texel, const float* tile, int tile_texels,
                            int64_t k, int num_dots, const PushPullResampler& resampler,
                            const SliceStoreWriter::FinishOptions& options, std::vector<float>* cells) {
  const Vec3 x = geometry.TexelCentre(texel);
  std::vector<Vec3> light;
  std::vector<Rgb> rgb;
  std::vector<double> pixel_value;  // proportional to the camera's I_q(x): R |i.z| / r^2
  for (int q = 0; q < num_dots; ++q) {
    const float* r = tile + (static_cast<int64_t>(q) * tile_texels + k) * 3;
    if (!std::isfinite(r[0]) || !std::isfinite(r[1]) || !std::isfinite(r[2])) continue;
    const Vec3 to_dot = geometry.dots[q] - x;
    light.push_back(to_dot.normalized());
    rgb.push_back({r[0], r[1], r[2]});
    pixel_value.push_back(Luminance(rgb.back()) * std::abs(light.back().z()) / to_dot.squaredNorm());
  }
  TexelSummary summary;
  summary.samples = static_cast<int>(light.size());
  cells->assign(resampler.grid().num_cells(), 0.0f);
  if (summary.samples == 0) return summary;
  double mean = 0;
  for (double v : pixel_value) mean += v;
  mean /= pixel_value.size();
  summary.rho_d = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::infinity()};
  bool any_bright = false;
  for (size_t s = 0; s < rgb.size(); ++s) {
    if (pixel_value[s] <= options.diffuse_threshold * mean) continue;
    any_bright = true;
    for (int c = 0; c < 3; ++c) summary.rho_d[c] = std::min(summary.rho_d[c], rgb[s][c]);
  }
  for (double& d : summary.rho_d) d = any_bright ? std::max(0.0, d) : 0.0;
  std::vector<float> values(rgb.size()), weights(rgb.size(), 1.0f);
  double peak = 0;
  for (size_t s = 0; s < rgb.size(); ++s) {
    values[s] = static_cast<float>(std::max(0.0, Luminance(rgb[s]) - Luminance(summary.rho_d)));
    peak = std::max(peak, static_cast<double>(values[s]));
  }
  std::vector<float> confidence;
  resampler.Resample(light, values, weights, cells, &confidence);
  summary.valid = summary.samples >= options.min_valid_dots && peak > 0;
  return summary;
}

}  // namespace

void SliceStoreWriter::Finish(const FinishOptions& options) {
  State& s = *state_;
  for (int q = 0; q < s.info.num_dots; ++q) {
    if (!HasDot(q)) ThrowInvalidInput(s.folder.string(), "is missing dot " + std::to_string(q), "process every dot first");
  }
  const Hemicube light_grid(s.info.light_resolution);
  const PushPullResampler resampler(light_grid);
  const int64_t texels = s.geometry.num_texels();
  const File slices(s.folder / kSlices, O_RDWR | O_CREAT | O_TRUNC);
  FloatImage rho_d(s.info.texels_x, s.info.texels_y, 3), mask(s.info.texels_x, s.info.texels_y, 1);
  int64_t valid_texels = 0;
  std::unique_ptr<ProgressBar> progress;
  if (options.progress) progress = std::make_unique<ProgressBar>("separate and resample", texels, "texels");
  std::vector<Half> tile_raw(TileBytes(s.info) / sizeof(Half));
  std::vector<float> tile(tile_raw.size());
  for (int64_t t = 0; t < NumTiles(s.info); ++t) {
    s.samples->ReadAt(tile_raw.data(), TileBytes(s.info), t * TileBytes(s.info));
    for (size_t k = 0; k < tile.size(); ++k) tile[k] = static_cast<float>(tile_raw[k]);
    const int64_t begin = t * s.info.tile_texels, end = std::min(texels, begin + s.info.tile_texels);
    std::vector<Half> slice_out((end - begin) * light_grid.num_cells());
    std::vector<TexelSummary> summaries(end - begin);
    ParallelFor(end - begin, options.threads, 16, [&](int64_t a, int64_t b) {
      std::vector<float> cells;
      for (int64_t k = a; k < b; ++k) {
        summaries[k] = SummariseTexel(s.geometry, begin + k, tile.data(), s.info.tile_texels, k, s.info.num_dots,
                                      resampler, options, &cells);
        for (size_t c = 0; c < cells.size(); ++c) slice_out[k * cells.size() + c] = Half(cells[c]);
      }
    });
    slices.WriteAt(slice_out.data(), slice_out.size() * sizeof(Half), begin * SliceBytes(light_grid));
    for (int64_t k = 0; k < end - begin; ++k) {
      const int col = static_cast<int>((begin + k) % s.info.texels_x), row = static_cast<int>((begin + k) / s.info.texels_x);
      for (int c = 0; c < 3; ++c) rho_d.at(col, row, c) = static_cast<float>(summaries[k].rho_d[c]);
      mask.at(col, row) = summaries[k].valid ? 1.0f : 0.0f;
      valid_texels += summaries[k].valid;
    }
    if (progress) progress->Advance(end - begin);
  }
  if (progress) progress->Finish();
  slices.Sync();
  WriteFloatImage(s.folder / "rho_d.exr", rho_d, /*half_precision=*/false, /*overwrite=*/true);
  WriteFloatImage(s.folder / "mask.exr", mask, false, true);
  const nlohmann::json statistics = {{"texels", texels}, {"valid_texels", valid_texels}};
  WriteManifest(s.folder, s.info, /*complete=*/true, statistics);
}

}  // namespace svbtdf::fit
