#include "volume/lightmap_error.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/error.h"
#include "image/metrics.h"
#include "math/types.h"
#include "volume/lightmap_atlas.h"

namespace freqlab {

namespace {
// The texels a lightmap measure counts: Valid in `valid`, and flagged in `only` when given.
bool measured(const Layer& valid, const std::vector<uint8_t>* only, size_t i) {
    return int(valid.data[i]) == int(TexelState::Valid) &&
           (!only || (i < only->size() && (*only)[i]));
}
}  // namespace

double valid_texel_luminance_sum(const LayerSet& lightmap, const std::string& layer,
                                 const std::vector<uint8_t>* only) {
    const Layer& l = lightmap.get(layer);
    const Layer& valid = lightmap.get("texel_valid");
    if (l.channels != 3) throw Error("", layer, "expected an RGB layer");
    if (only && only->size() != lightmap.pixel_count())
        throw Error("", layer, "the texel mask does not match the lightmap's size");
    double sum = 0.0;
    for (size_t i = 0; i < lightmap.pixel_count(); ++i)
        if (measured(valid, only, i))
            sum += luminance(vec3(l.data[3 * i], l.data[3 * i + 1], l.data[3 * i + 2]));
    return sum;
}

LightmapError compare_lightmaps(const LayerSet& test, const LayerSet& ref, const std::string& layer,
                                const std::vector<uint8_t>* only, size_t worst,
                                const LayerSet* ref_half) {
    auto check_size = [&](const LayerSet& r) {
        if (test.width() != r.width() || test.height() != r.height())
            throw Error("", layer,
                        "lightmap sizes differ: " + std::to_string(test.width()) + "x" +
                            std::to_string(test.height()) + " against " +
                            std::to_string(r.width()) + "x" + std::to_string(r.height()));
    };
    check_size(ref);
    if (ref_half) check_size(*ref_half);
    const Layer& a = test.get(layer);
    const Layer& b = ref.get(layer);
    const Layer* b2 = ref_half ? &ref_half->get(layer) : nullptr;
    if (b2 && b2->channels != b.channels)
        throw Error("", layer, "the two reference halves have different channel counts");
    const Layer& valid = ref.get("texel_valid");
    if (only && only->size() != ref.pixel_count())
        throw Error("", layer, "the texel mask does not match the lightmap's size");
    // The reference's value (the mean of the halves when there are two) and the variance of
    // that mean as the halves' difference estimates it.
    auto reference = [&](size_t k, double* variance) {
        const double r1 = b.data[k];
        if (!b2) return r1;
        const double r2 = b2->data[k];
        *variance = 0.25 * (r1 - r2) * (r1 - r2);
        return 0.5 * (r1 + r2);
    };
    LightmapError e;
    double mean_ref = 0.0, unused = 0.0;
    const int ch = std::min(a.channels, b.channels);
    for (size_t i = 0; i < ref.pixel_count(); ++i) {
        if (!measured(valid, only, i)) continue;
        ++e.texels;
        for (int c = 0; c < ch; ++c) mean_ref += reference(i * b.channels + c, &unused);
    }
    if (e.texels == 0) return e;
    mean_ref /= double(e.texels) * ch;
    const double eps = kLightmapRelMseEpsilonOfMean * mean_ref;
    const double eps2 = eps * eps + 1e-30;
    double rel = 0.0, sq = 0.0, ref2 = 0.0, rel_lit = 0.0, noise = 0.0, noise_lit = 0.0;
    std::vector<std::pair<double, size_t>> terms;  // (the texel's relmse term, texel)
    for (size_t i = 0; i < ref.pixel_count(); ++i) {
        if (!measured(valid, only, i)) continue;
        double texel_rel = 0.0, texel_ref = 0.0, texel_noise = 0.0;
        for (int c = 0; c < ch; ++c) {
            double variance = 0.0;
            const double r = reference(i * b.channels + c, &variance);
            const double t = a.data[i * a.channels + c];
            texel_rel += (t - r) * (t - r) / (r * r + eps2);
            texel_noise += variance / (r * r + eps2);
            sq += (t - r) * (t - r);
            ref2 += r * r;
            texel_ref += r;
        }
        rel += texel_rel;
        noise += texel_noise;
        if (texel_ref >= kLightmapLitTexelFractionOfMean * mean_ref * ch) {
            rel_lit += texel_rel;
            noise_lit += texel_noise;
            ++e.texels_lit;
        }
        if (worst > 0) terms.emplace_back(texel_rel, i);
    }
    const double n = double(e.texels) * ch;
    e.relmse = rel / n;
    e.relmse_lit = e.texels_lit > 0 ? rel_lit / (double(e.texels_lit) * ch) : 0.0;
    if (b2) {
        e.reference_noise = noise / n;
        e.reference_noise_lit = e.texels_lit > 0 ? noise_lit / (double(e.texels_lit) * ch) : 0.0;
    }
    const size_t listed = std::min(worst, terms.size());
    std::partial_sort(terms.begin(), terms.begin() + long(listed), terms.end(),
                      [](const auto& p, const auto& q) { return p.first > q.first; });
    const auto lum = [](const Layer& l, size_t i) {
        return l.channels == 3
                   ? luminance(vec3(l.data[3 * i], l.data[3 * i + 1], l.data[3 * i + 2]))
                   : l.data[i * l.channels];
    };
    for (size_t k = 0; k < listed; ++k) {
        const size_t i = terms[k].second;
        const float ref_lum = b2 ? 0.5f * (lum(b, i) + lum(*b2, i)) : lum(b, i);
        e.worst.push_back({int(i % ref.width()), int(i / ref.width()), lum(a, i), ref_lum,
                           rel > 0.0 ? terms[k].first / rel : 0.0});
    }
    e.rmse = std::sqrt(sq / n);
    e.rel_l2 = ref2 > 0.0 ? std::sqrt(sq / ref2) : 0.0;
    return e;
}

LightmapError combine_lightmap_errors(const std::vector<LightmapError>& parts) {
    LightmapError all;
    double rel = 0.0, rel_lit = 0.0, squares = 0.0, noise = 0.0, noise_lit = 0.0;
    bool noise_known = true, any = false;
    for (const LightmapError& e : parts) {
        if (e.texels == 0) continue;  // nothing measured (no such layer, no valid texel)
        any = true;
        rel += e.relmse * double(e.texels);
        rel_lit += e.relmse_lit * double(e.texels_lit);
        squares += e.rmse * e.rmse * double(e.texels);
        noise += e.reference_noise * double(e.texels);
        noise_lit += e.reference_noise_lit * double(e.texels_lit);
        noise_known = noise_known && e.reference_noise >= 0.0;
        all.texels += e.texels;
        all.texels_lit += e.texels_lit;
    }
    const double n = double(all.texels), n_lit = double(all.texels_lit);
    all.relmse = n > 0.0 ? rel / n : 0.0;
    all.relmse_lit = n_lit > 0.0 ? rel_lit / n_lit : 0.0;
    all.rmse = n > 0.0 ? std::sqrt(squares / n) : 0.0;
    all.rel_l2 = std::numeric_limits<double>::quiet_NaN();
    if (any && noise_known) {
        all.reference_noise = n > 0.0 ? noise / n : 0.0;
        all.reference_noise_lit = n_lit > 0.0 ? noise_lit / n_lit : 0.0;
    }
    return all;
}

}  // namespace freqlab
