#include "workbench.h"

#include "workbench_state.h"

#include <glad/gl.h>
#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>

#include "base/error.h"
#include "base/file_io.h"
#include "base/job.h"
#include "gl_host.h"
#include "glfw_host.h"
#include "image/image_io.h"
#include "layer_view.h"
#include "osmesa_host.h"
#include "render/frame_renderer.h"
#include "scene/scene_loader.h"
#include "settings_panel.h"

namespace freqlab::ui {

namespace fs = std::filesystem;

void restart_renderer(Workbench::State& s) {
    s.job.reset();  // cancels and joins
    s.trace_lines.clear();
    s.trace_pixel = {-1, -1};
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        s.results.clear();
    }
    s.shown = nullptr;
    s.shown_frame = -1;
    s.error.clear();
    if (s.device) s.renderer = std::make_unique<FrameRenderer>(s.scene, s.config, *s.device);
    // References depend on the settings too: drop them with the frames.
    s.reference_job.reset();
    s.reference_renderer.reset();
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        s.references.clear();
    }
    s.metrics.clear();
}

namespace {

const char* kStats[] = {"time_ms", "rays", "pixels_shaded"};

void start_job_if_needed(Workbench::State& s) {
    if (s.job && !s.job->done()) return;
    if (s.job) {
        const ProgressSnapshot snap = s.job->snapshot();
        if (!snap.error.empty()) s.error = snap.error;
        s.job.reset();
    }
    if (!s.renderer || !s.error.empty()) return;  // do not retry a failing render every frame
    int frame = s.frame;
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        if (s.results.count(s.frame)) return;
        // Scrubbing forward with a method that carries state across frames renders every
        // frame in between, in order; scrubbing back shows what is kept.
        if (s.config.needs_previous_frames())
            for (int f = 0; f < s.frame; ++f)
                if (!s.results.count(f)) {
                    frame = f;
                    break;
                }
    }
    s.job_frame = frame;
    Workbench::State* sp = &s;
    s.job = std::make_unique<Job>([sp, frame](Progress& progress) {
        progress.set_stage_count(sp->config.method == RenderMethod::GBuffer ? 1 : 2);
        FrameResult r = sp->renderer->render(frame, progress);
        std::lock_guard<std::mutex> lock(sp->results_mutex);
        sp->results[frame] = std::move(r);
    });
}

ImU32 to_u32(const vec3& c) {
    return ImGui::ColorConvertFloat4ToU32(ImVec4(c.r, c.g, c.b, 1.0f));
}

// Builds (or loads from the cache) the scene environment's bandwidth hierarchy, once.
void start_env_bandwidth_job(Workbench::State& s) {
    if (s.env_bandwidth_job || !s.scene.environment()) return;
    Workbench::State* sp = &s;
    s.env_bandwidth_job = std::make_unique<Job>([sp](Progress&) {
        const EnvironmentMap& env = *sp->scene.environment();
        const EnvBandwidthHierarchy h = EnvBandwidthHierarchy::cached(env);
        auto result = std::make_unique<FrameResult>();
        result->frame = -100;  // not a frame of the animation
        result->layers = bandwidth_layers(env, h, 1024);
        result->stats = {{"frame", -100},
                         {"time_ms", 0.0},
                         {"rays", 0},
                         {"levels", h.levels().size()},
                         {"env_width", h.env_width()},
                         {"nyquist_cycles_per_rad", h.nyquist()}};
        std::lock_guard<std::mutex> lock(sp->results_mutex);
        sp->env_bandwidth = std::move(result);
    });
}

void draw_settings_panel(Workbench::State& s) {
    ImGui::Text("scene: %s", s.scene.name.c_str());
    int method = int(s.config.method);
    const char* methods = "gbuffer\0mis\0reference\0points\0sparse\0";
    if (ImGui::Combo("method", &method, methods) && method != int(s.config.method)) {
        s.config.method = RenderMethod(method);
        restart_renderer(s);
    }
    if (ImGui::Checkbox("view environment bandwidth", &s.show_env_bandwidth)) s.view_dirty = true;
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "Method A's B_L hierarchy (cycles/rad) per window size over the lat-long "
            "map, in place of the frame; pick the level as a layer.");
    if (s.show_env_bandwidth) start_env_bandwidth_job(s);
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "gbuffer: primary rays only; mis: MIS direct lighting at mis.spp; "
            "reference: the same at reference.spp (cached on disk)");
    SettingsGroup group = s.config.settings_group();
    const uint32_t changed = draw_settings(group, !s.options.show_tables);
    if (changed & (kInvalidatesGBuffer | kInvalidatesShading))
        restart_renderer(s);
    else if (changed & kInvalidatesDisplay)
        s.view_dirty = true;

    draw_compare_panel(s);
    draw_tables_panel(*s.tables);
    if (ImGui::CollapsingHeader("Help")) {
        ImGui::TextWrapped(
            "Space: play / pause    Left / Right: previous / next frame\n"
            "Click the image: inspect that pixel    Wheel: zoom at the cursor\n"
            "Right-drag: pan    F: fit the image    Export menu: PNG, EXR, CSV");
    }
}

