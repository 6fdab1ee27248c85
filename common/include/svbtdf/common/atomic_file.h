#pragma once
// Writing files so that nothing the user has is ever half-overwritten: the bytes go to a
// temporary file in the same folder, are flushed to disk, and only then renamed over the target.
// A crash leaves either the old file or the new one, never a mix.

#include <filesystem>
#include <functional>
#include <string_view>

namespace svbtdf::common {

// Calls `write(temp_path)` to produce the file, fsyncs it, renames it to `path` and fsyncs the
// folder. If `write` throws, the temporary file is removed and the exception propagates.
// With `overwrite == false` an existing `path` is an error (ErrorKind::kIo) and is left alone.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path& temp_path)>& write,
                         bool overwrite = true);

// Convenience for text and small binary payloads.
void WriteTextAtomically(const std::filesystem::path& path, std::string_view contents,
                         bool overwrite = true);

// Reads a whole file; throws an Io error naming the file when it cannot.
std::string ReadTextFile(const std::filesystem::path& path);

// `mat/` and `mat//` name the folder `mat`: whatever is named after an output folder (its
// `.work` sibling, its checkpoint) must not depend on how the user typed it. "/" stays "/".
std::filesystem::path WithoutTrailingSeparators(const std::filesystem::path& path);

}  // namespace svbtdf::common
