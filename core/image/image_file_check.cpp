#include "image/image_file_check.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <set>
#include <string>

#include "base/error.h"

namespace freqlab {

namespace {

// The size OpenEXR 3.1 reads for a known attribute type whatever the declared size says (it
// reads the value by its type), or -1 for types it reads by the declared size.
int fixed_value_size(const std::string& type) {
    static const std::pair<const char*, int> kSizes[] = {
        {"box2i", 16},   {"box2f", 16},    {"compression", 1}, {"chromaticities", 32},
        {"double", 8},   {"envmap", 1},    {"float", 4},       {"int", 4},
        {"keycode", 28}, {"lineOrder", 1}, {"m33f", 36},       {"m33d", 72},
        {"m44f", 64},    {"m44d", 128},    {"rational", 8},    {"tiledesc", 9},
        {"timecode", 8}, {"v2i", 8},       {"v2f", 8},         {"v2d", 16},
        {"v3i", 12},     {"v3f", 12},      {"v3d", 24},        {"deepImageState", 1}};
    for (const auto& [name, size] : kSizes)
        if (type == name) return size;
    return -1;
}

// An EXR header is a list of (name\0, type\0, int32 size, value[size]) ended by an empty name;
// a multi-part file has several such lists, ended by an empty list. Values are skipped (seek),
// so a large file costs only its header's bytes. OpenEXR 3.1 reads a known type's value by its
// type, not by the declared size (a channel list until its empty name, a preview by its
// width x height), and names of at most 31 bytes without the long-names flag: where the two
// disagree, OpenEXR goes on reading from another offset than the declared one (fuzz_env_exr: a
// 206-byte file whose channel list ran past its size made it allocate 1.8 GB for an attribute
// read out of "\0com"). Such headers are refused here.
class AttributeWalker {
  public:
    AttributeWalker(const std::string& file, std::ifstream& in, size_t file_size, bool long_names)
        : file_(file), in_(in), size_(file_size), max_name_(long_names ? 255 : 31) {}

    void walk(bool multipart) {
        pos_ = 8;  // magic + version
        for (int part = 0;; ++part) {
            if (multipart && part > 0 && peek_end()) return;  // the empty header ends the list
            int attributes = 0;
            std::set<std::string> seen;
            for (;; ++attributes) {
                const std::string name = read_name("attribute name");
                if (name.empty()) break;
                // OpenEXR keeps one value per name (the last): a second dataWindow would be the
                // one it sizes its buffers from, not the first this walk checked (fuzz_env_exr:
                // a 16 x 8 window, then 983041 x 8: 1.8 s of allocation under ASan).
                if (!seen.insert(name).second)
                    fail("header." + name, "appears twice in one header");
                const std::string type = read_name("type of " + name);
                unsigned char le[4];
                if (size_ - pos_ < 4 || !in_.read(reinterpret_cast<char*>(le), 4))
                    fail("header." + name, "truncated before its size");
                pos_ += 4;
                const int32_t size = int32_t(uint32_t(le[0]) | uint32_t(le[1]) << 8 |
                                             uint32_t(le[2]) << 16 | uint32_t(le[3]) << 24);
                if (size < 0 || size_t(size) > size_ - pos_)
                    fail("header." + name, "declares " + std::to_string(size) + " bytes of " +
                                               type + ", the file has " +
                                               std::to_string(size_ - pos_) + " left");
                const int fixed = fixed_value_size(type);
                if (fixed >= 0 && size != fixed)
                    fail("header." + name, "declares " + std::to_string(size) + " bytes for a " +
                                               type + ", which is " + std::to_string(fixed));
                const size_t end = pos_ + size_t(size);
                if (name == "dataWindow" && type == "box2i") check_window();
                if (type == "chlist") check_channel_list(name, end);
                if (type == "preview") check_preview(name, size);
                pos_ = end;
                in_.seekg(std::streamoff(pos_));
            }
            if (attributes == 0 && !multipart) fail("header", "has no attributes");
            if (!multipart) return;
        }
    }

    long long window_pixels() const { return window_pixels_; }