void draw_colorbar(Workbench::State& s, const Layer& layer, ImVec2 origin, float width) {
    ImDrawList* dl = ImGui::GetWindowDrawList();
    s.colorbar_rect = {};
    s.legend.clear();
    if (layer.kind == LayerKind::Color || layer.channels >= 3) return;
    if (layer.kind == LayerKind::Categorical) {
        // Swatch + name per category, wrapping to new lines within the viewport's width.
        const float right = origin.x + std::max(width, ImGui::GetContentRegionAvail().x);
        float x = origin.x, y = origin.y;
        for (size_t i = 0; i < layer.legend.size(); ++i) {
            const float item = 18 + ImGui::CalcTextSize(layer.legend[i].c_str()).x + 14;
            if (x > origin.x && x + item > right) x = origin.x, y += 20;
            const ImVec2 a(x, y + 2), b(x + 14, y + 16);
            dl->AddRectFilled(a, b, to_u32(categorical(int(i))));
            dl->AddText(ImVec2(x + 18, y + 2), IM_COL32(230, 230, 230, 255),
                        layer.legend[i].c_str());
            s.legend.push_back({layer.legend[i], ScreenRect{a.x, a.y, b.x, b.y}});
            x += item;
        }
        ImGui::Dummy(ImVec2(width, y - origin.y + 20));
        return;
    }
    // Gradient in 128 steps drawn from the same colormap functions as the LUTs.
    const int steps = 128;
    const float h = 14;
    const DisplayRange r = s.shown_range;
    for (int i = 0; i < steps; ++i) {
        const float t0 = float(i) / steps, t1 = float(i + 1) / steps;
        const vec3 c0 = layer.kind == LayerKind::Signed ? diverging(2 * t0 - 1) : viridis(t0);
        const vec3 c1 = layer.kind == LayerKind::Signed ? diverging(2 * t1 - 1) : viridis(t1);
        dl->AddRectFilledMultiColor(ImVec2(origin.x + t0 * width, origin.y),
                                    ImVec2(origin.x + t1 * width + 0.5f, origin.y + h), to_u32(c0),
                                    to_u32(c1), to_u32(c1), to_u32(c0));
    }
    s.colorbar_rect = {origin.x, origin.y, origin.x + width, origin.y + h};
    for (double t : colorbar_ticks(r.lo, r.hi)) {
        // A one-pixel rectangle on a whole pixel: crisp, where an anti-aliased line would
        // smear over two columns at half intensity.
        const float x = std::floor(origin.x + float((t - r.lo) / (r.hi - r.lo)) * width);
        dl->AddRectFilled(ImVec2(x, origin.y + h), ImVec2(x + 1, origin.y + h + 5),
                          IM_COL32(230, 230, 230, 255));
        char label[32];
        std::snprintf(label, sizeof label, "%g", t);
        const float tw = ImGui::CalcTextSize(label).x;
        dl->AddText(
            ImVec2(std::clamp(x - tw / 2, origin.x, origin.x + width - tw), origin.y + h + 6),
            IM_COL32(230, 230, 230, 255), label);
    }
    ImGui::Dummy(ImVec2(width, h + 24));
}

