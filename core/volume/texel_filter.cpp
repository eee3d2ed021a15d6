#include "volume/texel_filter.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace freqlab {

namespace {

// Texel j on texel i's surface within a window of `radius`: valid, facing its way and within
// the window's diagonal in world units (with a margin for the chart's projection).
bool on_surface_of(const ObjectLightmap& map, size_t i, size_t j, int radius) {
    const LightmapTexel &t = map.texels[i], &u = map.texels[j];
    const float reach = 1.5f * float(radius + 1) * std::sqrt(2.0f) / map.density_at(i);
    return u.state == TexelState::Valid && glm::dot(u.normal, t.normal) >= 0.9f &&
           u.covered == t.covered && glm::length(u.position - t.position) <= reach;
}

template <typename Visit>
void for_each_in_window(const ObjectLightmap& map, size_t i, int radius, const Visit& visit) {
    const int x0 = int(i % size_t(map.width)), y0 = int(i / size_t(map.width));
    for (int y = std::max(0, y0 - radius); y <= std::min(map.height - 1, y0 + radius); ++y)
        for (int x = std::max(0, x0 - radius); x <= std::min(map.width - 1, x0 + radius); ++x)
            visit(size_t(y) * size_t(map.width) + size_t(x));
}

}  // namespace

std::vector<size_t> texel_filter_neighbours(const ObjectLightmap& map,
                                            const TexelFilterGuide& guide, size_t i, int radius,
                                            const std::vector<char>* among) {
    std::vector<size_t> out;
    if (map.texels[i].state != TexelState::Valid) return out;
    for_each_in_window(map, i, radius, [&](size_t j) {
        if ((among && !(*among)[j]) || guide.shadows[j] != guide.shadows[i] ||
            !texel_lights_agree(guide, i, j) || !on_surface_of(map, i, j, radius))
            return;
        out.push_back(j);
    });
    return out;
}

int texel_filter_capacity(const ObjectLightmap& map, size_t i, int radius, int stride) {
    int count = 0;
    if (map.texels[i].state != TexelState::Valid) return count;
    const size_t w = size_t(map.width);
    for_each_in_window(map, i, radius, [&](size_t j) {
        const bool lattice = int(j % w) % stride == 0 && int(j / w) % stride == 0;
        count += (j == i || lattice) && on_surface_of(map, i, j, radius);
    });
    return count;
}

std::vector<float> texel_mc_rates(const ObjectLightmap& map, const BakeEstimator& estimator) {
    const int radius = texel_filter_radius(estimator);
    const float rate = estimator.settings().texel_mc_rate;
    std::vector<float> rates(map.texels.size(), rate);
    if (radius <= 0 || rate >= 1.0f) return rates;
    const float window = float((2 * radius + 1) * (2 * radius + 1));
    tbb::parallel_for(size_t(0), rates.size(), [&](size_t i) {
        const int capacity = texel_filter_capacity(map, i, radius);
        if (capacity > 0)
            rates[i] = std::min(1.0f, rate * std::min(kMaxMcRateBoost, window / float(capacity)));
    });
    return rates;
}

uint64_t texel_shadow_bits(const BakeEstimator::FixedDirect& fixed) {
    uint64_t bits = 0;
    for (const auto& [light, connection] : fixed.occluded) bits |= shadow_bit(light);
    return bits;
}

void set_texel_filter_guide(TexelFilterGuide& guide, size_t i,
                            const BakeEstimator::FixedDirect& fixed, const IrradianceParts& sum,
                            float light_squares, int paths) {
    guide.shadows[i] = texel_shadow_bits(fixed);
    const float light = luminance(sum.total());
    guide.light[i] = light;
    if (!guide.scattered.empty()) guide.scattered[i] = luminance(sum.single + sum.multiple);
    // The sum of n paths: n times their sample variance, sum x^2 - (sum x)^2 / n.
    if (!guide.variance.empty())
        guide.variance[i] =
            paths > 1 ? std::max(0.0f, light_squares - light * light / float(paths)) : 0.0f;
}

bool texel_lights_agree(const TexelFilterGuide& guide, size_t i, size_t j) {
    const float a = guide.light[i], b = guide.light[j];
    if (std::max(a, b) <= kTexelFilterLightRatio * std::min(a, b)) return true;
    if (guide.variance.empty() || guide.scattered.empty()) return false;
    const float sa = guide.scattered[i], sb = guide.scattered[j];
    if (!(std::max(sa, sb) <= kTexelFilterLightRatio * std::min(sa, sb))) return false;
    const float spread = guide.variance[i] + guide.variance[j];
    return std::abs(a - b) <= kTexelFilterLightSigmas * std::sqrt(spread);
}

int texel_filter_radius(const BakeEstimator& estimator) {
    // Texels reading the vertex correction field run no terms of their own to filter.
    return estimator.method() == BakeMethod::Impulse && !estimator.texel_reads_field()
               ? estimator.settings().texel_mc_radius
               : 0;
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
                                               const TexelFilterGuide& guide, int radius,
                                               const std::vector<SingleCorrectionSums>* single,
                                               std::vector<int>* window) {
    if (window) window->assign(sums.size(), 0);
    if (radius <= 0 && !single) {
        if (window)
            for (size_t i = 0; i < sums.size(); ++i)
                (*window)[i] = map.texels[i].state == TexelState::Valid;
        return sums;
    }
    std::vector<IrradianceParts> out(sums.size());
    tbb::parallel_for(size_t(0), sums.size(), [&](size_t i) {
        const bool valid = map.texels[i].state == TexelState::Valid;
        if (radius <= 0) {
            out[i] = valid ? filtered_texel_terms(sums, single, i, {i}) : sums[i];
            if (window) (*window)[i] = valid;
            return;
        }
        const std::vector<size_t> near = texel_filter_neighbours(map, guide, i, radius);
        out[i] = filtered_texel_terms(sums, single, i, near);
        if (window) (*window)[i] = int(near.size());
    });
    return out;
}

vec3 ratio_correction(const std::vector<SingleCorrectionSums>& sums, size_t i,
                      const std::vector<size_t>& near) {
    vec3 real(0.0f), paired(0.0f);
    for (size_t j : near) {
        real += sums[j].real;
        paired += sums[j].paired_tables;
    }
    vec3 out(0.0f);
    for (int c = 0; c < 3; ++c) {
        const ExplainedSingle x = explained_single(real[c], paired[c], float(near.size()));
        out[c] = x.scale * sums[i].tables[c] + x.added - sums[i].tables[c];
    }
    return out;
}

ExplainedSingle explained_single(float real, float paired, float count) {
    const float below = paired + kTablesExplainShare * real;
    if (!(below > 0.0f) || !(count > 0.0f)) return {1.0f, 0.0f};  // nothing drawn
    return {real / below, kTablesExplainShare * real * real / (count * below)};
}

IrradianceParts filtered_texel_terms(const std::vector<IrradianceParts>& sums,
                                     const std::vector<SingleCorrectionSums>* single, size_t i,
                                     const std::vector<size_t>& near) {
    IrradianceParts out = mean_of_texels(sums, near);
    if (single) out.single += ratio_correction(*single, i, near);
    return out;
}

}  // namespace freqlab
