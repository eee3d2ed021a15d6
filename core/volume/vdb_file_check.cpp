#include "volume/vdb_file_check.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <vector>

namespace freqlab {

namespace {

// OpenVDB's constants (openvdb/version.h): the magic number and the file versions from which
// a field is present.
constexpr int64_t kMagic = 0x56444220;
constexpr uint32_t kVersionLibraryVersion = 211, kVersionGridOffsets = 212,
                   kVersionGridInstancing = 216, kVersionBoostUuid = 218,
                   kVersionSelectiveCompression = 220;

struct Walk {
    std::vector<char> bytes;
    size_t at = 0;
    std::string problem;  // set once

    size_t left() const { return at <= bytes.size() ? bytes.size() - at : 0; }
    bool fail(const std::string& what) {
        if (problem.empty()) problem = what + " at byte " + std::to_string(at);
        return false;
    }
    template <class T>
    bool read(T& v, const char* what) {
        if (left() < sizeof(T)) return fail(std::string("the file ends inside the ") + what);
        std::memcpy(&v, bytes.data() + at, sizeof(T));
        at += sizeof(T);
        return true;
    }
    // A uint32 byte count, then that many bytes (io::readString, Metadata::read).
    bool sized(const char* what) {
        uint32_t n = 0;
        if (!read(n, what)) return false;
        if (n > left())
            return fail(std::string("the ") + what + " declares " + std::to_string(n) +
                        " bytes but the file has " + std::to_string(left()) + " left");
        at += n;
        return true;
    }
    // MetaMap::readMeta: an int32 count of (name, type name, value) triples.
    bool metadata(const char* what) {
        int32_t count = 0;
        if (!read(count, what)) return false;
        // Each entry holds at least its three sizes.
        if (count < 0 || uint64_t(count) * 12 > left())
            return fail(std::string("the ") + what + " declares " + std::to_string(count) +
                        " entries");
        for (int32_t i = 0; i < count; ++i)
            if (!sized("metadata name") || !sized("metadata type name") || !sized("metadata value"))
                return false;
        return true;
    }
};

}  // namespace

std::string check_vdb_layout(const std::string& path) {
    Walk w;
    {
        std::ifstream in(path, std::ios::binary);
        if (!in) return "cannot open the file";
        w.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    int64_t magic = 0;
    uint32_t version = 0;
    if (!w.read(magic, "header")) return w.problem;
    if (magic != kMagic) return "not an OpenVDB file (no VDB magic number)";
    if (!w.read(version, "header")) return w.problem;
    // Older layouts are OpenVDB's alone to read (none of the fields below are checked).
    if (version < kVersionSelectiveCompression) return "";
    uint32_t library[2];
    char has_offsets = 0;
    if (version >= kVersionLibraryVersion && !w.read(library, "header")) return w.problem;
    if (version >= kVersionGridOffsets && !w.read(has_offsets, "header")) return w.problem;
    if (version >= kVersionBoostUuid) {
        if (w.left() < 36) return "the file ends inside the header's UUID";
        w.at += 36;
    }
    if (!w.metadata("file metadata")) return w.problem;
    int32_t grids = 0;
    if (!w.read(grids, "grid count")) return w.problem;
    if (grids < 0) return "negative grid count " + std::to_string(grids);
    for (int32_t g = 0; g < grids; ++g) {
        if (!w.sized("grid name") || !w.sized("grid type name")) return w.problem;
        if (version >= kVersionGridInstancing && !w.sized("grid's instance parent name"))
            return w.problem;
        int64_t offsets[3];  // the grid's data, its block data and its end
        if (!w.read(offsets, "grid descriptor")) return w.problem;
        uint32_t compression = 0;
        if (!w.read(compression, "grid compression")) return w.problem;
        if (!w.metadata("grid metadata") || !w.sized("transform type name")) return w.problem;
        // The grid's body cannot be walked field by field; its end offset skips it. Without
        // usable offsets (a stream), the grids after the first are OpenVDB's to check.
        const int64_t end = offsets[2];
        if (!has_offsets || end <= int64_t(w.at) || uint64_t(end) > w.bytes.size()) {
            if (has_offsets && uint64_t(end) > w.bytes.size())
                return "grid " + std::to_string(g) + " ends at byte " + std::to_string(end) +
                       " but the file has " + std::to_string(w.bytes.size());
            return "";
        }
        w.at = size_t(end);
    }
    return "";
}

}  // namespace freqlab