void draw_viewport(Workbench::State& s) {
    if (!s.error.empty()) {
        ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1, 0.4f, 0.4f, 1));
        ImGui::TextWrapped("error: %s", s.error.c_str());
        ImGui::PopStyleColor();
    }
    s.image_rect = {};
    if (!s.shown) {
        ImGui::TextDisabled("rendering frame %d ...", s.frame);
        return;
    }
    const LayerSet& L = s.shown->layers;
    ImGui::SetNextItemWidth(180);
    if (ImGui::BeginCombo("layer", s.layer_name.c_str())) {
        for (const Layer& l : L.layers())
            if (ImGui::Selectable(l.name.c_str(), l.name == s.layer_name)) {
                s.layer_name = l.name;
                s.view_dirty = true;
            }
        ImGui::EndCombo();
    }
    const Layer* layer = L.find(s.layer_name);
    if (!layer) {
        s.layer_name = "color";
        layer = &L.get("color");
        s.view_dirty = true;
    }
    ImGui::SameLine();
    ImGui::TextDisabled("[%s] %s", to_string(layer->kind), layer->description.c_str());
    if (layer->kind != LayerKind::Color) {
        if (ImGui::Checkbox("over colour", &s.overlay_on_color)) s.view_dirty = true;
        ImGui::SameLine();
        ImGui::SetNextItemWidth(100);
        ImGui::SliderFloat("opacity", &s.overlay_opacity, 0.0f, 1.0f);
        ImGui::SameLine();
        if (ImGui::Checkbox("fixed range", &s.fixed_range)) s.view_dirty = true;
        if (s.fixed_range) {
            ImGui::SameLine();
            ImGui::SetNextItemWidth(140);
            if (ImGui::InputFloat2("range", &s.range.lo)) s.view_dirty = true;
        }
    }
    if (s.view_dirty) {
        DisplayParams params;
        params.exposure_ev = s.config.frame.exposure;
        params.auto_range = !s.fixed_range;
        params.range = s.range;
        s.shown_range = s.view.render(L, *layer, params);
        if (!s.fixed_range) s.range = s.shown_range;
        if (s.overlay_on_color && layer->kind != LayerKind::Color)
            s.base_view.render(L, L.get("color"), params);
        render_reference_view(s, params);
        s.view_dirty = false;
    }

    const ImVec2 avail = ImGui::GetContentRegionAvail();
    const float colorbar_h = (layer->kind == LayerKind::Color || layer->channels >= 3) ? 0 : 44;
    const float fit = std::min(avail.x / L.width(), (avail.y - colorbar_h) / L.height());
    const ImVec2 size(L.width() * fit, L.height() * fit);
    const float half = 0.5f / s.zoom;
    s.centre.x = std::clamp(s.centre.x, half, 1 - half);
    s.centre.y = std::clamp(s.centre.y, half, 1 - half);
    const ImVec2 uv0(s.centre.x - half, s.centre.y - half),
        uv1(s.centre.x + half, s.centre.y + half);
    const ImVec2 origin = ImGui::GetCursorScreenPos();
    if (s.overlay_on_color && layer->kind != LayerKind::Color) {
        ImGui::Image(reinterpret_cast<ImTextureID>(intptr_t(s.base_view.texture())), size, uv0,
                     uv1);
        ImGui::SetCursorScreenPos(origin);
        ImGui::Image(reinterpret_cast<ImTextureID>(intptr_t(s.view.texture())), size, uv0, uv1,
                     ImVec4(1, 1, 1, s.overlay_opacity));
    } else {
        ImGui::Image(reinterpret_cast<ImTextureID>(intptr_t(s.view.texture())), size, uv0, uv1);
    }
    s.image_rect = {origin.x, origin.y, origin.x + size.x, origin.y + size.y};
    const bool item_hovered = ImGui::IsItemHovered();
    if (s.split && s.references.count(s.shown->frame)) {
        // Split view: the reference's colour right of the split, same zoom and pan.
        const float split_u = uv0.x + s.split_position * (uv1.x - uv0.x);
        const ImVec2 a(origin.x + s.split_position * size.x, origin.y);
        ImGui::GetWindowDrawList()->AddImage(
            reinterpret_cast<ImTextureID>(intptr_t(s.reference_view.texture())), a,
            ImVec2(origin.x + size.x, origin.y + size.y), ImVec2(split_u, uv0.y), uv1);
        ImGui::GetWindowDrawList()->AddLine(a, ImVec2(a.x, origin.y + size.y),
                                            IM_COL32(255, 255, 255, 255), 1.5f);
        ImGui::GetWindowDrawList()->AddText(ImVec2(a.x + 6, origin.y + 4),
                                            IM_COL32(255, 255, 255, 255), "reference");
    }
    const ImGuiIO& io = ImGui::GetIO();
    auto mouse_uv = [&] {
        return ImVec2(uv0.x + (io.MousePos.x - origin.x) / size.x * (uv1.x - uv0.x),
                      uv0.y + (io.MousePos.y - origin.y) / size.y * (uv1.y - uv0.y));
    };
    if (item_hovered) {
        if (ImGui::IsMouseClicked(0)) {
            const ImVec2 uv = mouse_uv();
            s.pick_x = std::clamp(int(uv.x * L.width()), 0, L.width() - 1);
            s.pick_y = std::clamp(int(uv.y * L.height()), 0, L.height() - 1);
        }
        if (io.MouseWheel != 0) {
            const ImVec2 before = mouse_uv();
            s.zoom = std::clamp(s.zoom * std::pow(1.25f, io.MouseWheel), 1.0f, 64.0f);
            const float h2 = 0.5f / s.zoom;
            // Keep the texel under the cursor where it is.
            const float fx = (io.MousePos.x - origin.x) / size.x,
                        fy = (io.MousePos.y - origin.y) / size.y;
            s.centre = ImVec2(before.x - (fx - 0.5f) * 2 * h2, before.y - (fy - 0.5f) * 2 * h2);
        }
        if (ImGui::IsMouseDragging(1)) {
            const ImVec2 d = io.MouseDelta;
            s.centre.x -= d.x / size.x / s.zoom;
            s.centre.y -= d.y / size.y / s.zoom;
        }
    }
    if (s.pick_x >= 0) {  // mark the inspected pixel
        const float px =
            origin.x + ((s.pick_x + 0.5f) / L.width() - uv0.x) / (uv1.x - uv0.x) * size.x;
        const float py =
            origin.y + ((s.pick_y + 0.5f) / L.height() - uv0.y) / (uv1.y - uv0.y) * size.y;
        if (s.image_rect.contains(px, py))
            ImGui::GetWindowDrawList()->AddCircle(ImVec2(px, py), 6, IM_COL32(255, 60, 200, 255),
                                                  12, 2);
    }
    draw_colorbar(s, *layer, ImGui::GetCursorScreenPos(), std::min(size.x, 420.0f));
}

