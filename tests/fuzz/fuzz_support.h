// What the fuzz targets share. File readers (impulse tables, env maps, VDB grids) get the
// input as a file: one per process in /dev/shm (memory, not disk), rewritten per input.
// FREQLAB_FUZZ_VERBOSE=1 prints each input's Error (to check that a seed loads).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include <unistd.h>

inline std::string write_fuzz_input(const uint8_t* data, size_t size, const char* extension) {
    static const std::string path = "/dev/shm/freqlab-fuzz-" + std::to_string(getpid()) + extension;
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(data), std::streamsize(size));
    return path;
}

// A reader's result that is not finite is a finding: NaN/Inf must never leak silently.
#define FUZZ_REQUIRE(cond)                                                                       \
    do {                                                                                         \
        if (!(cond)) {                                                                           \
            std::fprintf(stderr, "%s:%d: FUZZ_REQUIRE(%s) failed\n", __FILE__, __LINE__, #cond); \
            __builtin_trap();                                                                    \
        }                                                                                        \
    } while (0)

// The run key the run-store target reads its frames with (its seeds are written with it).
inline nlohmann::json fuzz_run_key() {
    return {{"freqlab", "fuzz"}, {"scene_hash", "0"}, {"method", "cache"}, {"seed", 0}};
}

inline void fuzz_report(const std::exception& e) {
    static const bool verbose = std::getenv("FREQLAB_FUZZ_VERBOSE") != nullptr;
    if (verbose) std::fprintf(stderr, "%s\n", e.what());
}
