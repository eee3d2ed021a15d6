#include "volume/emitter_roulette.h"

#include <algorithm>
#include <cmath>

#include "scene/light.h"

namespace freqlab {

float distant_light_strength(const std::vector<Light>& lights, const EnvironmentMap* environment) {
    double sum = 0.0;
    bool has_environment = false;
    for (const Light& light : lights) {
        if (light.type == LightType::Directional) sum += double(luminance(light.intensity));
        has_environment =
            has_environment || light.type == LightType::Environment || light.type == LightType::Sky;
    }
    if (has_environment && environment) {
        // Radiance / pdf is the integral over the sphere on average; a rank-1 lattice (the
        // golden ratio's fractions) spreads the fixed samples over the map.
        constexpr int kSamples = 1024;
        double integral = 0.0;
        for (int i = 0; i < kSamples; ++i) {
            const float a = (float(i) + 0.5f) / float(kSamples);
            const vec4 u(a, std::fmod(float(i) * 0.618034f, 1.0f),
                         std::fmod(float(i) * 0.754878f, 1.0f),
                         std::fmod(float(i) * 0.569840f, 1.0f));
            vec3 direction;
            float pdf = 0.0f;
            const vec3 radiance = environment->sample(u, &direction, &pdf);
            if (pdf > 0.0f) integral += double(luminance(radiance)) / double(pdf);
        }
        sum += 0.25 * integral / kSamples;
    }
    return std::isfinite(sum) ? float(sum) : 0.0f;
}

void emitter_keep_probabilities(const std::vector<float>& strength, float budget,
                                std::vector<float>& keep) {
    keep.assign(strength.size(), 1.0f);
    if (!(budget > 0.0f) || strength.size() < 2) return;
    double sum = 0.0;
    for (float s : strength)
        if (s > 0.0f && std::isfinite(s)) sum += s;
    if (!(sum > 0.0) || !std::isfinite(sum)) return;
    for (size_t i = 0; i < strength.size(); ++i) {
        const float s = strength[i] > 0.0f && std::isfinite(strength[i]) ? strength[i] : 0.0f;
        keep[i] = std::min(1.0f, std::max(kEmitterKeepFloor, float(budget * s / sum)));
    }
}

}  // namespace freqlab