// The radiance point's pilot samples in its cone frame (azimuthal-equidistant: distance from
// the centre is the angle from mu_rho): visible green, occluded red; the footprint circle; the
// 1-sigma ellipse of the occluded samples (Eq. 4.4) about their mean.
void draw_cone_samples(const RadiancePoint& rp) {
    ImGui::TextDisabled("pilot samples in the BRDF cone (N_L = %.0f, N_Omega = %.0f)", rp.N_L,
                        rp.N_omega);
    const float size = std::min(ImGui::GetContentRegionAvail().x, 220.0f);
    const ImVec2 o = ImGui::GetCursorScreenPos(), c(o.x + size / 2, o.y + size / 2);
    ImDrawList* dl = ImGui::GetWindowDrawList();
    dl->AddRectFilled(o, ImVec2(o.x + size, o.y + size), IM_COL32(24, 24, 28, 255));
    const double extent = std::max(rp.footprint_radius * 1.25, 0.05);
    const float scale = float(0.5 * size / extent);
    auto at = [&](double u, double v) {
        return ImVec2(c.x + float(u) * scale, c.y - float(v) * scale);
    };
    dl->AddCircle(c, float(rp.footprint_radius) * scale, IM_COL32(200, 200, 200, 200), 64, 1.0f);
    for (const RadiancePoint::ConeSample& q : rp.cone_samples)
        dl->AddCircleFilled(at(q.u, q.v), 2.0f,
                            q.occluded ? IM_COL32(235, 80, 60, 255) : IM_COL32(90, 210, 110, 255));
    if (rp.pilot_occluded > 1) {
        // Ellipse from the eigen-decomposition of the 2x2 covariance.
        const double a = rp.sigma_o[0], b = rp.sigma_o[1], d = rp.sigma_o[2];
        const double tr = 0.5 * (a + d),
                     det = std::sqrt(std::max(0.25 * (a - d) * (a - d) + b * b, 0.0));
        const double l1 = std::sqrt(std::max(tr + det, 0.0)),
                     l2 = std::sqrt(std::max(tr - det, 0.0));
        const double angle = 0.5 * std::atan2(2 * b, a - d);
        ImVec2 prev;
        for (int i = 0; i <= 48; ++i) {
            const double t = 2 * M_PI * i / 48, x = l1 * std::cos(t), y = l2 * std::sin(t);
            const ImVec2 p = at(rp.mu_o[0] + x * std::cos(angle) - y * std::sin(angle),
                                rp.mu_o[1] + x * std::sin(angle) + y * std::cos(angle));
            if (i) dl->AddLine(prev, p, IM_COL32(255, 200, 60, 255), 1.5f);
            prev = p;
        }
    }
    ImGui::Dummy(ImVec2(size, size + 4));
    ImGui::Text("sigma_rho %.4f rad, sigma_V %.4f rad, occluded %d / %d", rp.sigma_rho, rp.sigma_V,
                rp.pilot_occluded, rp.pilot_rays);
}

