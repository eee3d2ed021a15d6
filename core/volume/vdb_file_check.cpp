#include "volume/vdb_file_check.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <openvdb/version.h>

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
        for (int32_t i = 0; i < count; ++i) {
            if (!sized("metadata name")) return false;
            const size_t type_at = at + 4;
            if (!sized("metadata type name")) return false;
            const std::string type(bytes.data() + type_at, at - type_at);
            const size_t value_at = at;
            if (!sized("metadata value")) return false;
            // OpenVDB reads a value of a known fixed-size type at its own size, whatever the file
            // declares: a size that differs would shift every field after it.
            const size_t declared = at - value_at - 4, fixed = fixed_value_size(type);
            if (fixed && declared != fixed)
                return fail("a " + type + " metadata value declares " + std::to_string(declared) +
                            " bytes; a " + type + " has " + std::to_string(fixed));
        }
        return true;
    }
    // OpenVDB's registered fixed-size metadata types (openvdb/Metadata.h, math/*); 0: other.
    static size_t fixed_value_size(const std::string& type) {
        static const std::pair<const char*, size_t> kSizes[] = {
            {"bool", 1},   {"float", 4},  {"double", 8}, {"int32", 4},
            {"int64", 8},  {"vec2i", 8},  {"vec2s", 8},  {"vec2d", 16},
            {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}, {"vec4i", 16},
            {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};
        for (const auto& [name, size] : kSizes)
            if (type == name) return size;
        return 0;
    }
};

size_t linear_map_bytes(const std::string& type) {
    static const std::pair<const char*, size_t> kMaps[] = {{"AffineMap", 128},
                                                           {"UnitaryMap", 128},
                                                           {"ScaleMap", 5 * 24},
                                                           {"UniformScaleMap", 5 * 24},
                                                           {"TranslationMap", 24},
                                                           {"ScaleTranslateMap", 6 * 24},
                                                           {"UniformScaleTranslateMap", 6 * 24}};
    for (const auto& [name, bytes] : kMaps)
        if (type == name) return bytes;
    return 0;
}

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
    // Older layouts (before OpenVDB 2.0, 2013) are not walked, and OpenVDB reads them with
    // the same unchecked sizes (fuzz_vdb: a version 103 header declared 1.7e9 metadata entries),
    // so they are refused; so are versions newer than the OpenVDB freqlab links.
    if (version < kVersionSelectiveCompression || version > uint32_t(openvdb::OPENVDB_FILE_VERSION))
        return "file format version " + std::to_string(version) + " is outside the " +
               std::to_string(kVersionSelectiveCompression) + " .. " +
               std::to_string(openvdb::OPENVDB_FILE_VERSION) +
               " this reader checks (re-save the file with a current OpenVDB)";
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
        if (!w.metadata("grid metadata")) return w.problem;
        const size_t type_at = w.at + 4;
        if (!w.sized("transform type name")) return w.problem;
        // The linear maps' data (math/Maps.h: so many Vec3d / a Mat4d), then the tree's buffer
        // count: OpenVDB warns on a count other than 1 and reads on into a corrupted heap
        // (fuzz_vdb: "double free or corruption"). Other maps end the walk.
        const size_t map_bytes =
            linear_map_bytes(std::string(w.bytes.data() + type_at, w.at - type_at));
        if (map_bytes) {
            if (w.left() < map_bytes + 4) return "the file ends inside grid " + std::to_string(g);
            w.at += map_bytes;
            int32_t buffers = 0;
            w.read(buffers, "tree");
            if (buffers != 1)
                return "grid " + std::to_string(g) + "'s tree declares " + std::to_string(buffers) +
                       " buffers; OpenVDB reads trees of 1";
        }
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
