#include "svbtdf/fit/slice_store.h"

#include <fcntl.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "svbtdf/common/error.h"
#include "svbtdf/fit/slice_store_format.h"

namespace svbtdf::fit {
namespace fs = std::filesystem;
using namespace store;

// ---------------------------------------------------------------------------------------------
// Geometry

// ---------------------------------------------------------------------------------------------
// Geometry

model::Vec3 TexelGeometry::TexelCentre(int64_t texel) const {
  const int64_t col = texel % texels_x, row = texel / texels_x;
  return {-0.5 * width_m + (col + 0.5) * width_m / texels_x, 0.5 * height_m - (row + 0.5) * height_m / texels_y, 0.0};
}

model::Vec3 TexelGeometry::View(int64_t texel) const { return (camera_centre - TexelCentre(texel)).normalized(); }

model::Vec3 TexelGeometry::Light(int64_t texel, int dot) const { return (dots[dot] - TexelCentre(texel)).normalized(); }

double TexelGeometry::DotCellArea() const {
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


// ---------------------------------------------------------------------------------------------
// Reader

struct SliceStore::Files {
  File samples, slices;
  double dot_cell_area = 1e-4;
  Files(const fs::path& folder) : samples(folder / kSamples, O_RDONLY), slices(folder / kSlices, O_RDONLY) {}
};

SliceStore SliceStore::Open(const fs::path& folder) {
  if (!fs::is_directory(folder)) {
    common::ThrowInvalidInput(folder.string(), "is not a folder", "give the output folder of 'svbtdf process'");
  }
  const nlohmann::json manifest = ReadManifest(folder);
  SliceStore store;
  store.folder_ = folder;
  try {
    store.info_ = InfoFromManifest(manifest, (folder / kManifest).string());
  } catch (const nlohmann::json::exception& e) {
    common::ThrowFormatError((folder / kManifest).string(), std::string("is malformed: ") + e.what());
  }
  CheckInfo(store.info_, (folder / kManifest).string());
  if (!CompleteFromManifest(manifest, (folder / kManifest).string())) {
    common::ThrowInvalidInput(folder.string(), "holds an unfinished processing", "re-run 'svbtdf process' to finish it");
  }
  store.geometry_ = GeometryFromManifest(manifest, (folder / kManifest).string());
  if (static_cast<int>(store.geometry_.dots.size()) != store.info_.num_dots) {
    common::ThrowFormatError((folder / kManifest).string(), "lists a different number of dots in its geometry than num_dots");
  }
  store.light_grid_ = model::Hemicube(store.info_.light_resolution);
  store.files_ = std::make_shared<Files>(folder);
  store.files_->dot_cell_area = store.geometry_.DotCellArea();
  if (store.files_->samples.Size() != NumTiles(store.info_) * TileBytes(store.info_)) {
    common::ThrowFormatError((folder / kSamples).string(), "has the wrong size for its manifest");
  }
  if (store.files_->slices.Size() != store.geometry_.num_texels() * SliceBytes(store.light_grid_)) {
    common::ThrowFormatError((folder / kSlices).string(), "has the wrong size for its manifest");
  }
  const auto read_map = [&](const char* name, int channels) {
    common::FloatImage map = common::ReadFloatImage(folder / name);
    if (map.width != store.info_.texels_x || map.height != store.info_.texels_y || map.channels != channels) {
      common::ThrowFormatError((folder / name).string(), "does not match the texel grid of processed.json");
    }
    // A NaN here would be fitted into a material that its own reader refuses.
    common::RequireFinite(map, (folder / name).string());
    return map;
  };
  store.rho_d_ = read_map(kRhoD, 3);
  store.mask_ = read_map(kMask, 1);
  store.reach_ = read_map(kReach, 1);
  return store;
}

void SliceStore::ReadTile(int64_t tile, std::vector<float>* out) const {
  if (tile < 0 || tile >= NumTiles(info_)) common::ThrowInvalidInput("tile", std::to_string(tile) + " is outside the store");
  std::vector<Half> raw(TileBytes(info_) / sizeof(Half));
  files_->samples.ReadAt(raw.data(), TileBytes(info_), static_cast<uint64_t>(tile) * TileBytes(info_));
  out->resize(raw.size());
  for (size_t k = 0; k < raw.size(); ++k) (*out)[k] = static_cast<float>(raw[k]);
}

void SliceStore::ReadSamples(int64_t texel, std::vector<float>* out) const {
  if (texel < 0 || texel >= geometry_.num_texels()) {
    common::ThrowInvalidInput("texel", std::to_string(texel) + " is outside the store");
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
    common::ThrowInvalidInput("texel", std::to_string(texel) + " is outside the store");
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
    common::ThrowInvalidInput("texel", std::to_string(texel) + " is outside the store");
  }
  const size_t tile_values = static_cast<size_t>(info_.num_dots) * info_.tile_texels * 3;
  if (tile_samples.size() != tile_values) {
    common::ThrowInvalidInput("tile samples", std::to_string(tile_samples.size()) + " values where a tile has " +
                                          std::to_string(tile_values));
  }
  const size_t k = static_cast<size_t>(texel % info_.tile_texels);
  return SliceFromSamples(texel, &tile_samples[3 * k], static_cast<size_t>(info_.tile_texels) * 3, use_dot);
}

TexelSlice SliceStore::SliceFromSamples(int64_t texel, const float* rgb, size_t dot_stride,
                                        const std::vector<bool>& use_dot) const {
  const model::Vec3 x = geometry_.TexelCentre(texel);
  const int col = static_cast<int>(texel % info_.texels_x), row = static_cast<int>(texel / info_.texels_x);
  const model::Rgb rho_d = {rho_d_.at(col, row, 0), rho_d_.at(col, row, 1), rho_d_.at(col, row, 2)};
  TexelSlice slice;
  slice.view = geometry_.View(texel);
  // Room for every dot at once: grown one sample at a time, the six arrays were reallocated about
  // eleven times each per texel at 1,600 dots.
  const size_t dots = static_cast<size_t>(info_.num_dots);
  slice.light.reserve(dots);
  slice.rho.reserve(dots);
  slice.rho_rgb.reserve(dots);
  slice.measured_rgb.reserve(dots);
  slice.dot.reserve(dots);
  slice.solid_angle.reserve(dots);
  for (int q = 0; q < info_.num_dots; ++q) {
    if (!use_dot.empty() && !use_dot[q]) continue;
    const float* r = rgb + q * dot_stride;
    if (!std::isfinite(r[0]) || !std::isfinite(r[1]) || !std::isfinite(r[2])) continue;
    const model::Vec3 to_dot = geometry_.dots[q] - x;
    const model::Vec3 i = to_dot.normalized();
    const model::Rgb refractive = {std::max(0.0, r[0] - rho_d[0]), std::max(0.0, r[1] - rho_d[1]),
                            std::max(0.0, r[2] - rho_d[2])};
    slice.light.push_back(i);
    slice.rho.push_back(model::Luminance(refractive));
    slice.rho_rgb.push_back(refractive);
    slice.measured_rgb.push_back({r[0], r[1], r[2]});
    slice.dot.push_back(q);
    slice.solid_angle.push_back(files_->dot_cell_area * std::abs(i.z()) / to_dot.squaredNorm());
  }
  return slice;
}

}  // namespace svbtdf::fit