void draw_inspector(Workbench& wb, Workbench::State& s) {
    if (!s.shown || s.pick_x < 0) {
        ImGui::TextWrapped("Click a pixel in the viewport to see every layer's value there.");
        return;
    }
    ImGui::Text("pixel (%d, %d), frame %d", s.pick_x, s.pick_y, s.shown->frame);
    ImGui::Separator();
    for (const InspectorRow& row : wb.inspect()) {
        std::string values;
        char buf[32];
        for (size_t c = 0; c < row.values.size(); ++c) {
            std::snprintf(buf, sizeof buf, "%s%.5g", c ? ", " : "", row.values[c]);
            values += buf;
        }
        ImGui::Text("%-10s %s %s", row.layer.c_str(), values.c_str(), row.note.c_str());
    }
    ImGui::Separator();
    ImGui::TextDisabled("frame stats");
    for (const auto& [key, value] : s.shown->stats.items())
        if (!value.is_object() && (s.options.show_timings || key != "time_ms"))
            ImGui::Text("%-14s %s", key.c_str(), value.dump().c_str());
    // The method's record of this pixel: its estimate re-run with every sample traced.
    ImGui::Separator();
    // One pixel is cheap to re-run; it waits while a render job owns the renderer.
    const bool idle = (!s.job || s.job->done()) && !s.show_env_bandwidth;
    const std::pair<int, int> pick{s.pick_x, s.pick_y};
    if (s.renderer && idle && (s.trace_pixel != pick || s.trace_frame != s.shown->frame)) {
        RadiancePoint point;
        point.footprint_radius = -1.0;  // stays negative unless a radiance point was traced
        s.trace_lines = s.renderer->trace_pixel(*s.shown, s.pick_x, s.pick_y, 32, &point);
        s.trace_point.reset();
        if (point.footprint_radius >= 0.0) s.trace_point = point;
        s.trace_pixel = pick;
        s.trace_frame = s.shown->frame;
    }
    if (s.trace_point && s.trace_pixel == pick) draw_cone_samples(*s.trace_point);
    ImGui::TextDisabled("trace of this pixel's estimate");
    if (!s.trace_lines.empty() && s.trace_pixel == pick) {
        ImGui::BeginChild("trace", ImVec2(0, 0), true, ImGuiWindowFlags_HorizontalScrollbar);
        for (const std::string& l : s.trace_lines) ImGui::TextUnformatted(l.c_str());
        ImGui::EndChild();
    }
}