  private:
    // Entries (name\0, pixel type, pLinear, 3 reserved, x and y sampling: 16 bytes) up to an
    // empty name, which must end exactly at the declared size.
    void check_channel_list(const std::string& name, size_t end) {
        for (int entry = 0;; ++entry) {
            if (pos_ >= end) fail("header." + name, "channel list runs past its declared size");
            if (read_name("channel name").empty()) break;
            if (end - std::min(end, pos_) < 16)
                fail("header." + name, "channel entry " + std::to_string(entry) +
                                           " runs past the list's declared size");
            pos_ += 16;
            in_.seekg(std::streamoff(pos_));
        }
        if (pos_ != end)
            fail("header." + name, "channel list ends " + std::to_string(end - pos_) +
                                       " bytes before its declared size");
    }
    // Width and height (uint32 each), then width x height RGBA bytes.
    void check_preview(const std::string& name, int32_t size) {
        unsigned char le[8];
        if (size < 8 || !in_.read(reinterpret_cast<char*>(le), 8))
            fail("header." + name, "preview shorter than its size fields");
        const uint64_t w =
            uint32_t(le[0]) | uint32_t(le[1]) << 8 | uint32_t(le[2]) << 16 | uint32_t(le[3]) << 24;
        const uint64_t h =
            uint32_t(le[4]) | uint32_t(le[5]) << 8 | uint32_t(le[6]) << 16 | uint32_t(le[7]) << 24;
        if (8 + 4 * w * h != uint64_t(size))
            fail("header." + name, "preview of " + std::to_string(w) + " x " + std::to_string(h) +
                                       " needs " + std::to_string(8 + 4 * w * h) +
                                       " bytes, declares " + std::to_string(size));
    }
    // OpenEXR sizes its line buffers from the data window before any pixel is read (fuzz_env_exr:
    // an inverted window cost seconds of allocation), so the window is checked here first.
    void check_window() {
        unsigned char le[16];
        if (!in_.read(reinterpret_cast<char*>(le), 16)) fail("header.dataWindow", "truncated");
        int64_t v[4];
        for (int i = 0; i < 4; ++i)
            v[i] = int32_t(uint32_t(le[4 * i]) | uint32_t(le[4 * i + 1]) << 8 |
                           uint32_t(le[4 * i + 2]) << 16 | uint32_t(le[4 * i + 3]) << 24);
        const int64_t width = v[2] - v[0] + 1, height = v[3] - v[1] + 1;
        if (width <= 0 || height <= 0)
            fail("header.dataWindow", "is empty or inverted: (" + std::to_string(v[0]) + ", " +
                                          std::to_string(v[1]) + ") to (" + std::to_string(v[2]) +
                                          ", " + std::to_string(v[3]) + ")");
        check_image_size(file_, width, height, 1);
        if (window_pixels_ < 0) window_pixels_ = width * height;
    }
    int next() {
        if (pos_ >= size_) return -1;
        const int c = in_.get();
        if (c != EOF) ++pos_;
        return c;
    }
    bool peek_end() {
        if (pos_ >= size_) fail("header", "truncated in the list of parts");
        if (in_.peek() != 0) return false;
        next();
        return true;
    }
    std::string read_name(const std::string& what) {
        std::string name;
        for (int c = next();; c = next()) {
            if (c == EOF || c < 0) fail("header", "truncated in an " + what);
            if (c == 0) return name;
            if (int(name.size()) >= max_name_)
                fail("header", what + " is longer than " + std::to_string(max_name_) + " bytes" +
                                   (max_name_ < 255 ? " (no long-names flag)" : ""));
            name += char(c);
        }
    }
    [[noreturn]] void fail(const std::string& field, const std::string& what) const {
        throw Error(file_, field, what + " (not a valid OpenEXR file)");
    }
    std::string file_;
    std::ifstream& in_;
    size_t size_, pos_ = 0;
    int max_name_;
    long long window_pixels_ = -1;  // the first data window's width x height
};

}  // namespace

long long check_exr_attributes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return -1;  // the decoder names the missing file
    char head[8] = {};
    in.read(head, 8);
    const unsigned char magic[4] = {0x76, 0x2f, 0x31, 0x01};
    if (in.gcount() < 8 || std::memcmp(head, magic, 4) != 0) return -1;
    const bool multipart = (static_cast<unsigned char>(head[5]) & 0x10) != 0;   // version bit 12
    const bool long_names = (static_cast<unsigned char>(head[5]) & 0x04) != 0;  // version bit 10
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) return -1;
    AttributeWalker walker(path.string(), in, size_t(size), long_names);
    walker.walk(multipart);
    return walker.window_pixels();
}

void check_image_size(const std::filesystem::path& path, long long width, long long height,
                      long long channels) {
    if (width <= 0 || height <= 0 || channels < 1)
        throw Error(path.string(), "resolution",
                    "image has no pixels (" + std::to_string(width) + " x " +
                        std::to_string(height) + ", " + std::to_string(channels) + " channels)");
    if (double(width) * double(height) * double(channels) > double(kMaxImageValues))
        throw Error(path.string(), "resolution",
                    std::to_string(width) + " x " + std::to_string(height) + " x " +
                        std::to_string(channels) + " values exceed 2^28 (1 GB as floats)");
    if (double(width) * double(channels) > double(kMaxImageRowValues))
        throw Error(path.string(), "resolution",
                    "a row of " + std::to_string(width) + " x " + std::to_string(channels) +
                        " values exceeds 2^20 (OpenImageIO reads up to 256 rows at once)");
}

}  // namespace freqlab
