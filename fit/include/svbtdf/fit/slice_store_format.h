#pragma once
// The slice store's files as bytes (docs/slice-store.md): the vocabulary that its writer
// (process/slice_store_writer.h) and its reader (slice_store.h) share, and nothing else uses.

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>

#include <nlohmann/json.hpp>

#include "svbtdf/fit/slice_store.h"
#include "svbtdf/model/hemicube.h"

namespace svbtdf::fit::store {

// The files of PROCESSED/.
inline constexpr char kManifest[] = "processed.json";
inline constexpr char kCalibration[] = "calibration.json";
inline constexpr char kSamples[] = "samples.f16";
inline constexpr char kSlices[] = "slices.f16";
inline constexpr char kProgress[] = "progress.jsonl";
inline constexpr char kRhoD[] = "rho_d.exr";
inline constexpr char kMask[] = "mask.exr";
inline constexpr char kReach[] = "reach.exr";

// "No valid measurement" in samples.f16.
inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

using Half = Eigen::half;

// A file descriptor that closes itself, with whole-buffer positioned reads and writes.
class File {
 public:
  File() = default;
  File(const std::filesystem::path& path, int flags);  // O_RDONLY, O_RDWR | O_CREAT, ...
  ~File();
  File(const File&) = delete;
  File& operator=(const File&) = delete;

  void ReadAt(void* data, size_t bytes, uint64_t offset) const;
  void WriteAt(const void* data, size_t bytes, uint64_t offset) const;
  void Resize(uint64_t bytes) const;
  void Sync() const;
  uint64_t Size() const;

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

int64_t NumTiles(const SliceStoreInfo& info);
// Bytes of one tile of samples.f16: [dot][texel in tile][RGB].
uint64_t TileBytes(const SliceStoreInfo& info);
// Bytes of one texel's slice in slices.f16.
uint64_t SliceBytes(const model::Hemicube& grid);

// Throws svbtdf::Error(kInvalidInput) naming `source` for a grid, dot count, tile size or light
// resolution no store can have.
void CheckInfo(const SliceStoreInfo& info, const std::string& source);

// processed.json. The manifest records the texel geometry (the camera centre and the dots in
// the sample frame), so that reading a store needs no calibration.
void WriteManifest(const std::filesystem::path& folder, const SliceStoreInfo& info, const TexelGeometry& geometry,
                   bool complete, const nlohmann::json& statistics);
// The manifest, its format and version checked (svbtdf::Error naming the file otherwise).
nlohmann::json ReadManifest(const std::filesystem::path& folder);
SliceStoreInfo InfoFromManifest(const nlohmann::json& manifest, const std::string& source);
// Whether the manifest says its processing finished ("complete"; absent means not). A value that
// is not true or false throws svbtdf::Error naming `source`.
bool CompleteFromManifest(const nlohmann::json& manifest, const std::string& source);
// SliceStoreInfo::white_exitance_noise: 0 where the manifest has none (stores written before it);
// anything but three numbers in [0, 1) throws svbtdf::Error naming `source`.
std::array<double, 3> WhiteExitanceNoiseFromManifest(const nlohmann::json& manifest, const std::string& source);
// `source` names the manifest in errors.
TexelGeometry GeometryFromManifest(const nlohmann::json& manifest, const std::string& source);

}  // namespace svbtdf::fit::store