void draw_timeline(Workbench::State& s) {
    if (ImGui::Button(s.playing ? "Pause" : "Play")) s.playing = !s.playing;
    ImGui::SameLine();
    if (ImGui::Button("<")) s.frame = std::max(0, s.frame - 1);
    ImGui::SameLine();
    if (ImGui::Button(">")) s.frame = std::min(s.scene.frame_count - 1, s.frame + 1);
    ImGui::SameLine();
    ImGui::SetNextItemWidth(150);
    ImGui::Combo("##stat", &s.stat_index, kStats, 3);
    ImGui::SameLine();
    ImGui::SetNextItemWidth(-1);
    ImGui::SliderInt("##frame", &s.frame, 0, s.scene.frame_count - 1, "frame %d");
    // Stats strip: the chosen statistic for every rendered frame (0 where not rendered yet).
    std::vector<float> values(size_t(s.scene.frame_count), 0.0f);
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        for (const auto& [f, r] : s.results)
            values[size_t(f)] = r.stats[kStats[s.stat_index]].get<float>();
    }
    const float peak = *std::max_element(values.begin(), values.end());
    char overlay[64];
    std::snprintf(overlay, sizeof overlay, "%s (max %.4g)", kStats[s.stat_index], peak);
    ImGui::PlotHistogram("##strip", values.data(), int(values.size()), 0, overlay, 0.0f,
                         peak > 0 ? peak : 1.0f, ImVec2(ImGui::GetContentRegionAvail().x, 44));
    if (s.job && !s.job->done()) {
        const ProgressSnapshot p = s.job->snapshot();
        ImGui::Text("rendering frame %d: %s %.0f%%  ETA %s", s.job_frame, p.stage.c_str(),
                    100 * p.fraction,
                    p.eta_s >= 0 ? (std::to_string(int(p.eta_s + 0.5)) + " s").c_str() : "--");
        ImGui::SameLine();
        if (ImGui::SmallButton("cancel")) s.job->cancel();
    } else if (s.shown && s.options.show_timings) {
        ImGui::Text("frame %d: %.1f ms, %ld rays   %s", s.shown->frame,
                    s.shown->stats["time_ms"].get<double>(), s.shown->stats["rays"].get<long>(),
                    s.status.c_str());
    } else if (s.shown) {
        ImGui::Text("frame %d: %ld rays   %s", s.shown->frame, s.shown->stats["rays"].get<long>(),
                    s.status.c_str());
    }
}

}  // namespace

Workbench::Workbench(const WorkbenchOptions& options) : s_(std::make_unique<State>()) {
    reset(options);
}

void Workbench::reset(const WorkbenchOptions& options) {
    State& s = *s_;
    s.job.reset();
    s.reference_job.reset();
    s.reference_renderer.reset();
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        s.results.clear();
        s.references.clear();
    }
    s.metrics.clear();
    s.shown = nullptr;
    s.options = options;
    s.config = RenderConfig{};
    s.layer_name = options.layer.empty() ? "color" : options.layer;
    if (!options.show_timings) s.stat_index = 1;  // rays: the same on every host
    s.split = options.compare;
    s.tables->open = options.show_tables;
    s.tables->emitter = options.tables_emitter;
    s.pick_x = options.inspect_x;
    s.pick_y = options.inspect_y;
    s.error.clear();
    try {
        s.scene = load_scene(options.scene);
        s.config.method = parse_render_method(options.method);
        SettingsGroup group = s.config.settings_group();
        for (const std::string& a : options.settings) group.apply_assignment(a);
        s.frame = std::clamp(options.frame, 0, s.scene.frame_count - 1);
        if (!s.device) s.device = std::make_unique<EmbreeDevice>(0);
        restart_renderer(s);
    } catch (const Error& e) {
        s.error = e.what();
        s.scene = Scene{};
        s.scene.frame_count = 1;
        s.renderer.reset();
    }
}

Workbench::~Workbench() {
    s_->job.reset();
    s_->reference_job.reset();
}

