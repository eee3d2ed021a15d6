#include "volume/vdb_file_check.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <blosc.h>
#include <openvdb/version.h>

namespace freqlab {

namespace {

// OpenVDB's constants (openvdb/version.h): the magic number and the file versions from which
// a field is present.
constexpr int64_t kMagic = 0x56444220;
constexpr uint32_t kVersionLibraryVersion = 211, kVersionGridOffsets = 212,
                   kVersionGridInstancing = 216, kVersionBoostUuid = 218,
                   kVersionNodeMaskCompression = 222;

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
            const size_t name_at = at;
            if (!sized("metadata name")) return false;
            // OpenVDB throws on an empty name mid-map, and its Stream reads on from there.
            if (at - name_at == 4) return fail("a metadata entry has an empty name");
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
            if (type == "__delayedload" && !delayed_load(value_at + 4, declared)) return false;
        }
        return true;
    }
    // io::DelayedLoadMetadata::readValue reads its own parts, whatever the declared size: a
    // leaf count (OpenVDB sizes its arrays from it; fuzz_vdb: 7e8 in a 10 kB file), then the
    // leaves' masks (1 byte each) and compressed sizes (8 bytes each), each as a uint32 size
    // and that many blosc bytes, or 0 and the raw bytes (as OpenVDB 10 writes them: checked on
    // files of 1 and 600 leaves, every compression). They must fill the declared size
    // exactly, or every field after them shifts (fuzz_vdb: a multi-GB string).
    bool delayed_load(size_t value, size_t declared) {
        if (declared == 0) return true;  // read as nothing
        if (declared < 12)
            return fail("the delayed-load metadata is " + std::to_string(declared) +
                        " bytes, shorter than its 12-byte header");
        uint32_t leaves = 0, masks = 0, sizes = 0;
        std::memcpy(&leaves, bytes.data() + value, 4);
        if (uint64_t(leaves) * 64 > bytes.size())
            return fail("the delayed-load metadata declares " + std::to_string(leaves) +
                        " leaves; a file of " + std::to_string(bytes.size()) +
                        " bytes holds at most " + std::to_string(bytes.size() / 64));
        std::memcpy(&masks, bytes.data() + value + 4, 4);
        const uint64_t mask_bytes = masks ? masks : uint64_t(leaves);
        if (mask_bytes + 12 > declared)
            return fail("the delayed-load metadata's masks overrun its value");
        std::memcpy(&sizes, bytes.data() + value + 8 + mask_bytes, 4);
        // 0xffffffff: no sizes stored (a file without blosc / zip compression).
        const uint64_t size_bytes = sizes == 0xffffffffu ? 0 : sizes ? sizes : uint64_t(leaves) * 8;
        if (mask_bytes + size_bytes + 12 != declared)
            return fail("the delayed-load metadata's parts take " +
                        std::to_string(mask_bytes + size_bytes + 12) + " bytes; it declares " +
                        std::to_string(declared));
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

// The grid type's name at `at` (a uint32 length, then the name).
std::string grid_type(const Walk& w, size_t at) {
    uint32_t n = 0;
    std::memcpy(&n, w.bytes.data() + at, 4);
    return std::string(w.bytes.data() + at + 4, n);
}

// A tree this walk knows: Tree_<value>_5_4_3 of a fixed-size value, "_HalfFloat" when its
// floating-point values are stored as halves (OpenVDB's io::HalfReader).
struct TreeValues {
    size_t bytes = 0;   // of a value (0: not a tree this walk knows)
    size_t stored = 0;  // of a value in a node's value chunk
    bool half = false;
};
TreeValues tree_values(std::string type) {
    const std::string suffix = "_HalfFloat";
    const bool half = type.size() > suffix.size() &&
                      type.compare(type.size() - suffix.size(), suffix.size(), suffix) == 0;
    if (half) type.resize(type.size() - suffix.size());
    static const std::pair<const char*, size_t> kTrees[] = {
        {"Tree_float_5_4_3", 4}, {"Tree_double_5_4_3", 8}, {"Tree_int32_5_4_3", 4},
        {"Tree_int64_5_4_3", 8}, {"Tree_vec3s_5_4_3", 12}, {"Tree_vec3d_5_4_3", 24},
        {"Tree_vec3i_5_4_3", 12}};
    for (const auto& [name, bytes] : kTrees)
        if (type == name) {
            const bool real = std::strstr(name, "int") == nullptr;  // halves of reals only
            return TreeValues{bytes, half && real ? bytes / 2 : bytes, half && real};
        }
    return TreeValues{};
}

size_t popcount(const Walk& w, size_t at, size_t bytes) {
    size_t n = 0;
    for (size_t i = 0; i < bytes; ++i) n += size_t(__builtin_popcount(uint8_t(w.bytes[at + i])));
    return n;
}

// io::readCompressedValues for a node of `count` values whose value mask is at `mask_at`: a
// flag byte, inactive values, a selection mask, then the chunk of (active) values. A chunk
// marked uncompressed must hold exactly what the node expects: OpenVDB 10's bloscFromStream /
// unzipFromStream read it at the length the file declares and compare only afterwards
// (fuzz_vdb: a heap-buffer overflow).
bool walk_values(Walk& w, const TreeValues& v, uint32_t compression, size_t count, size_t mask_at,
                 size_t mask_bytes) {
    constexpr uint32_t kZip = 1, kActiveMask = 2, kBlosc = 4;
    int8_t flag = 6;  // NO_MASK_AND_ALL_VALS
    if (!w.read(flag, "node's value flags")) return false;
    const size_t inactive = flag == 2 || flag == 4 ? 1 : flag == 5 ? 2 : 0;
    const size_t selection = flag >= 3 && flag <= 5 ? mask_bytes : 0;
    if (w.left() < inactive * v.bytes + selection) return w.fail("the file ends inside a node");
    w.at += inactive * v.bytes + selection;
    if ((compression & kActiveMask) && flag != 6) count = popcount(w, mask_at, mask_bytes);
    if (v.half && count == 0) return true;  // HalfReader reads nothing then
    const size_t bytes = count * v.stored;
    if (compression & (kBlosc | kZip)) {
        int64_t n = 0;
        if (!w.read(n, "value chunk size")) return false;
        if (n <= 0) {
            if (uint64_t(-(n + 1)) + 1 != bytes && !(n == 0 && bytes == 0))
                return w.fail("an uncompressed value chunk declares " + std::to_string(-n) +
                              " bytes where its node holds " + std::to_string(bytes));
        } else if (uint64_t(n) > w.left()) {
            return w.fail("a value chunk declares " + std::to_string(n) +
                          " bytes but the file has " + std::to_string(w.left()) + " left");
        } else {
            // c-blosc decodes a damaged chunk's block offsets unchecked (fuzz_vdb: a SEGV in
            // libblosc under bloscFromStream); its own validation says whether decoding is safe.
            size_t decoded = 0;
            if ((compression & kBlosc) &&
                blosc_cbuffer_validate(w.bytes.data() + w.at, size_t(n), &decoded) != 0)
                return w.fail("a blosc value chunk is damaged (c-blosc's validation refuses it)");
            if ((compression & kBlosc) && decoded != bytes)
                return w.fail("a blosc value chunk decodes to " + std::to_string(decoded) +
                              " bytes where its node holds " + std::to_string(bytes));
            w.at += size_t(n);
            return true;
        }
    }
    if (bytes > w.left()) return w.fail("the file ends inside a node's values");
    w.at += bytes;
    return true;
}

// InternalNode::readTopology (log2 dimension 5 or 4) down to the leaves' masks; counts leaves.
bool walk_internal(Walk& w, const TreeValues& v, uint32_t compression, int log2dim,
                   size_t& leaves) {
    const size_t values = size_t(1) << (3 * log2dim), mask_bytes = values / 8;
    if (w.left() < 2 * mask_bytes) return w.fail("the file ends inside a node's masks");
    const size_t child_mask = w.at, value_mask = w.at + mask_bytes;
    w.at += 2 * mask_bytes;
    if (!walk_values(w, v, compression, values, value_mask, mask_bytes)) return false;
    const size_t children = popcount(w, child_mask, mask_bytes);
    if (log2dim == 4) {  // the children are leaves: their value masks only (64 bytes each)
        if (w.left() < children * 64) return w.fail("the file ends inside the leaves' masks");
        w.at += children * 64;
        leaves += children;
        return true;
    }
    for (size_t c = 0; c < children; ++c)
        if (!walk_internal(w, v, compression, log2dim - 1, leaves)) return false;
    return true;
}

// Tree::readTopology (the root's background, tiles and children), then, at `block_at` (< 0:
// right after), Tree::readBuffers: per leaf its value mask and its values.
bool walk_tree(Walk& w, const TreeValues& v, uint32_t compression, int64_t block_at) {
    int32_t buffers = 0;
    if (!w.read(buffers, "tree")) return false;
    // OpenVDB warns on another count and reads on into a corrupted heap (fuzz_vdb).
    if (buffers != 1)
        return w.fail("the tree declares " + std::to_string(buffers) +
                      " buffers; OpenVDB reads trees of 1");
    uint32_t counts[2] = {0, 0};  // tiles, children
    if (w.left() < v.bytes) return w.fail("the file ends inside the tree's background");
    w.at += v.bytes;
    if (!w.read(counts, "root node")) return false;
    if (uint64_t(counts[0]) * (13 + v.bytes) + uint64_t(counts[1]) * 12 > w.left())
        return w.fail("the root declares " + std::to_string(counts[0]) + " tiles and " +
                      std::to_string(counts[1]) + " children");
    // A root entry's origin: OpenVDB offsets it by its node's extent (4096 voxels, 5-4-3
    // trees) in int arithmetic (fuzz_vdb: origin 2147483647 + 4095, an overflow UBSan caught in
    // openvdb/math/Coord.h); such coordinates are no grid's.
    auto origin = [&](const char* what) {
        int32_t xyz[3];
        if (!w.read(xyz, what)) return false;
        for (int32_t c : xyz)
            if (c > std::numeric_limits<int32_t>::max() - 4095)
                return w.fail(std::string("a ") + what + " at coordinate " + std::to_string(c) +
                              ", past the last node int32 coordinates hold");
        return true;
    };
    for (uint32_t t = 0; t < counts[0]; ++t) {
        if (!origin("root tile's origin")) return false;
        w.at += v.bytes + 1;  // value, active flag
    }
    size_t leaves = 0;
    for (uint32_t c = 0; c < counts[1]; ++c) {
        if (!origin("root child's origin")) return false;
        if (!walk_internal(w, v, compression, 5, leaves)) return false;
    }
    if (block_at >= 0 && int64_t(w.at) != block_at)
        return w.fail("the tree's topology ends here but its descriptor says byte " +
                      std::to_string(block_at));
    for (size_t l = 0; l < leaves; ++l) {
        if (w.left() < 64) return w.fail("the file ends inside a leaf's mask");
        const size_t mask_at = w.at;
        w.at += 64;
        if (!walk_values(w, v, compression, 512, mask_at, 64)) return false;
    }
    return true;
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
    // Older layouts (before OpenVDB 3.0, 2014) are not walked, and OpenVDB reads them with the
    // same unchecked sizes (fuzz_vdb: a version 103 header declared 1.7e9 metadata entries), so
    // they are refused; so are versions newer than the OpenVDB freqlab links.
    if (version < kVersionNodeMaskCompression || version > uint32_t(openvdb::OPENVDB_FILE_VERSION))
        return "file format version " + std::to_string(version) + " is outside the " +
               std::to_string(kVersionNodeMaskCompression) + " .. " +
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
        if (!w.sized("grid name")) return w.problem;
        const size_t type_at = w.at;
        if (!w.sized("grid type name")) return w.problem;
        if (version >= kVersionGridInstancing && !w.sized("grid's instance parent name"))
            return w.problem;
        int64_t offsets[3];  // the grid's data, its block data and its end
        if (!w.read(offsets, "grid descriptor")) return w.problem;
        uint32_t compression = 0;
        if (!w.read(compression, "grid compression")) return w.problem;
        if (!w.metadata("grid metadata")) return w.problem;
        const size_t transform_at = w.at + 4;
        if (!w.sized("transform type name")) return w.problem;
        const size_t map_bytes =
            linear_map_bytes(std::string(w.bytes.data() + transform_at, w.at - transform_at));
        const TreeValues values = tree_values(grid_type(w, type_at));
        if (map_bytes && values.bytes) {
            w.at = std::min(w.at + map_bytes, w.bytes.size() + 1);
            if (!walk_tree(w, values, compression, has_offsets ? offsets[1] : -1))
                return "grid " + std::to_string(g) + ": " + w.problem;
            if (has_offsets && int64_t(w.at) != offsets[2])
                return "grid " + std::to_string(g) + "'s buffers end at byte " +
                       std::to_string(w.at) + ", its descriptor says " + std::to_string(offsets[2]);
            continue;
        }
        // A grid this walk does not know (a frustum map, a tree of other values): its end
        // offset skips it; without usable offsets (a stream) the rest is OpenVDB's to check.
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
