#include "scene/provenance.h"

#include <cstdio>

#include "scene/scene.h"

#ifndef FREQLAB_VERSION
#define FREQLAB_VERSION "unknown"
#endif

namespace freqlab {

const char* freqlab_version() {
    return FREQLAB_VERSION;
}

nlohmann::json output_provenance(const Scene& scene, const std::string& method,
                                 const nlohmann::json& settings, long seed,
                                 const std::vector<MediumDesc>& media) {
    char hash[20];
    std::snprintf(hash, sizeof hash, "%016llx",
                  static_cast<unsigned long long>(scene.content_hash));
    nlohmann::json list = nlohmann::json::array();
    for (const MediumDesc& m : media)
        list.push_back({{"name", m.name},
                        {"sigma_s", m.sigma_s},
                        {"sigma_a", m.sigma_a},
                        {"g", m.g},
                        {"density_scale", m.density_scale}});
    return {{"freqlab", freqlab_version()},
            {"scene", scene.source},
            {"scene_hash", hash},
            {"method", method},
            {"seed", seed},
            {"settings", settings},
            {"media", list}};
}

nlohmann::json output_provenance(const Scene& scene, const std::string& method,
                                 const nlohmann::json& settings, long seed) {
    return output_provenance(scene, method, settings, seed, scene.media);
}

std::string provenance_csv_header(const nlohmann::json& provenance) {
    std::string out;
    for (const auto& [key, value] : provenance.items())
        out += "# " + key + ": " + (value.is_string() ? value.get<std::string>() : value.dump()) +
               "\n";
    return out;
}

}  // namespace freqlab