void Workbench::draw(int fb_w, int fb_h) {
    State& s = *s_;
    const float left_w = 320, right_w = 300, bottom_h = 130, menu_h = ImGui::GetFrameHeight();
    const ImGuiWindowFlags fixed =
        ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse;

    // Keyboard shortcuts (when no widget wants the keyboard).
    if (!ImGui::GetIO().WantCaptureKeyboard) {
        if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Space))) s.playing = !s.playing;
        if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_LeftArrow)))
            s.frame = std::max(0, s.frame - 1);
        if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_RightArrow)))
            s.frame = std::min(s.scene.frame_count - 1, s.frame + 1);
        if (ImGui::IsKeyPressed('F')) s.zoom = 1.0f, s.centre = ImVec2(0.5f, 0.5f);
    }

    if (ImGui::BeginMainMenuBar()) {
        draw_session_menu(*this, s);
        draw_export_menu(s);
        ImGui::EndMainMenuBar();
    }
    poll_reference(s);

    if (s.playing && ++s.play_ticks >= 2) {  // advance when the next frame is ready
        s.play_ticks = 0;
        std::lock_guard<std::mutex> lock(s.results_mutex);
        if (s.results.count(s.frame)) s.frame = (s.frame + 1) % s.scene.frame_count;
    }
    start_job_if_needed(s);
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        auto it = s.results.find(s.frame);
        // Keep showing the latest rendered frame at or before the current one.
        if (it == s.results.end() && !s.results.empty()) {
            auto lb = s.results.upper_bound(s.frame);
            if (lb != s.results.begin()) it = std::prev(lb);
        }
        const FrameResult* r = it == s.results.end() ? nullptr : &it->second;
        if (s.show_env_bandwidth) r = s.env_bandwidth.get();
        if (r != s.shown || (r && r->frame != s.shown_frame)) {
            s.shown = r;
            s.shown_frame = r ? r->frame : -1;
            s.view_dirty = true;
        }
    }

    ImGui::SetNextWindowPos(ImVec2(0, menu_h));
    ImGui::SetNextWindowSize(ImVec2(left_w, fb_h - bottom_h - menu_h));
    ImGui::Begin("Settings", nullptr, fixed);
    draw_settings_panel(s);
    ImGui::End();

    ImGui::SetNextWindowPos(ImVec2(left_w, menu_h));
    ImGui::SetNextWindowSize(ImVec2(fb_w - left_w - right_w, fb_h - bottom_h - menu_h));
    ImGui::Begin("Viewport", nullptr, fixed);
    draw_viewport(s);
    ImGui::End();

    ImGui::SetNextWindowPos(ImVec2(fb_w - right_w, menu_h));
    ImGui::SetNextWindowSize(ImVec2(right_w, fb_h - bottom_h - menu_h));
    ImGui::Begin("Inspector", nullptr, fixed);
    draw_inspector(*this, s);
    ImGui::End();

    ImGui::SetNextWindowPos(ImVec2(0, fb_h - bottom_h));
    ImGui::SetNextWindowSize(ImVec2(float(fb_w), bottom_h));
    ImGui::Begin("Timeline", nullptr, fixed | ImGuiWindowFlags_NoTitleBar);
    draw_timeline(s);
    ImGui::End();
}

void Workbench::set_frame(int frame) {
    s_->frame = std::clamp(frame, 0, s_->scene.frame_count - 1);
}
int Workbench::frame() const {
    return s_->frame;
}

bool Workbench::set_layer(const std::string& name) {
    if (s_->shown && !s_->shown->layers.find(name)) return false;
    s_->layer_name = name;
    s_->view_dirty = true;
    return true;
}

void Workbench::apply_setting(const std::string& assignment) {
    SettingsGroup group = s_->config.settings_group();
    const uint32_t flags = group.apply_assignment(assignment, "workbench");
    if (flags & (kInvalidatesGBuffer | kInvalidatesShading))
        restart_renderer(*s_);
    else
        s_->view_dirty = true;
}

bool Workbench::frame_shown() const {
    const bool env_view = s_->show_env_bandwidth && s_->shown && s_->shown->frame == -100;
    return (s_->shown && (s_->shown->frame == s_->frame || env_view) && !s_->view_dirty) ||
           !s_->error.empty();
}

void Workbench::wait_for_render() {
    if (s_->job) s_->job->wait();
}

const LayerSet* Workbench::layers() const {
    return s_->shown ? &s_->shown->layers : nullptr;
}
DisplayRange Workbench::shown_range() const {
    return s_->shown_range;
}

void Workbench::select_pixel(int x, int y) {
    s_->pick_x = x;
    s_->pick_y = y;
}

std::vector<InspectorRow> Workbench::inspect() const {
    std::vector<InspectorRow> rows;
    const State& s = *s_;
    if (!s.shown || s.pick_x < 0) return rows;
    const LayerSet& L = s.shown->layers;
    if (s.pick_x >= L.width() || s.pick_y >= L.height()) return rows;
    for (const Layer& l : L.layers()) {
        InspectorRow row{l.name, {}, ""};
        for (int c = 0; c < l.channels; ++c)
            row.values.push_back(l.at(L.width(), s.pick_x, s.pick_y, c));
        if (l.kind == LayerKind::Categorical) {
            const int v = int(std::lround(row.values[0]));
            if (v >= 0 && v < int(l.legend.size())) row.note = l.legend[size_t(v)];
        }
        rows.push_back(std::move(row));
    }
    return rows;
}

ScreenRect Workbench::image_rect() const {
    return s_->image_rect;
}
ScreenRect Workbench::colorbar_rect() const {
    return s_->colorbar_rect;
}
std::vector<std::pair<std::string, ScreenRect>> Workbench::legend_swatches() const {
    return s_->legend;
}
const std::string& Workbench::error() const {
    return s_->error;
}

