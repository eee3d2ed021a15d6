// A LayerSet as one byte string and back: how a frame travels between processes (an MPI rank
// to rank 0, app/cluster.h) before the one writer turns it into EXR / PNG. Every field of every
// layer round-trips exactly (names, kinds, legends, palettes, the float bits), so the file rank 0
// writes is the file the rendering process would have written.
#pragma once

#include <string>

#include "image/layers.h"

namespace freqlab {

std::string encode_layers(const LayerSet& layers);
// Throws Error naming `source` when the bytes are not a whole encoded LayerSet.
LayerSet decode_layers(const std::string& bytes, const std::string& source);

// A little-endian byte stream for such messages (fixed-width integers, raw arrays, strings).
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
    std::string& bytes() { return bytes_; }

  private:
    std::string bytes_;
};

class ByteReader {
  public:
    ByteReader(const std::string& bytes, std::string source)
        : bytes_(bytes), source_(std::move(source)) {}
    template <class T>
    T get() {
        T value;
        get_bytes(&value, sizeof(T));
        return value;
    }
    void get_bytes(void* out, size_t n);  // throws Error when fewer than n bytes are left
    std::string get_string();
    size_t remaining() const { return bytes_.size() - at_; }

  private:
    const std::string& bytes_;
    std::string source_;
    size_t at_ = 0;
};

}  // namespace freqlab
