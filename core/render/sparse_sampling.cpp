#include "render/sparse_sampling.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace freqlab {

double sampling_density(double B_S, double radians_per_pixel, const SparseSettings& s) {
    const double b_min = 1.0 / (2.0 * s.f_max);
    const double d = B_S * radians_per_pixel * s.density_scale;
    return std::isfinite(d) ? std::clamp(d, b_min, 1.0) : 1.0;
}

PixelFeature pixel_feature(const SurfaceHit& hit, const vec3& view_dir, double radians_per_pixel) {
    if (!hit.valid) return PixelFeature{};
    const float cos_view = std::fabs(glm::dot(hit.geometric_normal, view_dir));
    return PixelFeature{true, hit.object, hit.position, hit.shading_normal,
                        float(hit.distance * radians_per_pixel) / std::max(cos_view, 0.05f)};
}

double radians_per_pixel(const CameraRayGenerator& camera, int w, int h) {
    const double fov_y = 2.0 * std::atan(double(camera.tan_half_fov));
    const double fov_x = 2.0 * std::atan(double(camera.tan_half_fov) * camera.aspect);
    return std::max(fov_x / w, fov_y / h);
}

bool rejection_sample(double density, CounterRng& rng) {
    return double(rng.next_float()) < density;
}

void upsample_statistics(int w, int h, const std::vector<PixelFeature>& f,
                         const std::vector<int>& sources,
                         const std::vector<VisibilityStats>& values, int stride,
                         std::vector<VisibilityStats>& out, std::vector<char>& found) {
    out.assign(size_t(w) * h, VisibilityStats{});
    found.assign(size_t(w) * h, 0);
    // Sources bucketed into stride x stride cells: a window visits ~25 cells, not (4 stride)^2
    // pixels.
    const int cw = (w + stride - 1) / stride, ch = (h + stride - 1) / stride;
    std::vector<std::vector<int>> cells(size_t(cw) * ch);
    for (size_t k = 0; k < sources.size(); ++k) {
        const int sx = sources[k] % w, sy = sources[k] / w;
        cells[size_t(sy / stride) * cw + size_t(sx / stride)].push_back(int(k));
    }
    const int radius = 2 * stride;
    const float inv_s2 = 1.0f / (2.0f * float(stride) * float(stride));
    tbb::parallel_for(0, h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            const PixelFeature& fi = f[i];
            if (!fi.valid) continue;
            double sum_w = 0.0;
            std::array<double, kUpsampledStats> acc{};
            for (int cy = std::max(0, (y - radius) / stride);
                 cy <= std::min(ch - 1, (y + radius) / stride); ++cy)
                for (int cx = std::max(0, (x - radius) / stride);
                     cx <= std::min(cw - 1, (x + radius) / stride); ++cx)
                    for (int k : cells[size_t(cy) * cw + size_t(cx)]) {
                        const size_t j = size_t(sources[size_t(k)]);
                        const int xx = int(j % size_t(w)), yy = int(j / size_t(w));
                        if (std::abs(xx - x) > radius || std::abs(yy - y) > radius) continue;
                        if (f[j].object != fi.object) continue;
                        const float dx = float(xx - x), dy = float(yy - y);
                        const float dn2 =
                            glm::dot(fi.normal - f[j].normal, fi.normal - f[j].normal);
                        const float reach = std::max(fi.footprint * float(stride), 1e-12f);
                        const float dp = glm::length(fi.position - f[j].position) / reach;
                        const double weight = std::exp(-(dx * dx + dy * dy) * inv_s2 -
                                                       dn2 / (2.0f * 0.0625f) - 0.5f * dp * dp);
                        if (!(weight > 1e-8)) continue;
                        sum_w += weight;
                        for (int c = 0; c < kUpsampledStats; ++c)
                            acc[size_t(c)] += weight * values[size_t(k)][size_t(c)];
                    }
            if (sum_w > 0) {
                found[i] = 1;
                for (int c = 0; c < kUpsampledStats; ++c)
                    out[i][size_t(c)] = float(acc[size_t(c)] / sum_w);
            }
        }
    });
}

}  // namespace freqlab
