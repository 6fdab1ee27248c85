#pragma once
// Checks an OpenEXR file's headers against the file's own size before OpenEXR reads them (private
// to common/). OpenEXR 3.1 believes what a header says: a 29-byte file whose string attribute
// claims 842 MB makes it allocate 842 MB, and a data window or tile of 2^30 pixels makes it
// allocate offset tables and tile buffers of that size, before it finds the file is short.
// Every claim checked here must fit in the bytes that follow it, so a damaged or hostile file is
// refused in one line naming it, at the cost of one pass over the headers (a few hundred bytes).

#include <cstdint>
#include <filesystem>
#include <string_view>

namespace svbtdf::common {

// True when `bytes` begin with OpenEXR's magic number (0x76 0x2f 0x31 0x01).
bool HasExrMagic(std::string_view bytes);

// Walks every header of the EXR file at `path` (single- and multi-part) and throws
// svbtdf::Error (kFormat) naming the file when an attribute's size, a preview's pixel count, a
// string vector's element, the data window, the channel list, the tile size or the chunk offset
// table claims more than the file holds or than RequireSaneImageSize allows.
void RequirePlausibleExrHeaders(const std::filesystem::path& path);

}  // namespace svbtdf::common
