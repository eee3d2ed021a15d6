// A/B of two recorded runs (issue "The timeline as a recorded run": two runs with different
// settings kept and compared side by side). "Keep this run as A" remembers the run shown (its key
// and folder in the run store); after a settings change the shown run is B, and each frame B
// shows is compared with A's recording of the same frame, read from the run store: the split
// view (A right of the split), the layers run_a / error / relative_error and the metrics of the
// reference comparison, and A's per-frame statistic drawn under B's in the timeline's strip.
// A frame A did not record is said, not rendered: A stays what was recorded.
#include <imgui.h>

#include <cstdio>
#include <mutex>

#include "base/error.h"
#include "render/frame_store.h"
#include "workbench_state.h"

namespace freqlab::ui {

namespace {

// Numbers as %.6g: settings are floats, and their doubles print as 9.999999747378752e-05.
std::string short_text(const nlohmann::json& v) {
    if (!v.is_number_float()) return v.dump();
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", v.get<double>());
    return text;
}

// "key: A -> B" for every setting that differs between two runs' keys (their settings JSON).
std::string settings_difference(const nlohmann::json& a, const nlohmann::json& b,
                                const std::string& prefix = "") {
    std::string out;
    if (a.is_object() && b.is_object()) {
        for (const auto& [key, value] : a.items()) {
            const std::string name = prefix.empty() ? key : prefix + "." + key;
            if (!b.contains(key))
                out += (out.empty() ? "" : ", ") + name + ": " + value.dump() + " -> (none)";
            else if (const std::string d = settings_difference(value, b[key], name); !d.empty())
                out += (out.empty() ? "" : ", ") + d;
        }
        return out;
    }
    return a == b ? "" : prefix + ": " + short_text(a) + " -> " + short_text(b);
}

}  // namespace

bool comparing_runs(const Workbench::State& s) {
    return s.run_a && s.run_a->dir != s.run_dir;
}

void pin_run_a(Workbench::State& s) {
    if (s.bake || s.run_dir.empty()) {
        s.status = "A/B compares recorded render runs (not bakes)";
        return;
    }
    RunA a;
    a.key = s.run_key;
    a.dir = s.run_dir;
    a.method = render_method_info(s.config.method).name;
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        a.stats = s.recorded;
        s.references.clear();
    }
    s.metrics.clear();
    s.run_a = std::move(a);
    s.split = true;
    s.status = "run A kept: change a setting, and each frame is compared with A's";
}

void unpin_run_a(Workbench::State& s) {
    s.run_a.reset();
    std::lock_guard<std::mutex> lock(s.results_mutex);
    s.references.clear();
    s.metrics.clear();
}

void poll_run_a(Workbench::State& s) {
    if (!comparing_runs(s) || !s.shown || s.shown->environment_view) return;
    const int frame = s.shown->frame;
    std::lock_guard<std::mutex> lock(s.results_mutex);
    if (s.references.count(frame)) {
        if (!s.shown->layers.find(kRunALayer)) attach_reference(s, frame);
        return;
    }
    // A's own recording may have grown since it was kept (it rendered on in the background).
    if (!s.run_a->stats.count(frame) && s.run_a->rescanned_for != frame) {
        s.run_a->stats = recorded_frame_stats(s.run_a->dir);
        s.run_a->rescanned_for = frame;
    }
    if (!s.run_a->stats.count(frame)) return;
    try {
        s.references[frame] = read_recorded_frame(s.run_a->dir, s.run_a->key, frame).layers;
    } catch (const Error& e) {
        s.run_a->stats.erase(frame);
        s.status = std::string("run A's frame unreadable: ") + e.what();
        return;
    }
    attach_reference(s, frame);
    s.view_dirty = true;
}

void draw_run_ab_panel(Workbench::State& s) {
    if (!ImGui::CollapsingHeader("A/B runs", s.run_a ? ImGuiTreeNodeFlags_DefaultOpen : 0)) return;
    if (!s.run_a) {
        if (ImGui::Button("Keep this run as A")) pin_run_a(s);
        if (ImGui::IsItemHovered())
            ImGui::SetTooltip(
                "Remembers this run (its frames stay in the run store). Change a setting: the "
                "new run is B, and every frame is compared with A's recording of it.");
        return;
    }
    const std::string diff = settings_difference(s.run_a->key.value("settings", nlohmann::json()),
                                                 s.run_key.value("settings", nlohmann::json()));
    if (!comparing_runs(s)) {
        ImGui::TextWrapped("A is the run shown: change a setting to make B.");
    } else {
        ImGui::TextWrapped("A -> B: %s", diff.empty() ? "(method)" : diff.c_str());
        const int frame = s.shown ? s.shown->frame : -1;
        if (frame >= 0 && !s.run_a->stats.count(frame))
            ImGui::TextWrapped("A has no frame %d (A recorded %zu frames)", frame,
                               s.run_a->stats.size());
    }
    if (ImGui::Button("Forget A")) unpin_run_a(s);
}

std::vector<float> run_a_strip(const Workbench::State& s, const char* stat) {
    std::vector<float> values(size_t(std::max(0, s.scene.frame_count)), 0.0f);
    if (!comparing_runs(s)) return {};
    for (const auto& [f, stats] : s.run_a->stats)
        if (f >= 0 && f < s.scene.frame_count) values[size_t(f)] = stats.value(stat, 0.0f);
    return values;
}

}  // namespace freqlab::ui
