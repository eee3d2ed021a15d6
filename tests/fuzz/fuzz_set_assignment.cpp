// libFuzzer target (issue "Reliability"): `--set key=value` parsing over every settings schema
// (one assignment per input line), the CLI's and the session's one namespace. Bad input must
// end in freqlab::Error naming the flag and the key; anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "base/error.h"
#include "fuzz_support.h"
#include "settings/bake_settings.h"
#include "settings/cache_settings.h"
#include "settings/render_settings.h"
#include "settings/settings_group.h"
#include "settings/shading_settings.h"
#include "settings/sparse_settings.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace freqlab;
    BakeSettings bake;
    CacheSettings cache;
    SparseSettings sparse;
    FrameSettings frame;
    GBufferSettings gbuffer;
    MisSettings mis;
    ReferenceSettings reference;
    PointsSettings points;
    ShadingSettings shading;
    SettingsGroup group;
    group.bind(BakeSettings::schema(), &bake);
    group.bind(CacheSettings::schema(), &cache);
    group.bind(SparseSettings::schema(), &sparse);
    group.bind(FrameSettings::schema(), &frame);
    group.bind(GBufferSettings::schema(), &gbuffer);
    group.bind(MisSettings::schema(), &mis);
    group.bind(ReferenceSettings::schema(), &reference);
    group.bind(PointsSettings::schema(), &points);
    group.bind(ShadingSettings::schema(), &shading);
    std::istringstream lines(std::string(reinterpret_cast<const char*>(data), size));
    for (std::string line; std::getline(lines, line);) {
        try {
            group.apply_assignment(line);
        } catch (const Error& e) {
            fuzz_report(e);
        }
    }
    return 0;
}
