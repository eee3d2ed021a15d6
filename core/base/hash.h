// A stable 64-bit content hash (FNV-1a) for cache keys: the same bytes give the same key on
// every machine and every run, unlike std::hash.
#pragma once

#include <cstdint>
#include <string>

namespace freqlab {

inline uint64_t fnv1a(const std::string& bytes, uint64_t h = 0xcbf29ce484222325ULL) {
    for (unsigned char c : bytes) h = (h ^ c) * 0x100000001b3ULL;
    return h;
}

// FNV-1a over little-endian 64-bit words (then the tail bytes): the same stability, 8x fewer
// multiplies, for megabyte payloads checked on every load (the impulse tables).
inline uint64_t fnv1a_words(const char* data, size_t size, uint64_t h = 0xcbf29ce484222325ULL) {
    size_t i = 0;
    for (; i + 8 <= size; i += 8) {
        uint64_t word = 0;
        for (int b = 0; b < 8; ++b)
            word |= uint64_t(static_cast<unsigned char>(data[i + size_t(b)])) << (8 * b);
        h = (h ^ word) * 0x100000001b3ULL;
    }
    for (; i < size; ++i) h = (h ^ static_cast<unsigned char>(data[i])) * 0x100000001b3ULL;
    return h;
}

}  // namespace freqlab
