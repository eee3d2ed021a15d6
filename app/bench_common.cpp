#include "bench_common.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"
#include "base/file_io.h"

namespace freqlab {

int equal_time_mis_spp(const Scene& scene, const std::function<RenderConfig(int spp)>& mis_config,
                       const EmbreeDevice& device, int frame, double target_ms,
                       Progress& progress) {
    constexpr int kLow = 8, kHigh = 64, kTimings = 3;
    auto time_at = [&](int spp) {
        FrameRenderer r(scene, mis_config(spp), device);
        r.render(frame, progress);  // warm
        std::vector<double> t;
        for (int i = 0; i < kTimings; ++i)
            t.push_back(r.render(frame, progress).stats["time_ms"].get<double>());
        return median(t);
    };
    const double t_low = time_at(kLow), t_high = time_at(kHigh);
    // A frame too small for its samples to show in the time (or a hiccup of a noisy machine)
    // gives no slope to extrapolate: refused, not replaced by a guess.
    if (!(t_high > t_low))
        throw Error("--size", "",
                    "MIS frames at " + std::to_string(kLow) + " and " + std::to_string(kHigh) +
                        " spp took " + std::to_string(t_low) + " and " + std::to_string(t_high) +
                        " ms (medians of " + std::to_string(kTimings) +
                        "): no time per sample to reach the equal-time count from; use a "
                        "larger frame");
    const double per_spp = (t_high - t_low) / double(kHigh - kLow), t_0 = t_low - kLow * per_spp;
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

WorkPart bench_work_part(const BenchArgs& args) {
    const Cluster& cluster = Cluster::world();
    if (args.part.empty()) return cluster.part();
    if (cluster.distributed())
        throw Error("--part", args.part, "not under mpirun: the ranks split the work there");
    return parse_work_part(args.part, "--part");
}

void write_bench_part(const BenchArgs& args, WorkPart part, const nlohmann::json& header,
                      const nlohmann::json& rows) {
    const nlohmann::json file = {{"study", args.study},
                                 {"part", {{"index", part.index}, {"count", part.count}}},
                                 {"header", header},
                                 {"rows", rows}};
    write_text_atomically(std::filesystem::path(args.out) / "bench_part.json", file.dump(2) + "\n");
}

}  // namespace freqlab
