#include "image/image_file_check.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include "base/error.h"

namespace freqlab {

namespace {

// An EXR header is a list of (name\0, type\0, int32 size, value[size]) ended by an empty name;
// a multi-part file has several such lists, ended by an empty list. Values are skipped (seek),
// so a large file costs only its header's bytes.
class AttributeWalker {
  public:
    AttributeWalker(const std::string& file, std::ifstream& in, size_t file_size)
        : file_(file), in_(in), size_(file_size) {}

    void walk(bool multipart) {
        pos_ = 8;  // magic + version
        for (int part = 0;; ++part) {
            if (multipart && part > 0 && peek_end()) return;  // the empty header ends the list
            int attributes = 0;
            for (;; ++attributes) {
                const std::string name = read_name("attribute name");
                if (name.empty()) break;
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
                if (name == "dataWindow" && type == "box2i" && size == 16) check_window();
                pos_ += size_t(size);
                in_.seekg(std::streamoff(pos_));
            }
            if (attributes == 0 && !multipart) fail("header", "has no attributes");
            if (!multipart) return;
        }
    }

  private:
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
            if (name.size() >= 255) fail("header", what + " is longer than 255 bytes");
            name += char(c);
        }
    }
    [[noreturn]] void fail(const std::string& field, const std::string& what) const {
        throw Error(file_, field, what + " (not a valid OpenEXR file)");
    }
    std::string file_;
    std::ifstream& in_;
    size_t size_, pos_ = 0;
};

}  // namespace

void check_exr_attributes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return;  // the decoder names the missing file
    char head[8] = {};
    in.read(head, 8);
    const unsigned char magic[4] = {0x76, 0x2f, 0x31, 0x01};
    if (in.gcount() < 8 || std::memcmp(head, magic, 4) != 0) return;
    const bool multipart = (static_cast<unsigned char>(head[5]) & 0x10) != 0;  // version bit 12
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (ec) return;
    AttributeWalker(path.string(), in, size_t(size)).walk(multipart);
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
