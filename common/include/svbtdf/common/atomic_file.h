#pragma once
// Writing files so that nothing the user has is ever half-overwritten: the bytes go to a
// temporary file in the same folder, are flushed to disk, and only then renamed over the target.
// A crash leaves either the old file or the new one, never a mix.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

namespace svbtdf::common {

// Calls `write(temp_path)` to produce the file (an empty file is refused as a failed write), fsyncs it, renames it to `path` and fsyncs the
// folder. If `write` throws, the temporary file is removed and the exception propagates.
// With `overwrite == false` an existing `path` is an error (ErrorKind::kIo) and is left alone.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path& temp_path)>& write,
                         bool overwrite = true);

// Writes `bytes` as the whole file `path` the same way, every write(2) and the fsync checked and
// the file's size compared with `bytes` before the rename: a full disk is an error, never a
// short or empty file under the final name. Text, JSON and encoded images all go through here.
void WriteBytesAtomically(const std::filesystem::path& path, std::string_view bytes, bool overwrite = true);

// Convenience for text payloads (the same as WriteBytesAtomically).
void WriteTextAtomically(const std::filesystem::path& path, std::string_view contents,
                         bool overwrite = true);

// The checked primitives under the above, for the house's other durable files (the journals,
// the slice store): all `size` bytes at `offset` (or, with offset < 0, at the file's position),
// retrying short writes; fsync. Each is a durable operation (fault_injection.h), and a failure
// throws Error(kIo) naming `path` with the system's reason.
void WriteAllOrThrow(int fd, const void* data, size_t size, const std::filesystem::path& path, int64_t offset = -1);
void SyncOrThrow(int fd, const std::filesystem::path& path);

// Removes the temporary files and staging folders that an interrupted atomic write leaves in
// `folder` (".NAME.tmp-*", at any depth); returns how many were removed. Call it only while
// holding the folder's lock (folder_lock.h).
int RemoveStaleTemporaryFiles(const std::filesystem::path& folder);

// Creates the folder `folder` whole: `fill(staging)` builds it under a hidden temporary sibling
// (PARENT/.NAME.tmp-*), which is then fsynced and renamed to `folder` (absent, or an empty folder).
// A kill leaves at most the hidden sibling, never a half-made `folder`; the next call removes
// such leftovers of `folder` (callers hold the folder's lock, folder_lock.h). Parents are created.
void CreateFolderAtomically(const std::filesystem::path& folder,
                            const std::function<void(const std::filesystem::path& staging)>& fill);

// Free bytes available to an unprivileged writer at `folder` or, when it does not exist yet, at
// its first existing ancestor. Throws Error(kIo) naming the folder when the system cannot tell.
uint64_t FreeSpaceAt(const std::filesystem::path& folder);

// Reads a whole file; throws an Io error naming the file when it cannot.
std::string ReadTextFile(const std::filesystem::path& path);

// `mat/` and `mat//` name the folder `mat`: whatever is named after an output folder (its
// `.work` sibling, its checkpoint) must not depend on how the user typed it. "/" stays "/".
std::filesystem::path WithoutTrailingSeparators(const std::filesystem::path& path);

}  // namespace svbtdf::common
