#include "base/byte_stream.h"

#include <cstring>

#include "base/error.h"

namespace freqlab {

void ByteReader::get_bytes(void* out, size_t n) {
    if (n > remaining())
        throw Error(source_, field_,
                    "truncated message: " + std::to_string(n) + " bytes wanted at offset " +
                        std::to_string(at_) + ", " + std::to_string(remaining()) + " left");
    if (n > 0) std::memcpy(out, bytes_.data() + at_, n);
    at_ += n;
}

void ByteReader::skip(size_t n) {
    if (n > remaining())
        throw Error(source_, field_,
                    "truncated message: " + std::to_string(n) + " bytes to skip at offset " +
                        std::to_string(at_) + ", " + std::to_string(remaining()) + " left");
    at_ += n;
}

void ByteReader::check_left(uint64_t count, size_t size) const {
    if (size > 0 && count > remaining() / size)
        throw Error(source_, field_,
                    "an array of " + std::to_string(count) + " elements of " +
                        std::to_string(size) + " bytes with " + std::to_string(remaining()) +
                        " bytes left");
}

std::string ByteReader::get_string() {
    return std::string(get_view());
}

std::string_view ByteReader::get_view() {
    const uint64_t n = get<uint64_t>();
    if (n > remaining())
        throw Error(source_, field_,
                    "a string of " + std::to_string(n) + " bytes with " +
                        std::to_string(remaining()) + " left");
    const std::string_view s = bytes_.substr(at_, size_t(n));
    at_ += size_t(n);
    return s;
}

}  // namespace freqlab
