#include "svbtdf/fit/slice_store_format.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "svbtdf/common/atomic_file.h"
#include "svbtdf/common/json.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/fault_injection.h"

namespace svbtdf::fit::store {
namespace fs = std::filesystem;
namespace {

nlohmann::json InfoToJson(const SliceStoreInfo& info) {
  return {{"texels_x", info.texels_x},     {"texels_y", info.texels_y},
          {"num_dots", info.num_dots},     {"light_resolution", info.light_resolution},
          {"tile_texels", info.tile_texels}, {"eta", info.eta},
          {"white_exitance_noise", info.white_exitance_noise}};
}

nlohmann::json VectorToJson(const model::Vec3& v) { return {v.x(), v.y(), v.z()}; }

model::Vec3 VectorFromJson(const nlohmann::json& j) {
  if (!j.is_array() || j.size() != 3) throw nlohmann::json::type_error::create(302, "a vector is 3 numbers", &j);
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

nlohmann::json GeometryToJson(const TexelGeometry& g) {
  nlohmann::json dots = nlohmann::json::array();
  for (const model::Vec3& p : g.dots) dots.push_back(VectorToJson(p));
  return {{"width_m", g.width_m},
          {"height_m", g.height_m},
          {"camera_centre", VectorToJson(g.camera_centre)},
          {"monitor_normal", VectorToJson(g.monitor_normal)},
          {"dots", dots}};
}

}  // namespace

File::File(const fs::path& path, int flags) : path_(path), fd_(::open(path.c_str(), flags | O_CLOEXEC, 0644)) {
  if (fd_ < 0) common::ThrowIoError(path.string(), std::string("cannot open: ") + std::strerror(errno));
}

File::~File() {
  if (fd_ >= 0) ::close(fd_);
}

void File::ReadAt(void* data, size_t bytes, uint64_t offset) const {
  auto* p = static_cast<char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::pread(fd_, p, bytes, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) common::ThrowIoError(path_.string(), n == 0 ? "is shorter than its manifest says" : std::strerror(errno));
    p += n, bytes -= n, offset += n;
  }
}

void File::WriteAt(const void* data, size_t bytes, uint64_t offset) const {
  common::WriteAllOrThrow(fd_, data, bytes, path_, static_cast<int64_t>(offset));
}

void File::Resize(uint64_t bytes) const {
  const std::string what = "cannot allocate " + std::to_string(bytes) + " bytes";
  common::FailOrKillIfInjected(path_.string(), what);
  if (::ftruncate(fd_, static_cast<off_t>(bytes)) != 0) common::ThrowSystemError(path_.string(), what, errno);
}

void File::Sync() const { common::SyncOrThrow(fd_, path_); }

uint64_t File::Size() const {
  struct stat st {};
  if (::fstat(fd_, &st) != 0) common::ThrowIoError(path_.string(), std::strerror(errno));
  return static_cast<uint64_t>(st.st_size);
}

int64_t NumTiles(const SliceStoreInfo& info) {
  const int64_t texels = static_cast<int64_t>(info.texels_x) * info.texels_y;
  return (texels + info.tile_texels - 1) / info.tile_texels;
}

uint64_t TileBytes(const SliceStoreInfo& info) {
  return static_cast<uint64_t>(info.num_dots) * info.tile_texels * 3 * sizeof(Half);
}

uint64_t SliceBytes(const model::Hemicube& grid) { return static_cast<uint64_t>(grid.num_cells()) * sizeof(Half); }

SliceStoreInfo InfoFromManifest(const nlohmann::json& j, const std::string& source) {
  SliceStoreInfo info;
  info.texels_x = common::IntegerAt(j, "texels_x", source);
  info.texels_y = common::IntegerAt(j, "texels_y", source);
  info.num_dots = common::IntegerAt(j, "num_dots", source);
  info.light_resolution = common::IntegerAt(j, "light_resolution", source);
  info.tile_texels = common::IntegerAt(j, "tile_texels", source);
  info.eta = j.value("eta", 0.0);
  info.provenance = j.value("provenance", nlohmann::json::object());
  if (!info.provenance.is_object()) common::ThrowFormatError(source, "has a \"provenance\" that is not an object");
  info.white_exitance_noise = WhiteExitanceNoiseFromManifest(j, source);
  return info;
}

std::array<double, 3> WhiteExitanceNoiseFromManifest(const nlohmann::json& manifest, const std::string& source) {
  std::array<double, 3> noise = {0.0, 0.0, 0.0};
  const auto found = manifest.find("white_exitance_noise");
  if (found == manifest.end()) return noise;
  const auto is_fraction = [](const nlohmann::json& v) {
    return v.is_number() && std::isfinite(v.get<double>()) && v.get<double>() >= 0 && v.get<double>() < 1;
  };
  if (!found->is_array() || found->size() != 3 || !std::all_of(found->begin(), found->end(), is_fraction)) {
    common::ThrowFormatError(source, "has a \"white_exitance_noise\" that is not three numbers in [0, 1)");
  }
  for (int c = 0; c < 3; ++c) noise[c] = (*found)[c].get<double>();
  return noise;
}

void CheckInfo(const SliceStoreInfo& info, const std::string& source) {
  if (info.texels_x <= 0 || info.texels_y <= 0 || info.num_dots <= 0 || info.tile_texels <= 0) {
    common::ThrowInvalidInput(source, "needs a positive texel grid, dot count and tile size");
  }
  const int r = info.light_resolution;
  if (r < 2 || (r & (r - 1)) != 0) {
    common::ThrowInvalidInput(source, "light hemicube resolution " + std::to_string(r) + " is not a power of two >= 2");
  }
}

void WriteManifest(const fs::path& folder, const SliceStoreInfo& info, const TexelGeometry& geometry, bool complete,
                   const nlohmann::json& statistics) {
  nlohmann::json manifest = InfoToJson(info);
  manifest["format"] = "svbtdf-processed";
  manifest["version"] = kSliceStoreFormatVersion;
  manifest["complete"] = complete;
  manifest["provenance"] = info.provenance;
  manifest["geometry"] = GeometryToJson(geometry);
  manifest["statistics"] = statistics;
  manifest["files"] = {{"samples", kSamples}, {"slices", kSlices}, {"calibration", kCalibration},
                       {"rho_d", kRhoD}, {"mask", kMask}, {"reach", kReach}};
  common::WriteTextAtomically(folder / kManifest, manifest.dump(2) + "\n");
}

nlohmann::json ReadManifest(const fs::path& folder) {
  const fs::path path = folder / kManifest;
  try {
    nlohmann::json manifest = common::ReadJsonFile(path);
    if (manifest.at("format") != "svbtdf-processed") common::ThrowFormatError(path.string(), "is not a processed session");
    if (manifest.at("version") != kSliceStoreFormatVersion) {
      common::ThrowFormatError(path.string(), "has version " + manifest.at("version").dump() + "; this svbtdf reads version " +
                                          std::to_string(kSliceStoreFormatVersion), "re-run 'svbtdf process'");
    }
    return manifest;
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(path.string(), std::string("is malformed: ") + e.what());
  }
}


bool CompleteFromManifest(const nlohmann::json& manifest, const std::string& source) {
  if (!manifest.contains("complete")) return false;
  const nlohmann::json& complete = manifest["complete"];
  if (!complete.is_boolean()) {
    common::ThrowFormatError(source, "has \"complete\": " + complete.dump() + ", which is neither true nor false");
  }
  return complete.get<bool>();
}

TexelGeometry GeometryFromManifest(const nlohmann::json& manifest, const std::string& source) {
  try {
    TexelGeometry g;
    const nlohmann::json& j = manifest.at("geometry");
    g.texels_x = common::IntegerAt(manifest, "texels_x", source);
    g.texels_y = common::IntegerAt(manifest, "texels_y", source);
    g.width_m = j.at("width_m").get<double>();
    g.height_m = j.at("height_m").get<double>();
    g.camera_centre = VectorFromJson(j.at("camera_centre"));
    g.monitor_normal = VectorFromJson(j.at("monitor_normal"));
    for (const nlohmann::json& p : j.at("dots")) g.dots.push_back(VectorFromJson(p));
    return g;
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError(source, std::string("has a malformed geometry: ") + e.what());
  }
}

}  // namespace svbtdf::fit::store
