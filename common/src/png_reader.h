#pragma once
// Reading camera frames from PNG with libpng directly (private to common/): OpenImageIO's PNG
// reader leaves libpng's default error handler in place, which prints "libpng error: ..." on
// stderr before svbtdf's own one-line error. Here every libpng message becomes the Error's text.

#include <filesystem>

#include "svbtdf/common/image_io.h"

namespace svbtdf::common {

// Throws svbtdf::Error (kIo, kFormat) naming the file; values as ReadCameraImage documents.
CameraImage ReadPngCameraImage(const std::filesystem::path& path);

// The one check that an image file is there, for every image reader: "does not exist", or what
// stat said (a symlink loop, a folder without search permission), naming the file.
void RequireExistingFile(const std::filesystem::path& path);

// The one bound on what a header may claim (2^30 samples), for every image reader.
void RequireSaneImageSize(const std::filesystem::path& path, int64_t width, int64_t height, int channels);

}  // namespace svbtdf::common
