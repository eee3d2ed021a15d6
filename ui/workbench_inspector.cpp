// The workbench's inspector panel: every layer's value at the picked pixel, the frame's stats,
// the method's trace of that pixel and, for radiance points, their pilot samples in the cone.
#include "workbench_state.h"

#include <imgui.h>

#include <cmath>
#include <cstdio>

namespace freqlab::ui {

// The radiance point's pilot samples in its cone frame (azimuthal-equidistant: distance from
// the centre is the angle from mu_rho): visible green, occluded red; the footprint circle; the
// 1-sigma ellipse of the occluded samples (Eq. 4.4) about their mean.
namespace {

void draw_cone_samples(const RadiancePoint& rp) {
    ImGui::TextDisabled("pilot samples in the BRDF cone (N_L = %.0f, N_Omega = %.0f)", rp.N_L,
                        rp.N_omega);
    const float size =
        std::min(ImGui::GetContentRegionAvail().x, 220.0f * ImGui::GetFontSize() / 13.0f);
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

}  // namespace

namespace {

void draw_values(Workbench& wb, const Workbench::State& s) {
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
}

// The method's record of the picked pixel: its estimate re-run with every sample traced, once
// the renderer is free. While a job owns it, what the frame recorded when it ran: the cache's
// decision for every entry landing near the pixel, with each test's numbers (FrameResult::
// cache_records, read from the run, not recomputed).
void update_trace(Workbench::State& s) {
    const bool idle = (!s.job || s.job->done()) && !s.show_env_bandwidth;
    const std::pair<int, int> pick{s.pick_x, s.pick_y};
    const bool stale = s.trace_pixel != pick || s.trace_frame != s.shown->frame;
    if (s.bake) {
        if (!bake_busy(s) && stale) {
            s.trace_lines = bake_trace(s, s.pick_x, s.pick_y);
            s.trace_point.reset();
            s.trace_pixel = pick;
            s.trace_frame = s.shown->frame;
            s.trace_partial = false;
        }
        return;
    }
    if (s.shown->partial) return;  // its records are on their way (recorded_result)
    if (s.shown->preview) {        // no estimate of its own to trace yet
        s.trace_lines = {"(the frame's first image: its trace comes with the rendered frame)"};
        s.trace_point.reset();
        s.trace_pixel = {-1, -1};
        return;
    }
    if (s.renderer && idle && (stale || s.trace_partial)) {
        RadiancePoint point;
        point.footprint_radius = -1.0;  // stays negative unless a radiance point was traced
        s.trace_lines = s.renderer->trace_pixel(*s.shown, s.pick_x, s.pick_y, 32, &point);
        s.trace_point.reset();
        if (point.footprint_radius >= 0.0) s.trace_point = point;
        s.trace_pixel = pick;
        s.trace_frame = s.shown->frame;
        s.trace_partial = false;
    } else if (!idle && stale && s.shown->cache_records) {
        char head[160];
        std::snprintf(head, sizeof head,
                      "(frame %d is rendering: the cache's decisions as frame %d recorded them; "
                      "the full trace when the job ends)",
                      s.job_frame, s.shown->frame);
        s.trace_lines = {head};
        for (std::string& line :
             cache_entries_near(*s.shown->cache_records, s.shown->cache_snapshot.get(), s.pick_x,
                                s.pick_y, 1, s.shown->layers.width(), s.config.cache, 32))
            s.trace_lines.push_back(std::move(line));
        s.trace_point.reset();
        s.trace_pixel = pick;
        s.trace_frame = s.shown->frame;
        s.trace_partial = true;
    }
}

void draw_trace(const Workbench::State& s) {
    const std::pair<int, int> pick{s.pick_x, s.pick_y};
    if (s.trace_point && s.trace_pixel == pick) draw_cone_samples(*s.trace_point);
    if (s.trace_lines.empty() || s.trace_pixel != pick) {
        ImGui::TextDisabled("the trace waits for the render job to end");
        return;
    }
    // Wrapped: a trace line is read whole (a scrollbar hid the values at their ends).
    ImGui::BeginChild("trace", ImVec2(0, 0), true);
    ImGui::PushTextWrapPos(0.0f);
    for (const std::string& l : s.trace_lines) ImGui::TextUnformatted(l.c_str());
    ImGui::PopTextWrapPos();
    ImGui::EndChild();
}

}  // namespace

void draw_inspector(Workbench& wb, Workbench::State& s) {
    if (!s.shown || s.pick_x < 0) {
        ImGui::TextWrapped("Click a pixel in the viewport to see every layer's value there.");
        return;
    }
    if (s.shown->environment_view)
        ImGui::Text("texel (%d, %d) of the environment bandwidth view", s.pick_x, s.pick_y);
    else
        ImGui::Text("pixel (%d, %d), frame %d", s.pick_x, s.pick_y, s.shown->frame);
    update_trace(s);
    // Tabs: the trace gets the whole panel, whatever the window's height (under the values it
    // was squeezed to 0 px at 1280 x 760 and 1600 x 900).
    if (ImGui::BeginTabBar("inspector")) {
        if (ImGui::BeginTabItem("values")) {
            draw_values(wb, s);
            ImGui::EndTabItem();
        }
        const std::string trace_tab =
            "trace (" +
            std::to_string(s.trace_pixel == std::pair{s.pick_x, s.pick_y} ? s.trace_lines.size()
                                                                          : size_t(0)) +
            " lines)###trace";
        if (ImGui::BeginTabItem(trace_tab.c_str(), nullptr,
                                s.select_trace_tab ? ImGuiTabItemFlags_SetSelected : 0)) {
            draw_trace(s);
            ImGui::EndTabItem();
        }
        s.select_trace_tab = false;
        ImGui::EndTabBar();
    }
}
}  // namespace freqlab::ui
