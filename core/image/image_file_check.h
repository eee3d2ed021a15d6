// What freqlab checks of an image file before a decoder sees it (issue "Reliability": found by
// fuzz_env_exr). OpenEXR 3.1 trusts an attribute's declared size and allocates it before
// reading (a 24-byte file asked for gigabytes); decoders allocate width x height x channels
// from the header. Both are refused here with the file and the field named.
//
// | limit                     | value        | why                                            |
// |---------------------------|--------------|------------------------------------------------|
// | EXR attribute size        | <= file size | the value must be in the file                  |
// | EXR attribute/type names  | < 32 bytes   | OpenEXR's own limit (< 256 with the long-names |
// |                           |              | flag); longer ones it reads cut, then misreads |
// | known EXR attribute types | own size     | OpenEXR 3.1 reads them by type, not by the     |
// |                           |              | declared size (channel lists, previews too)    |
// | width x height x channels | <= 2^28      | 1 GB of floats: 8k x 4k RGBA fits, 16k x 8k not |
// | width x channels          | <= 2^20      | OpenImageIO buffers a whole compression chunk |
// |                           |              | (DWAB: 256 rows): 2 x 1e6 px asked for 2.3 GB |
#pragma once

#include <cstddef>
#include <filesystem>

namespace freqlab {

constexpr size_t kMaxImageValues = size_t(1) << 28;
constexpr size_t kMaxImageRowValues = size_t(1) << 20;

// Throws Error(file, "header" / "header.<attribute>", ...) when an OpenEXR file's attribute
// list does not fit in the file or reads otherwise than OpenEXR reads it; other formats pass
// (their decoders bound their reads). Returns the data window's pixel count (the first part's),
// or -1 when the file is no OpenEXR file or has no window.
long long check_exr_attributes(const std::filesystem::path& path);
// Throws Error(file, "resolution", ...) unless 0 < width, height and the values fit the limit.
void check_image_size(const std::filesystem::path& path, long long width, long long height,
                      long long channels);

}  // namespace freqlab