void Workbench::show_env_bandwidth() {
    s_->show_env_bandwidth = true;
    start_env_bandwidth_job(*s_);
    if (s_->env_bandwidth_job) s_->env_bandwidth_job->wait();
}

bool Workbench::tables_ready() const {
    std::lock_guard<std::mutex> lock(s_->tables->mutex);
    return s_->tables->tables != nullptr;
}

void render_ui_frame(GlHost& host, Workbench& workbench) {
    host.begin_frame();
    ImGui_ImplOpenGL3_NewFrame();
    ImGui::NewFrame();
    int w, h;
    host.framebuffer_size(&w, &h);
    workbench.draw(w, h);
    ImGui::Render();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, w, h);
    glClearColor(0.1f, 0.1f, 0.1f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

namespace {

// Shared by both hosts: run until the requested frame is on screen (plus two frames for the
// layout to settle), write the screenshot if asked, or keep going until the window closes.
int run_loop(GlHost& host, Workbench& wb, const WorkbenchOptions& options, bool interactive) {
    int settle = -1;
    if (options.warm_from >= 0) {
        for (int f = options.warm_from; f < options.frame; ++f) {
            wb.set_frame(f);
            for (int i = 0; i < 1000 && !wb.frame_shown(); ++i) {
                wb.wait_for_render();
                render_ui_frame(host, wb);
                host.end_frame();
            }
        }
        wb.set_frame(options.frame);
    }
    if (options.inspect_x >= 0) wb.select_pixel(options.inspect_x, options.inspect_y);
    if (options.show_env_bandwidth) wb.show_env_bandwidth();
    if (options.show_tables)
        for (int i = 0; i < 100000 && !wb.tables_ready(); ++i) {
            render_ui_frame(host, wb);
            host.end_frame();
        }
    if (options.compare) {
        for (int i = 0; i < 1000 && !wb.frame_shown(); ++i) {
            wb.wait_for_render();
            render_ui_frame(host, wb);
            host.end_frame();
        }
        wb.request_reference();
        for (int i = 0; i < 100000 && (wb.reference_busy() || !wb.metrics()); ++i) {
            render_ui_frame(host, wb);
            host.end_frame();
            if (!wb.error().empty()) break;
        }
    }
    for (;;) {
        if (interactive && host.should_close()) return 0;
        if (!interactive && !wb.frame_shown()) wb.wait_for_render();
        render_ui_frame(host, wb);
        if (!options.screenshot.empty()) {
            if (settle < 0 && wb.frame_shown()) settle = 2;
            if (settle == 0) {
                int w, h;
                host.framebuffer_size(&w, &h);
                write_png(options.screenshot, w, h, host.read_rgb());
                std::fprintf(stderr, "wrote %s (%dx%d)\n", options.screenshot.c_str(), w, h);
                if (!wb.error().empty())
                    std::fprintf(stderr, "error shown: %s\n", wb.error().c_str());
                return wb.error().empty() ? 0 : 1;
            }
            if (settle > 0) --settle;
        }
        host.end_frame();
    }
}

struct ImGuiSession {
    ImGuiSession() {
        IMGUI_CHECKVERSION();
        ImGui::CreateContext();
        ImGui::GetIO().IniFilename = nullptr;
        ImGui::StyleColorsDark();
    }
    ~ImGuiSession() { ImGui::DestroyContext(); }
};

}  // namespace

namespace {

int run_on_host(GlHost& host, const WorkbenchOptions& options, bool interactive) {
    ImGui_ImplOpenGL3_Init("#version 330");
    int code;
    {
        Workbench wb(options);
        if (!options.session.empty()) wb.load_session(options.session);
        code = run_loop(host, wb, options, interactive);
    }
    ImGui_ImplOpenGL3_Shutdown();
    return code;
}

}  // namespace

int run_workbench(const WorkbenchOptions& options) {
    ImGuiSession imgui;
    GlfwHost host(options.width, options.height, "freqlab — " + options.scene);
    return run_on_host(host, options, true);
}

int run_headless(const WorkbenchOptions& options) {
    if (options.screenshot.empty())
        throw Error("--headless", "--screenshot",
                    "the headless workbench needs --screenshot OUT.png");
    ImGuiSession imgui;
    OsMesaHost host(options.width, options.height);
    return run_on_host(host, options, false);
}

}  // namespace freqlab::ui
