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

}  // namespace freqlab
