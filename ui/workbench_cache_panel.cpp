// The workbench's cache panel (method A's cache, seed Fig. 12(b) and 17): per rendered frame,
// the pixels reused and newly shaded and the cache entries discarded by each reason, as lines
// in the decision palette; the frame being shown is marked.
#include <imgui.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "cache/cache_decision.h"
#include "workbench_state.h"

namespace freqlab::ui {

namespace {

ImU32 colour_u32(const vec3& c) {
    return IM_COL32(int(255 * c.x), int(255 * c.y), int(255 * c.z), 255);
}

struct Series {
    std::string label;
    vec3 colour;
    std::vector<float> values;
};

}  // namespace

void draw_cache_panel(Workbench::State& s) {
    if (!ImGui::CollapsingHeader("Cache per frame", ImGuiTreeNodeFlags_DefaultOpen)) return;
    const int frames = s.scene.frame_count;
    std::vector<Series> series = {{"reused px", vec3(0.85f), {}},
                                  {"new px", vec3(0.3f, 0.6f, 1.0f), {}}};
    for (int k = int(CacheDecision::DiscardZbuffer); k < kCacheDecisionCount; ++k)
        series.push_back({std::string(to_string(CacheDecision(k))).substr(8),
                          decision_colour(CacheDecision(k)),
                          {}});
    series.push_back({"merged", decision_colour(CacheDecision::Merged), {}});
    for (Series& x : series) x.values.assign(size_t(frames), 0.0f);
    std::vector<char> recorded(size_t(frames), 0);  // lines join recorded frames only
    // The entries of the frame asked for, else of the latest recorded before it (while it
    // renders; what a first image on screen stands on).
    int counted = -1;
    long points = 0, bytes = 0;
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        for (const auto& [f, stats] : s.recorded) {
            if (f < 0 || f >= frames || !stats.contains("discards")) continue;
            series[0].values[size_t(f)] = stats.value("pixels_reused", 0.0f);
            series[1].values[size_t(f)] = stats.value("pixels_new", 0.0f);
            size_t k = 2;
            for (int d = int(CacheDecision::DiscardZbuffer); d < kCacheDecisionCount; ++d, ++k)
                series[k].values[size_t(f)] = stats["discards"].value(
                    std::string(to_string(CacheDecision(d))).substr(8), 0.0f);
            series[k].values[size_t(f)] = stats.value("merged", 0.0f);
            recorded[size_t(f)] = 1;
            if (f <= s.frame) {
                counted = f;
                points = stats.value("cache_points", 0L);
                bytes = stats.value("cache_bytes", 0L);
            }
        }
    }
    static bool log_scale = true;
    ImGui::Checkbox("log scale", &log_scale);
    ImGui::SameLine();
    if (counted >= 0)
        ImGui::Text(
            "frame %d: %ld entries, %.1f MB (%.0f B/entry)%s", counted, points, bytes / 1e6,
            points ? double(bytes) / double(points) : 0.0,
            counted == s.frame ? "" : ("; " + std::to_string(s.frame) + " not yet").c_str());
    else
        ImGui::TextDisabled("frame %d: not rendered yet", s.frame);
    const ImVec2 origin = ImGui::GetCursorScreenPos();
    const float width = ImGui::GetContentRegionAvail().x,
                height = 120.0f * ImGui::GetFontSize() / 13.0f;
    // The x axis spans the frames rendered so far (at least 10).
    int last = 9;
    for (const Series& x : series)
        for (int f = 0; f < frames; ++f)
            if (x.values[size_t(f)] > 0) last = std::max(last, f);
    const int span = std::min(last + 1, frames);
    ImDrawList* dl = ImGui::GetWindowDrawList();
    dl->AddRectFilled(origin, ImVec2(origin.x + width, origin.y + height),
                      IM_COL32(25, 25, 28, 255));
    float peak = 1.0f;
    for (const Series& x : series)
        for (float v : x.values) peak = std::max(peak, v);
    auto map_y = [&](float v) {
        const float t = log_scale ? std::log10(1.0f + v) / std::log10(1.0f + peak) : v / peak;
        return origin.y + height - 4.0f - t * (height - 8.0f);
    };
    auto map_x = [&](int f) {
        return origin.x + 4.0f + (width - 8.0f) * float(f) / std::max(span - 1, 1);
    };
    for (const Series& x : series)
        for (int f = 1; f < span; ++f)
            if (recorded[size_t(f - 1)] && recorded[size_t(f)] &&
                (x.values[size_t(f - 1)] > 0 || x.values[size_t(f)] > 0))
                dl->AddLine(ImVec2(map_x(f - 1), map_y(x.values[size_t(f - 1)])),
                            ImVec2(map_x(f), map_y(x.values[size_t(f)])), colour_u32(x.colour),
                            1.5f);
    dl->AddLine(ImVec2(map_x(s.frame), origin.y), ImVec2(map_x(s.frame), origin.y + height),
                IM_COL32(255, 255, 255, 90));
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g", peak);
    dl->AddText(ImVec2(origin.x + 6, origin.y + 2), IM_COL32(200, 200, 200, 255), buf);
    ImGui::Dummy(ImVec2(width, height));
    if (ImGui::IsItemHovered()) {
        const int f = std::clamp(int(std::lround((ImGui::GetMousePos().x - origin.x - 4.0f) /
                                                 (width - 8.0f) * (span - 1))),
                                 0, span - 1);
        ImGui::BeginTooltip();
        ImGui::Text("frame %d", f);
        for (const Series& x : series)
            ImGui::Text("%-12s %.0f", x.label.c_str(), x.values[size_t(f)]);
        ImGui::EndTooltip();
    }
    for (size_t k = 0; k < series.size(); ++k) {  // the legend
        if (k % 3) ImGui::SameLine();
        ImGui::ColorButton(("##c" + series[k].label).c_str(),
                           ImVec4(series[k].colour.x, series[k].colour.y, series[k].colour.z, 1.0f),
                           ImGuiColorEditFlags_NoTooltip, ImVec2(12, 12));
        ImGui::SameLine();
        ImGui::TextUnformatted(series[k].label.c_str());
    }
}

}  // namespace freqlab::ui
