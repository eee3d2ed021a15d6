// libFuzzer target (issue "Reliability"): an OpenVDB density grid as a scene's medium reads it
// (volume/vdb_reader.h). Bad input must end in freqlab::Error naming the scene field; a grid
// that loads has finite, non-negative voxels and a finite box.
#include <cmath>

#include "base/error.h"
#include "fuzz_support.h"
#include "volume/vdb_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace freqlab;
    const std::string path = write_fuzz_input(data, size, ".vdb");
    try {
        const VdbDensity d = read_vdb_density(path, "density", "fuzz.json", "media[0].density");
        for (float v : d.voxels) FUZZ_REQUIRE(std::isfinite(v) && v >= 0.0f);
        for (int a = 0; a < 3; ++a)
            FUZZ_REQUIRE(std::isfinite(d.box_min[a]) && std::isfinite(d.box_max[a]) &&
                         d.box_max[a] > d.box_min[a]);
    } catch (const Error& e) {
        fuzz_report(e);
    }
    return 0;
}
