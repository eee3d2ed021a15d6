#include "render/frame_renderer.h"

#include <chrono>
#include <cmath>

#include "base/error.h"
#include "render/gbuffer.h"

namespace freqlab {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace

const std::vector<std::string>& render_method_names() {
    static const std::vector<std::string> names = {"gbuffer", "mis",    "reference",
                                                   "points",  "sparse", "cache"};
    return names;
}

RenderMethod parse_render_method(const std::string& name) {
    const auto& names = render_method_names();
    for (size_t i = 0; i < names.size(); ++i) {
        if (name != names[i]) continue;
        if (i == 0) return RenderMethod(i);
        throw Error("--method", name,
                    "this method is not implemented yet (it lands with its issue); the "
                    "implemented method is: gbuffer");
    }
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    throw Error("--method", name, "unknown method; expected one of: " + list);
}

SettingsGroup RenderConfig::settings_group() {
    SettingsGroup g;
    g.bind(FrameSettings::schema(), &frame);
    g.bind(GBufferSettings::schema(), &gbuffer);
    return g;
}

long count_nonfinite(const LayerSet& layers) {
    long n = 0;
    for (const Layer& l : layers.layers())
        for (float v : l.data) n += !std::isfinite(v);
    return n;
}

FrameRenderer::FrameRenderer(const Scene& scene, const RenderConfig& config,
                             const EmbreeDevice& device)
    : scene_(scene), config_(config), ray_scene_(scene, device) {}

FrameResult FrameRenderer::render(int frame, Progress& progress) {
    const auto t_start = Clock::now();
    FrameResult result;
    result.frame = frame;
    result.time_s = scene_.time_of_frame(frame);
    nlohmann::json stages = nlohmann::json::object();

    auto t0 = Clock::now();
    ray_scene_.update(result.time_s);
    stages["accel_update"] = ms_since(t0);

    t0 = Clock::now();
    GBufferOutput gb = render_gbuffer(ray_scene_, frame, config_.frame, config_.gbuffer, progress);
    stages["gbuffer"] = ms_since(t0);
    result.layers = std::move(gb.layers);

    const long nonfinite = count_nonfinite(result.layers);
    result.stats = {
        {"frame", frame},
        {"time_s", result.time_s},
        {"time_ms", ms_since(t_start)},
        {"stages", stages},
        {"rays", gb.rays},
        {"pixels_total", long(result.layers.pixel_count())},
        {"pixels_shaded", long(result.layers.pixel_count())},
        {"nonfinite", nonfinite},
    };
    return result;
}

}  // namespace freqlab
