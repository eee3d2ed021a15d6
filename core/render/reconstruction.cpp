#include "render/reconstruction.h"

#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>

#include "math/fast_math.h"

namespace freqlab {

double reconstruction_weight(const PixelFeature& fi, const PixelFeature& fj, float mu_i, float mu_j,
                             float sigma_i, float sigma_j, const SparseSettings& s) {
    const vec3 d = fi.position - fj.position;
    const float footprint = std::max(fi.footprint, 1e-12f);
    const float dp2 = glm::dot(d, d) / (footprint * footprint);
    const float dn2 = glm::dot(fi.normal - fj.normal, fi.normal - fj.normal);
    const float dm = mu_i - mu_j, ds = sigma_i - sigma_j;
    return fast_exp(-(dp2 / (2.0f * s.sigma_position * s.sigma_position) +
                      dn2 / (2.0f * s.sigma_normal * s.sigma_normal) +
                      dm * dm / (2.0f * s.sigma_mu_v * s.sigma_mu_v) +
                      ds * ds / (2.0f * s.sigma_sigma_v * s.sigma_sigma_v)));
}

namespace {

// Eq. 6.1's sums at pixel (x, y) over the samples within radius r: the weights' sum, and the
// weighted values into *acc.
inline double weighted_sum(const ReconstructionInput& in, int x, int y, float r,
                           const SparseSettings& s, glm::dvec3* acc, ReconstructionRecord* record) {
    const int w = in.width, h = in.height;
    const size_t i = size_t(y) * w + x;
    const PixelFeature& fi = in.features[i];
    const int ri = int(std::ceil(r));
    double sum_w = 0.0;
    for (int yy = std::max(0, y - ri); yy <= std::min(h - 1, y + ri); ++yy) {
        // Only the row's span inside the disc (the profile showed the scan of the square's
        // corners and their feature loads).
        const float dy = float(yy - y), room = r * r - dy * dy;
        if (room < 0.0f) continue;
        const int span = int(std::sqrt(room)) + 1;
        for (int xx = std::max(0, x - span); xx <= std::min(w - 1, x + span); ++xx) {
            const size_t j = size_t(yy) * w + xx;
            if (!in.sampled[j]) continue;
            const float dx = float(xx - x);
            if (dx * dx + dy * dy > r * r) continue;
            const PixelFeature& fj =
                in.sample_features.empty() ? in.features[j] : in.sample_features[j];
            if (fj.object != fi.object) continue;
            const double weight = reconstruction_weight(fi, fj, in.mu_v[i], in.mu_v[j],
                                                        in.sigma_v[i], in.sigma_v[j], s);
            sum_w += weight;
            *acc += weight * glm::dvec3(in.value[j]);
            if (record) record->used.push_back({xx, yy, weight});
        }
    }
    return sum_w;
}

}  // namespace

void reconstruct_pixel_at(const ReconstructionInput& in, int x, int y, float r,
                          const SparseSettings& s, ReconstructionRecord& record) {
    record.used.clear();
    glm::dvec3 acc(0.0);
    record.sum = weighted_sum(in, x, y, r, s, &acc, &record);
    record.radius = r;
    record.recorded = true;
}

ReconstructionOutput reconstruct(const ReconstructionInput& in, const SparseSettings& s,
                                 ReconstructionRecord* record) {
    const int w = in.width, h = in.height;
    const size_t n = size_t(w) * h;
    ReconstructionOutput out;
    out.value.assign(n, vec3(0.0f));
    out.weight.assign(n, 0.0f);
    out.radius_used.assign(n, 0.0f);
    out.fallback.assign(n, 0);
    std::atomic<long> fallbacks{0};
    // 16 x 16 tiles (seed §7), rows of tiles in parallel; each pixel reads only the inputs.
    const int tiles_y = (h + 15) / 16;
    tbb::parallel_for(0, tiles_y, [&](int ty) {
        long local_fallbacks = 0;
        for (int y = ty * 16; y < std::min(h, ty * 16 + 16); ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = size_t(y) * w + x;
                const PixelFeature& fi = in.features[i];
                if (!fi.valid) continue;
                float r = std::clamp(in.radius[i], 1.0f, s.f_max);
                ReconstructionRecord* here =
                    record && record->x == x && record->y == y ? record : nullptr;
                for (;;) {
                    if (here) here->used.clear();
                    glm::dvec3 acc(0.0);
                    const double sum_w = weighted_sum(in, x, y, r, s, &acc, here);
                    if (here) {
                        here->radius = r;
                        here->sum = sum_w;
                        here->recorded = true;
                    }
                    if (sum_w > 1e-6) {
                        out.value[i] = vec3(acc / sum_w);
                        out.weight[i] = float(sum_w);
                        out.radius_used[i] = r;
                        break;
                    }
                    if (r >= 4.0f * s.f_max) {
                        out.fallback[i] = 1;
                        out.radius_used[i] = r;
                        ++local_fallbacks;
                        break;
                    }
                    r = std::min(2.0f * r, 4.0f * s.f_max);
                }
            }
        fallbacks.fetch_add(local_fallbacks, std::memory_order_relaxed);
    });
    out.fallback_pixels = fallbacks.load();
    return out;
}

}  // namespace freqlab
