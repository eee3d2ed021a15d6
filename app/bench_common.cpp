#include "bench_common.h"

#include <algorithm>
#include <cmath>

namespace freqlab {

int equal_time_mis_spp(const Scene& scene, const std::function<RenderConfig(int spp)>& mis_config,
                       const EmbreeDevice& device, int frame, double target_ms,
                       Progress& progress) {
    auto time_at = [&](int spp) {
        FrameRenderer r(scene, mis_config(spp), device);
        r.render(frame, progress);  // warm
        return r.render(frame, progress).stats["time_ms"].get<double>();
    };
    const double t8 = time_at(8), t32 = time_at(32);
    const double per_spp = std::max((t32 - t8) / 24.0, 1e-6), t_0 = t8 - 8.0 * per_spp;
    return std::max(1, int(std::floor((target_ms - t_0) / per_spp)));
}

RenderConfig bench_config(RenderMethod method, const std::vector<std::string>& sets,
                          const std::vector<std::string>& extra, int width, int height) {
    RenderConfig c;
    c.method = method;
    SettingsGroup g = c.settings_group();
    for (const std::string& s : sets) g.apply_assignment(s);
    for (const std::string& s : extra) g.apply_assignment(s);
    c.frame.width = width;
    c.frame.height = height;
    return c;
}

double median(std::vector<double> v) {
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    const size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace freqlab
