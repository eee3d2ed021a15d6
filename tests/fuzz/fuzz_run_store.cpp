// libFuzzer target (issue "The timeline as a recorded run"): what the workbench reads back from
// its run store. The first byte picks the reader: even, a recorded frame file
// (render/frame_store.h: header, run key, layers, stats, cache records, positions, size);
// bit 1 set, its on-screen layer first (read_recorded_frame with only "color"); odd, method
// A's cache state as a checkpoint holds it (RadianceCache::decode, whose bytes are
// re-encoded identically when accepted). Bad input must end in freqlab::Error.
#include <filesystem>

#include "base/byte_stream.h"
#include "base/error.h"
#include "base/file_io.h"
#include "cache/radiance_cache.h"
#include "fuzz_support.h"
#include "render/frame_store.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size == 0) return 0;
    const std::string rest(reinterpret_cast<const char*>(data) + 1, size - 1);
    try {
        if (data[0] & 1) {
            freqlab::RadianceCache cache;
            freqlab::ByteReader r(rest, "fuzz", "cache");
            cache.decode(r, "fuzz");
            freqlab::ByteWriter w;
            cache.encode(w);
            FUZZ_REQUIRE(w.bytes() == rest.substr(0, rest.size() - r.remaining()));
        } else {
            static const std::filesystem::path dir =
                "/dev/shm/freqlab-fuzz-run-" + std::to_string(getpid());
            std::filesystem::create_directories(dir / "frames");
            std::ofstream(freqlab::recorded_frame_path(dir, 3), std::ios::binary | std::ios::trunc)
                .write(rest.data(), std::streamsize(rest.size()));
            // A timeline jump reads the layer on screen alone first (bit 1 of the first byte):
            // its layers' headers are checked the same; what it holds is what the whole read has.
            if (data[0] & 2) {
                const freqlab::FrameResult part =
                    freqlab::read_recorded_frame(dir, fuzz_run_key(), 3, {"color"});
                FUZZ_REQUIRE(part.frame == 3 && part.partial);
                FUZZ_REQUIRE(part.layers.layers().size() <= 1);
            }
            const freqlab::FrameResult r = freqlab::read_recorded_frame(dir, fuzz_run_key(), 3);
            FUZZ_REQUIRE(r.frame == 3);
        }
    } catch (const freqlab::Error& e) {
        fuzz_report(e);
    }
    return 0;
}
