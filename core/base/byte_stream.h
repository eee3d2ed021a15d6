// A little-endian byte stream for messages and state files: fixed-width integers, raw arrays,
// strings (MPI frames, image/layer_codec.h; method A's cache checkpoints,
// cache/cache_checkpoint.h). The reader checks every length against what is left and throws
// Error naming its source and field.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace freqlab {

class ByteWriter {
  public:
    template <class T>
    void put(const T& value) {
        bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
    }
    void put_bytes(const void* data, size_t n) { bytes_.append(static_cast<const char*>(data), n); }
    void put_string(const std::string& s) {
        put<uint64_t>(s.size());
        bytes_ += s;
    }
    // The size, then the elements' bytes (trivially copyable T).
    template <class T>
    void put_vector(const std::vector<T>& v) {
        put<uint64_t>(v.size());
        put_bytes(v.data(), v.size() * sizeof(T));
    }
    std::string& bytes() { return bytes_; }

  private:
    std::string bytes_;
};

class ByteReader {
  public:
    // `field` names what the bytes hold in errors ("layers", "cache").
    // `bytes` must outlive the reader (a string, a mapped file).
    ByteReader(std::string_view bytes, std::string source, std::string field = "layers")
        : bytes_(bytes), source_(std::move(source)), field_(std::move(field)) {}
    template <class T>
    T get() {
        T value;
        get_bytes(&value, sizeof(T));
        return value;
    }
    void get_bytes(void* out, size_t n);  // throws Error when fewer than n bytes are left
    std::string get_string();
    std::string_view get_view();  // a string's bytes in place (valid as long as `bytes`)
    template <class T>
    std::vector<T> get_vector() {
        const uint64_t n = get<uint64_t>();
        check_left(n, sizeof(T));
        std::vector<T> v(static_cast<size_t>(n));
        get_bytes(v.data(), size_t(n) * sizeof(T));
        return v;
    }
    size_t remaining() const { return bytes_.size() - at_; }

  private:
    // Throws when `count` elements of `size` bytes cannot be left (before allocating them).
    void check_left(uint64_t count, size_t size) const;
    std::string_view bytes_;
    std::string source_, field_;
    size_t at_ = 0;
};

}  // namespace freqlab
