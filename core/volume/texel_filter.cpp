#include "volume/texel_filter.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace freqlab {

std::vector<size_t> texel_filter_neighbours(const ObjectLightmap& map,
                                            const TexelFilterGuide& guide, size_t i, int radius) {
    std::vector<size_t> out;
    const LightmapTexel& t = map.texels[i];
    if (t.state != TexelState::Valid) return out;
    const int x0 = int(i % size_t(map.width)), y0 = int(i / size_t(map.width));
    // The window's diagonal in world units, with a margin for the chart's projection.
    const float reach = 1.5f * float(radius + 1) * std::sqrt(2.0f) / map.density_at(i);
    for (int y = std::max(0, y0 - radius); y <= std::min(map.height - 1, y0 + radius); ++y)
        for (int x = std::max(0, x0 - radius); x <= std::min(map.width - 1, x0 + radius); ++x) {
            const size_t j = size_t(y) * size_t(map.width) + size_t(x);
            const LightmapTexel& u = map.texels[j];
            const float a = guide.light[i], b = guide.light[j];
            if (u.state != TexelState::Valid || guide.shadows[j] != guide.shadows[i] ||
                !(std::max(a, b) <= kTexelFilterLightRatio * std::min(a, b)) ||
                glm::dot(u.normal, t.normal) < 0.9f || glm::length(u.position - t.position) > reach)
                continue;
            out.push_back(j);
        }
    return out;
}

void set_texel_filter_guide(TexelFilterGuide& guide, size_t i,
                            const BakeEstimator::FixedDirect& fixed, const IrradianceParts& sum) {
    guide.shadows[i] = 0;
    for (const auto& [light, connection] : fixed.occluded)
        guide.shadows[i] |= uint64_t(1) << (unsigned(light) % 64u);
    guide.light[i] = luminance(sum.total());
}

int texel_filter_radius(const BakeEstimator& estimator) {
    return estimator.method() == BakeMethod::Impulse ? estimator.settings().texel_mc_radius : 0;
}

IrradianceParts mean_of_texels(const std::vector<IrradianceParts>& sums,
                               const std::vector<size_t>& near) {
    IrradianceParts sum;
    if (near.empty()) return sum;
    for (size_t j : near) sum += sums[j];
    const float inv = 1.0f / float(near.size());
    sum.surface *= inv;
    sum.single *= inv;
    sum.multiple *= inv;
    return sum;
}

std::vector<IrradianceParts> filter_texel_sums(const ObjectLightmap& map,
                                               const std::vector<IrradianceParts>& sums,
                                               const TexelFilterGuide& guide, int radius) {
    if (radius <= 0) return sums;
    std::vector<IrradianceParts> out(sums.size());
    tbb::parallel_for(size_t(0), sums.size(), [&](size_t i) {
        out[i] = mean_of_texels(sums, texel_filter_neighbours(map, guide, i, radius));
    });
    return out;
}

}  // namespace freqlab
