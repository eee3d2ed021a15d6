// libFuzzer target (issue "Reliability"): the scene JSON loader, media, animation and asset
// fields included; assets resolve first in tests/fuzz/assets (small stand-ins for the
// Debian packages' files, so that an input loads in milliseconds). Bad input must end in
// freqlab::Error (file, field, expectation); any other exception, crash, sanitizer report, hang or
// leak is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "base/error.h"
#include "fuzz_support.h"
#include "scene/scene_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const freqlab::Scene scene = freqlab::parse_scene(text, "fuzz.json", FUZZ_ASSET_DIR);
        (void)scene;
    } catch (const freqlab::Error& e) {
        fuzz_report(e);
    }
    return 0;
}
