// A little-endian byte stream for messages and state files: fixed-width integers, raw arrays,
// strings (MPI frames, image/layer_codec.h; method A's cache checkpoints,
// cache/cache_checkpoint.h). The reader checks every length against what is left and throws
// Error naming its source and field.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace freqlab {

// Where a writer's bytes go; the typed puts are built on put_bytes.
class ByteSink {
  public:
    virtual ~ByteSink() = default;
    virtual void put_bytes(const void* data, size_t n) = 0;
    template <class T>
    void put(const T& value) {
        put_bytes(&value, sizeof(T));
    }
    void put_string(std::string_view s) {
        put<uint64_t>(s.size());
        put_bytes(s.data(), s.size());
    }
    // The size, then the elements' bytes (trivially copyable T).
    template <class T>
    void put_vector(const std::vector<T>& v) {
        put<uint64_t>(v.size());
        put_bytes(v.data(), v.size() * sizeof(T));
    }
};

// Into a string (messages, state).
class ByteWriter : public ByteSink {
  public:
    void put_bytes(const void* data, size_t n) override {
        bytes_.append(static_cast<const char*>(data), n);
    }
    std::string& bytes() { return bytes_; }

  private:
    std::string bytes_;
};

// Straight into a stream (files of tens of MB: no copy of them in memory), counting.
class StreamByteWriter : public ByteSink {
  public:
    explicit StreamByteWriter(std::ostream& out) : out_(out) {}
    void put_bytes(const void* data, size_t n) override {
        out_.write(static_cast<const char*>(data), std::streamsize(n));
        written_ += n;
    }
    uint64_t written() const { return written_; }

  private:
    std::ostream& out_;
    uint64_t written_ = 0;
};

// Only counts (the size of what a writer would write, before writing it).
class ByteCounter : public ByteSink {
  public:
    void put_bytes(const void*, size_t n) override { counted_ += n; }
    uint64_t counted() const { return counted_; }

  private:
    uint64_t counted_ = 0;
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
    void skip(size_t n);  // throws Error when fewer than n bytes are left
    size_t remaining() const { return bytes_.size() - at_; }

  private:
    // Throws when `count` elements of `size` bytes cannot be left (before allocating them).
    void check_left(uint64_t count, size_t size) const;
    std::string_view bytes_;
    std::string source_, field_;
    size_t at_ = 0;
};

}  // namespace freqlab
