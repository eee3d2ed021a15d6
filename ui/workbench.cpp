#include "workbench.h"

#include "workbench_state.h"

#include <glad/gl.h>
#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>

#include "base/error.h"
#include "base/file_io.h"
#include "base/heap_reuse.h"
#include "base/job.h"
#include "gl_host.h"
#include "glfw_host.h"
#include "image/image_io.h"
#include "layer_view.h"
#include "osmesa_host.h"
#include "render/frame_checkpoint.h"
#include "render/frame_renderer.h"
#include "render/shading_memo_store.h"
#include "scene/provenance.h"
#include "scene/scene_loader.h"
#include "settings_panel.h"
#include "volume/bake_estimators.h"

namespace freqlab::ui {

namespace fs = std::filesystem;

void restart_renderer(Workbench::State& s) {
    s.job.reset();  // cancels and joins
    s.trace_lines.clear();
    s.trace_pixel = {-1, -1};
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        s.results.clear();
        s.recorded.clear();
        s.store_failure.clear();
        s.preview.reset();
        s.last_stage_times.clear();
    }
    s.shown = nullptr;
    s.shown_frame = -1;
    s.error.clear();
    s.run_dir.clear();
    if (s.bake) {  // method B: the bake job fills results[0]
        s.renderer.reset();
        start_bake(s);
        return;
    }
    if (s.device) {
        s.renderer = std::make_unique<FrameRenderer>(s.scene, s.config, *s.device);
        s.renderer->keep_cache_details(true);  // the inspector lists cache entries' tuples
    }
    s.state_next = 0;
    s.cancelled_frame = -1;
    // Every render method's frames go to the run store: a run opened again shows them at once.
    s.run_key = frame_checkpoint_key(
        output_provenance(s.scene, render_method_info(s.config.method).name,
                          s.config.settings_group().to_json(), long(s.config.frame.seed)));
    s.run_dir = run_store_directory(s.run_key);
    const nlohmann::json memo_key = ShadingMemo::key_of(s.run_key);
    if (!s.shading_memo || memo_key != s.shading_memo_key) {
        s.shading_memo = std::make_shared<ShadingMemo>(s.shading_memo_cap);
        s.shading_memo_key = memo_key;
    }
    // Points earlier runs of these settings wrote to the run store, this session or another.
    s.shading_memo->set_loader(memo_loader(runs_sharing_memo(s.run_dir, memo_key), memo_key));
    if (s.renderer) s.renderer->set_shading_memo(s.shading_memo);
    s.shading_memo_recalled_before = s.shading_memo->counts().recalled;
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        s.recorded = recorded_frame_stats(s.run_dir);
    }
    // References depend on the settings too: drop them with the frames.
    s.reference_job.reset();
    s.reference_renderer.reset();
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        s.references.clear();
    }
    s.metrics.clear();
}

std::shared_ptr<FrameResult> recorded_result(Workbench::State& s, int frame) {
    if (std::shared_ptr<FrameResult> r = s.results.find(frame)) return r;
    if (!s.recorded.count(frame) || s.run_dir.empty()) return nullptr;
    try {
        // Whole, a frame is 55 MB at 640 x 360: 23 ms from the page cache into reused memory,
        // 110-160 ms into fresh pages, more when the page cache lost it; the layers on screen
        // are ~5 % of it.
        std::vector<std::string> on_screen{s.layer_name};
        if (s.layer_name != "color") on_screen.push_back("color");
        auto r = std::make_shared<FrameResult>(
            read_recorded_frame(s.run_dir, s.run_key, frame, on_screen));
        touch_recorded_frame(s.run_dir, frame);  // the run store drops what was used least lately
        s.frame_reader->request(s.run_dir, s.run_key, frame);
        return r;
    } catch (const Error&) {
        // Trimmed from the run store, or damaged: the frame renders again.
        s.recorded.erase(frame);
        return nullptr;
    }
}

namespace {

// The frame shown went from the run store (trimmed, or damaged) after its layers on screen were
// read: nothing is shown until it renders again, and the status line says why.
void forget_shown(Workbench::State& s, const std::string& why) {
    s.shown = nullptr;
    s.shown_frame = -1;
    s.status = "frame read again from the run store failed (" + why + "): it renders again";
}

}  // namespace

void poll_frame_reader(Workbench::State& s) {
    for (BackgroundFrameReader::Read& read : s.frame_reader->take()) {
        if (read.dir != s.run_dir) continue;  // a run no longer shown
        const bool shown = s.shown && s.shown->partial && s.shown->frame == read.frame;
        if (!read.result) {  // went from the run store since its layers were read
            s.recorded.erase(read.frame);
            if (shown) forget_shown(s, read.error);
            continue;
        }
        s.results.keep(read.result);
        if (shown) {
            if (!s.shown->layers.find(s.layer_name)) s.view_dirty = true;  // e.g. attached ones
            s.shown = read.result;
        }
    }
}

void complete_shown(Workbench::State& s) {
    std::lock_guard<std::mutex> lock(s.results_mutex);
    auto partial = [&] { return s.shown && s.shown->partial; };
    while (partial() && s.frame_reader->wanted(s.run_dir, s.shown->frame)) {
        s.frame_reader->wait_until_idle_or_done();
        poll_frame_reader(s);
    }
    poll_frame_reader(s);
    if (!partial()) return;
    const int frame = s.shown->frame;
    try {
        auto r = std::make_shared<FrameResult>(read_recorded_frame(s.run_dir, s.run_key, frame));
        s.results.keep(r);
        s.shown = r;
    } catch (const Error& e) {
        s.recorded.erase(frame);
        forget_shown(s, e.what());
    }
}

void keep_result(Workbench::State& s, FrameResult result) {
    if (s.preview && s.preview->frame == result.frame) s.preview.reset();
    s.recorded[result.frame] = result.stats;
    s.results.keep(std::make_shared<FrameResult>(std::move(result)));
}

namespace {

const char* kStats[] = {"time_ms", "rays", "pixels_shaded"};

// D: method A's cache decisions (the previous frame's entries where they land, coloured by
// reuse or discard reason) over the colour, and back.
void toggle_decision_overlay(Workbench::State& s) {
    const char* kLayer = "cache_decisions";
    if (s.layer_name == kLayer) {
        s.layer_name = "color";
    } else if (!s.shown || s.shown->layers.find(kLayer)) {
        s.layer_name = kLayer;
        s.overlay_on_color = true;
    } else {
        s.status = "D: this method has no cache decisions (method cache has)";
        return;
    }
    s.view_dirty = true;
}

// Time left until the frame asked for is shown: the frame rendering now (its job's ETA, planned
// from the last frame's stages) and, for a stateful method on its way, the frames after it at
// the last frame's time. -1 while unknown.
double way_eta_seconds(const Workbench::State& s, const ProgressSnapshot& p) {
    if (p.eta_s < 0) return -1.0;
    const int after = s.config.needs_previous_frames() ? s.frame - s.job_frame : 0;
    if (after <= 0) return p.eta_s;
    std::lock_guard<std::mutex> lock(s.results_mutex);
    if (s.last_stage_times.empty()) return -1.0;
    double frame_s = 0.0;
    for (const StageTime& t : s.last_stage_times) frame_s += t.seconds;
    return p.eta_s + after * frame_s;
}

void start_job_if_needed(Workbench::State& s) {
    if (s.job && !s.job->done()) return;
    if (s.job) {
        const ProgressSnapshot snap = s.job->snapshot();
        if (!snap.error.empty()) s.error = snap.error;
        if (snap.cancelled) s.cancelled_frame = s.frame;
        s.job.reset();
    }
    if (s.cancelled_frame == s.frame) return;
    s.cancelled_frame = -1;
    if (!s.renderer || !s.error.empty()) return;  // do not retry a failing render every frame
    int frame = s.frame;
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        if (s.recorded.count(s.frame)) return;
    }
    // A method with state across frames renders every frame from where it starts up to the one
    // asked for, in order (each kept: scrubbing back is instant). It starts where its state
    // is, from the run's newest checkpoint at or before the frame, or cold at frame 0,
    // whichever renders fewer frames; every start gives the frames of the run from frame 0.
    const bool stateful = s.config.needs_previous_frames();
    int restore = -1;
    if (stateful) {
        const int next = s.state_next;
        frame = 0;
        int cost = s.frame + 1;
        if (next >= 0 && next <= s.frame && s.frame - next + 1 <= cost) {
            frame = next;
            cost = s.frame - next + 1;
        }
        const int c =
            s.config.cache.checkpoint_every > 0 ? latest_frame_checkpoint(s.run_dir, s.frame) : -1;
        if (c > 0 && s.frame - c + 1 < cost) frame = restore = c;
    }
    s.job_frame = frame;
    // The checkpoint the frames rendered since the last jump started from (-1: frame 0).
    if (restore > 0)
        s.job_resumed_from = restore;
    else if (frame == 0)
        s.job_resumed_from = -1;
    Workbench::State* sp = &s;
    const fs::path restore_file = restore > 0 ? frame_checkpoint_path(s.run_dir, restore) : "";
    const int every = stateful ? s.config.cache.checkpoint_every : 0;
    std::vector<StageTime> plan;
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        plan = s.last_stage_times;
    }
    s.job = std::make_unique<Job>([sp, frame, restore_file, every, plan, memo = s.shading_memo,
                                   memo_key = s.shading_memo_key](Progress& progress) {
        progress.set_stage_count(sp->config.method == RenderMethod::GBuffer ? 1 : 2);
        progress.set_expected_stages(plan);
        if (!restore_file.empty())
            sp->renderer->restore_state(read_frame_checkpoint(restore_file, sp->run_key).state,
                                        restore_file.string());
        const auto start = std::chrono::steady_clock::now();
        sp->renderer->set_preview_sink([sp, frame, start](LayerSet&& layers) {
            auto p = std::make_shared<FrameResult>();
            p->frame = frame;
            p->preview = true;
            p->layers = std::move(layers);
            p->stats = {{"frame", frame},
                        {"preview", true},
                        {"rays", 0},
                        {"time_ms", std::chrono::duration<double, std::milli>(
                                        std::chrono::steady_clock::now() - start)
                                        .count()}};
            std::lock_guard<std::mutex> lock(sp->results_mutex);
            sp->preview = std::move(p);
        });
        FrameResult r = sp->renderer->render(frame, progress);
        std::string failure;
        try {  // a full disk keeps the frame in memory only, and says so
            if (sp->renderer->has_state()) {
                sp->state_next = frame + 1;
                const fs::path file = frame_checkpoint_path(sp->run_dir, frame + 1);
                if (every > 0 && (frame + 1) % every == 0 && !fs::exists(file))
                    write_frame_checkpoint(file, sp->run_key, frame + 1,
                                           sp->renderer->save_state());
            }
            write_recorded_frame(sp->run_dir, sp->run_key, r);
            // The points this run shaded, for later runs of other cache.* settings (a frame
            // whose points were all recalled has them on disk already).
            const nlohmann::json* shading =
                r.stats.contains("shading_memo") ? &r.stats["shading_memo"] : nullptr;
            if (memo && shading && shading->value("shaded", 0L) > 0)
                if (const auto table = memo->frame(frame))
                    write_memo_frame(sp->run_dir, memo_key, frame, *table);
            trim_run_store(sp->run_dir);
        } catch (const std::exception& e) {
            failure = std::string("frame not kept in the run store: ") + e.what();
        }
        std::lock_guard<std::mutex> lock(sp->results_mutex);
        sp->store_failure = failure;
        sp->last_stage_times = progress.stage_times();
        keep_result(*sp, std::move(r));
    });
}

// Builds (or loads from the cache) the scene environment's bandwidth hierarchy, once.
void start_env_bandwidth_job(Workbench::State& s) {
    if (s.env_bandwidth_job || !s.scene.environment()) return;
    Workbench::State* sp = &s;
    s.env_bandwidth_job = std::make_unique<Job>([sp](Progress&) {
        const EnvironmentMap& env = *sp->scene.environment();
        const EnvBandwidthHierarchy h = EnvBandwidthHierarchy::cached(env);
        auto result = std::make_shared<FrameResult>();
        result->frame = -1;
        result->environment_view = true;
        result->layers = bandwidth_layers(env, h, 1024);
        result->stats = {{"frame", -1},
                         {"environment_view", true},
                         {"time_ms", 0.0},
                         {"rays", 0},
                         {"levels", h.levels().size()},
                         {"env_width", h.env_width()},
                         {"nyquist_cycles_per_rad", h.nyquist()}};
        std::lock_guard<std::mutex> lock(sp->results_mutex);
        sp->env_bandwidth = std::move(result);
    });
}

// What a settings change invalidates, acted on once for the panel and apply_setting(): a
// change to the G-buffer, the shading or method A's cache (a cache.* key) re-renders, anything
// else redraws. (apply_setting ignored cache.* changes while the panel restarted on them.)
void apply_render_invalidation(Workbench::State& s, uint32_t flags) {
    if (flags & (kInvalidatesGBuffer | kInvalidatesShading | kInvalidatesCache))
        restart_renderer(s);
    else if (flags != 0)
        s.view_dirty = true;
}

std::string current_method_name(const Workbench::State& s) {
    return s.bake ? std::string(to_string(bake_method(s)))
                  : render_method_info(s.config.method).name;
}

// Every method, render and bake, in one menu: render methods in id order, then the bakes.
std::vector<std::string> all_method_names() {
    std::vector<std::string> names = render_method_names();
    for (const auto& [method, name] : kBakeMethodNames) names.push_back(name);
    return names;
}

void draw_method_menu(Workbench::State& s) {
    const std::vector<std::string> names = all_method_names();
    const std::string current = current_method_name(s);
    if (ImGui::BeginCombo("method", current.c_str())) {
        for (const std::string& name : names) {
            const bool bake = is_bake_method(name);
            if (ImGui::Selectable((name + (bake ? " (bake)" : "")).c_str(), name == current) &&
                name != current)
                s.pending_method = name;
        }
        ImGui::EndCombo();
    }
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "Render methods (A): gbuffer: primary rays only; mis: MIS direct lighting at "
            "mis.spp; reference: the same at reference.spp (cached on disk); points, sparse, "
            "cache: method A's stages.\nBake methods (lightmaps and probes): surface: media "
            "ignored; extinction: transmittance on every segment; impulse: plus the tables' "
            "scattered light (method B); vpt: volumetric path tracing (the ground truth).\n"
            "Switching keeps the settings chosen so far.");
}

void draw_settings_panel_items(Workbench::State& s);

void draw_settings_panel(Workbench::State& s) {
    // Every label of the panel fits: the settings' and the bake panel's media sliders.
    float labels = std::max(settings_label_width(s.config.settings_group()),
                            ImGui::CalcTextSize("density scale").x);
    // Labels depend on the declaration only: no copy of the session's settings per frame.
    if (s.bake) labels = std::max(labels, settings_label_width(BakeSettings::schema()));
    push_label_room(labels);
    draw_settings_panel_items(s);
    ImGui::PopItemWidth();
}

void draw_settings_panel_items(Workbench::State& s) {
    ImGui::Text("scene: %s", s.scene.name.c_str());
    // What the loader changed in the input (dropped triangles, negative texels read as 0).
    ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.8f, 0.3f, 1.0f));
    for (const std::string& note : s.scene.load_notes) ImGui::TextWrapped("note: %s", note.c_str());
    if (s.bake) draw_bake_notes(s);
    ImGui::PopStyleColor();
    if (s.bake) {
        draw_method_menu(s);
        draw_bake_panel(s);
        draw_compare_panel(s);  // against a VPT bake (workbench_bake.cpp)
        follow_bake_media(s);
        draw_tables_panel(*s.tables);
        return;
    }
    draw_method_menu(s);
    if (ImGui::Checkbox("view environment bandwidth", &s.show_env_bandwidth)) s.view_dirty = true;
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "Method A's B_L hierarchy (cycles/rad) per window size over the lat-long "
            "map, in place of the frame; pick the level as a layer.");
    if (s.show_env_bandwidth) start_env_bandwidth_job(s);
    SettingsGroup group = s.config.settings_group();
    apply_render_invalidation(s, draw_settings(group, !s.options.show_tables));

    draw_compare_panel(s);
    draw_tables_panel(*s.tables);
    if (ImGui::CollapsingHeader("Help")) {
        ImGui::TextWrapped(
            "Space: play / pause    Left / Right: previous / next frame\n"
            "Click the image: inspect that pixel    Wheel: zoom at the cursor\n"
            "Right-drag: pan    F: fit the image    Export menu: PNG, EXR, CSV");
    }
}

// Under the frame slider: a tick per recorded frame (green), the frames the running job renders
// on its way to the one asked for (orange), the frame the viewport holds (white).
void draw_frame_marks(const Workbench::State& s) {
    const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
    const int n = std::max(1, s.scene.frame_count);
    const float w = (hi.x - lo.x) / float(n), y0 = hi.y - 3.0f, y1 = hi.y;
    ImDrawList* draw = ImGui::GetWindowDrawList();
    auto tick = [&](int f, ImU32 colour) {
        const float x = lo.x + w * float(f);
        draw->AddRectFilled(ImVec2(x, y0), ImVec2(x + std::max(1.0f, w - 1.0f), y1), colour);
    };
    if (s.job && !s.job->done() && s.job_frame >= 0)
        for (int f = s.job_frame; f <= std::min(s.frame, n - 1); ++f)
            tick(f, IM_COL32(255, 160, 40, 255));
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        for (const auto& [f, stats] : s.recorded)
            if (f >= 0 && f < n) tick(f, IM_COL32(80, 200, 90, 255));
    }
    if (s.shown && !s.shown->environment_view && s.shown->frame < n)
        tick(s.shown->frame, IM_COL32(255, 255, 255, 255));
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
    // The viewport may hold another frame than the one asked for while that one renders.
    const int held = s.shown && !s.shown->environment_view ? s.shown->frame : -1;
    const std::string format = held >= 0 && held != s.frame
                                   ? "frame %d (showing " + std::to_string(held) + ")"
                                   : std::string("frame %d");
    ImGui::SliderInt("##frame", &s.frame, 0, s.scene.frame_count - 1, format.c_str());
    draw_frame_marks(s);
    // Stats strip: the chosen statistic for every rendered frame (0 where not rendered yet).
    std::vector<float> values(size_t(s.scene.frame_count), 0.0f);
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        for (const auto& [f, stats] : s.recorded)
            if (f >= 0 && f < s.scene.frame_count)
                values[size_t(f)] = stats.value(kStats[s.stat_index], 0.0f);
    }
    const float peak = *std::max_element(values.begin(), values.end());
    char overlay[64];
    std::snprintf(overlay, sizeof overlay, "%s (max %.4g)", kStats[s.stat_index], peak);
    const std::vector<float> a_values = run_a_strip(s, kStats[s.stat_index]);
    const float a_peak =
        a_values.empty() ? 0.0f : *std::max_element(a_values.begin(), a_values.end());
    const float scale = std::max({peak, a_peak, 1e-30f});
    ImGui::PlotHistogram("##strip", values.data(), int(values.size()), 0,
                         (a_values.empty() ? overlay : std::string("B: ") + overlay).c_str(), 0.0f,
                         scale,
                         ImVec2(ImGui::GetContentRegionAvail().x, a_values.empty() ? 44 : 30));
    if (!a_values.empty()) {  // A/B: run A's statistic on the same scale, under B's
        char label[64];
        std::snprintf(label, sizeof label, "A: %s (max %.4g)", kStats[s.stat_index], a_peak);
        ImGui::PlotHistogram("##strip_a", a_values.data(), int(a_values.size()), 0, label, 0.0f,
                             scale, ImVec2(ImGui::GetContentRegionAvail().x, 30));
    }
    if (s.job && !s.job->done()) {
        const ProgressSnapshot p = s.job->snapshot();
        // Which frame the job really renders: on the way to the one asked for, a stateful
        // method renders those before it (from a checkpoint when the run store has one).
        std::string way;
        if (s.job_frame != s.frame && s.config.needs_previous_frames())
            way = " on the way to " + std::to_string(s.frame) +
                  (s.job_resumed_from > 0
                       ? " (from the checkpoint before " + std::to_string(s.job_resumed_from) + ")"
                       : "");
        // A cache.* change renders again what an earlier run shaded: say how much it recalls.
        std::string memo;
        if (s.shading_memo) {
            const long recalled =
                s.shading_memo->counts().recalled - s.shading_memo_recalled_before;
            if (recalled > 0)
                memo = "   (" + std::to_string(recalled) +
                       " radiance points recalled from earlier runs, not shaded again)";
        }
        const double eta = way_eta_seconds(s, p);
        ImGui::Text("rendering frame %d%s: %s %.0f%%  ETA %s%s", s.job_frame, way.c_str(),
                    p.stage.c_str(), 100 * p.fraction,
                    eta >= 0 ? (std::to_string(int(eta + 0.5)) + " s").c_str() : "--",
                    memo.c_str());
        ImGui::SameLine();
        if (ImGui::SmallButton("cancel")) s.job->cancel();
    } else if (s.cancelled_frame == s.frame && !s.bake) {
        ImGui::Text("frame %d: cancelled (not rendered)", s.frame);
        ImGui::SameLine();
        if (ImGui::SmallButton("render")) s.cancelled_frame = -1;
    } else if (s.shown && s.shown->environment_view) {
        ImGui::Text("environment bandwidth: %d levels   %s", s.shown->stats["levels"].get<int>(),
                    s.status.c_str());
    } else if (s.shown && s.shown->preview) {
        ImGui::Text("frame %d: first image (the initial grid alone), refining   %s", s.shown->frame,
                    s.status.c_str());
    } else if (s.shown && s.options.show_timings) {
        ImGui::Text("frame %d: %.1f ms, %ld rays   %s", s.shown->frame,
                    s.shown->stats["time_ms"].get<double>(), s.shown->stats["rays"].get<long>(),
                    s.status.c_str());
    } else if (s.shown) {
        ImGui::Text("frame %d: %ld rays   %s", s.shown->frame, s.shown->stats["rays"].get<long>(),
                    s.status.c_str());
    }
    std::lock_guard<std::mutex> lock(s.results_mutex);
    if (!s.store_failure.empty())  // the frames still show; they are not kept on disk
        ImGui::TextColored(ImVec4(1.0f, 0.8f, 0.3f, 1.0f), "%s", s.store_failure.c_str());
}

}  // namespace

Workbench::Workbench(const WorkbenchOptions& options) : s_(std::make_unique<State>()) {
    reset(options);
}

void Workbench::reset(const WorkbenchOptions& options) {
    reset(options, nullptr);
}

void Workbench::reset(const WorkbenchOptions& options, Scene* loaded) {
    State& s = *s_;
    s.job.reset();
    s.reference_job.reset();
    s.reference_renderer.reset();
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        s.results.clear();
        s.recorded.clear();
        s.references.clear();
    }
    s.metrics.clear();
    s.shown = nullptr;
    s.options = options;
    s.scene_path = options.scene;
    s.config = RenderConfig{};
    s.layer_name = options.layer.empty() ? "color" : options.layer;
    if (!options.show_timings) s.stat_index = 1;  // rays: the same on every host
    s.split = options.compare;
    s.tables->open = options.show_tables;
    s.tables->emitter = options.tables_emitter;
    s.select_trace_tab = options.inspect_trace;
    s.pick_x = options.inspect_x;
    s.pick_y = options.inspect_y;
    s.error.clear();
    try {
        s.results = DecodedFrames(decoded_frames_cap());
        s.shading_memo_cap = ShadingMemo::default_max_bytes();
        s.shading_memo.reset();
        s.scene = loaded ? std::move(*loaded) : load_scene(options.scene);
        s.bake.reset();
        if (!s.device) s.device = std::make_unique<EmbreeDevice>(0);
        if (is_bake_method(options.method)) {
            // frame.* settings (the preview's size) go to the render config, bake.* to the bake.
            std::vector<std::string> bake_sets, frame_sets;
            for (const std::string& a : options.settings)
                (a.rfind("bake.", 0) == 0 ? bake_sets : frame_sets).push_back(a);
            SettingsGroup group = s.config.settings_group();
            for (const std::string& a : frame_sets) group.apply_assignment(a);
            make_bake_session(s, options.method, bake_sets);
        } else {
            s.config.method = parse_render_method(options.method);
            SettingsGroup group = s.config.settings_group();
            for (const std::string& a : options.settings) group.apply_assignment(a);
        }
        s.frame = std::clamp(options.frame, 0, s.scene.frame_count - 1);
        s.playing = options.play;
        restart_renderer(s);
    } catch (const Error& e) {
        s.error = e.what();
        s.scene = Scene{};
        s.scene.frame_count = 1;
        s.renderer.reset();
    }
}

void Workbench::open_scene(const std::string& path) {
    State& s = *s_;
    std::optional<Scene> scene;
    try {
        scene = load_scene(path);
    } catch (const Error& e) {
        s.error = e.what();  // the workbench stays as it was
        return;
    }
    reopen(path, current_method_name(s), &*scene);
}

void Workbench::set_method(const std::string& name) {
    if (name == method()) return;
    if (s_->bake && is_bake_method(name)) return switch_bake_method(*s_, parse_bake_method(name));
    if (!is_bake_method(name)) parse_render_method(name);  // throws naming --method
    reopen(s_->options.scene, name, nullptr);
}

std::string Workbench::method() const {
    return current_method_name(*s_);
}

void Workbench::reopen(const std::string& scene_path, const std::string& method, Scene* loaded) {
    State& s = *s_;
    // What the panels hold now (they edit s.config and the bake session, not s.options).
    const nlohmann::json render_settings = s.config.settings_group().to_json();
    std::optional<BakeSettings> bake_settings;
    if (s.bake) bake_settings = bake_session_file(s).settings;
    WorkbenchOptions o = s.options;
    o.scene = scene_path;
    o.method = method;
    o.frame = is_bake_method(method) ? 0 : s.frame;  // a bake is one still frame
    o.settings.clear();
    o.layer.clear();  // the new method's layers differ: colour
    reset(o, loaded);
    if (!s.error.empty()) return;
    s.config.settings_group().from_json(render_settings, "workbench", "settings");
    if (!s.bake) s.config.method = parse_render_method(method);
    if (s.bake && bake_settings) {
        BakeSessionFile f = bake_session_file(s);
        f.settings = *bake_settings;
        apply_bake_session(s, f);
    }
    restart_renderer(s);
}

Workbench::~Workbench() {
    s_->bake.reset();
    s_->job.reset();
    s_->reference_job.reset();
}

void Workbench::draw(int fb_w, int fb_h) {
    State& s = *s_;
    // Panel sizes in units of the font (--ui-scale), resizable by their inner borders: the
    // settings panel's right edge, the inspector's left edge, the timeline's top edge. The
    // inspector starts wider on wide windows (traces are long lines).
    const float k = ImGui::GetFontSize() / 13.0f, menu_h = ImGui::GetFrameHeight();
    if (s.left_w <= 0.0f) {
        s.left_w = 320.0f * k;
        s.bottom_h = 130.0f * k;
        s.right_w = std::max(300.0f * k, 0.3f * (float(fb_w) - s.left_w));
    }
    // Room for the viewport whatever the window: each side panel at most a third of it.
    const float side_max = std::max(160.0f * k, float(fb_w) / 3.0f);
    s.left_w = std::clamp(s.left_w, 160.0f * k, side_max);
    s.right_w = std::clamp(s.right_w, 160.0f * k, side_max);
    s.bottom_h = std::clamp(s.bottom_h, 90.0f * k, std::max(90.0f * k, 0.5f * float(fb_h)));
    const float left_w = s.left_w, right_w = s.right_w, bottom_h = s.bottom_h;
    const ImGuiWindowFlags fixed = ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoCollapse;

    // Keyboard shortcuts (when no widget wants the keyboard).
    if (!ImGui::GetIO().WantCaptureKeyboard) {
        if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Space))) s.playing = !s.playing;
        if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_LeftArrow)))
            s.frame = std::max(0, s.frame - 1);
        if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_RightArrow)))
            s.frame = std::min(s.scene.frame_count - 1, s.frame + 1);
        if (ImGui::IsKeyPressed('F')) s.zoom = 1.0f, s.centre = ImVec2(0.5f, 0.5f);
        if (ImGui::IsKeyPressed('D')) toggle_decision_overlay(s);
    }

    if (ImGui::BeginMainMenuBar()) {
        draw_session_menu(*this, s);
        draw_export_menu(s);
        draw_view_menu(s);
        draw_help_menu();
        ImGui::EndMainMenuBar();
    }
    poll_reference(s);
    poll_run_a(s);

    if (s.playing && ++s.play_ticks >= 2) {  // advance when the next frame is ready
        s.play_ticks = 0;
        std::lock_guard<std::mutex> lock(s.results_mutex);
        if (s.recorded.count(s.frame)) s.frame = (s.frame + 1) % s.scene.frame_count;
    }
    start_job_if_needed(s);
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        poll_frame_reader(s);
        // The frame, else the latest recorded frame before it, until it is rendered.
        int want = -1;
        auto lb = s.recorded.upper_bound(s.frame);
        if (lb != s.recorded.begin()) want = std::prev(lb)->first;
        std::shared_ptr<const FrameResult> r;
        if (s.show_env_bandwidth)
            r = s.env_bandwidth;
        else if (want != s.frame && s.preview && s.preview->frame <= s.frame &&
                 s.preview->frame > want)
            r = s.preview;  // a first image, of the frame or one on the way, while it renders
        else if (s.results.contains(want) || !s.shown || s.shown->environment_view ||
                 s.shown->frame != want)
            r = want >= 0 ? recorded_result(s, want) : nullptr;
        else
            r = s.shown;  // still on screen although no longer decoded in memory
        if (r != s.shown || (r && r->frame != s.shown_frame)) {
            s.shown = r;
            s.shown_frame = r ? r->frame : -1;
            s.view_dirty = true;
        }
    }

    ImGui::SetNextWindowPos(ImVec2(0, menu_h));
    ImGui::SetNextWindowSize(ImVec2(left_w, fb_h - bottom_h - menu_h));
    ImGui::Begin("Settings", nullptr, fixed);
    s.left_w = ImGui::GetWindowWidth();  // a drag of its right edge
    draw_settings_panel(s);
    ImGui::End();

    ImGui::SetNextWindowPos(ImVec2(left_w, menu_h));
    ImGui::SetNextWindowSize(ImVec2(fb_w - left_w - right_w, fb_h - bottom_h - menu_h));
    ImGui::Begin("Viewport", nullptr, fixed | ImGuiWindowFlags_NoResize);
    draw_viewport(s);
    if (s.bake) draw_probe_lobes(s);
    // Method A's cache: what each frame reused, shaded anew and discarded, under the image.
    if (s.config.method == RenderMethod::Cache && !s.show_env_bandwidth) draw_cache_panel(s);
    ImGui::End();

    ImGui::SetNextWindowPos(ImVec2(fb_w - right_w, menu_h));
    ImGui::SetNextWindowSize(ImVec2(right_w, fb_h - bottom_h - menu_h));
    ImGui::Begin("Inspector", nullptr, fixed);
    s.right_w = ImGui::GetWindowWidth();  // a drag of its left edge
    draw_inspector(*this, s);
    ImGui::End();

    ImGui::SetNextWindowPos(ImVec2(0, fb_h - bottom_h));
    ImGui::SetNextWindowSize(ImVec2(float(fb_w), bottom_h));
    ImGui::Begin("Timeline", nullptr, fixed | ImGuiWindowFlags_NoTitleBar);
    s.bottom_h = ImGui::GetWindowHeight();  // a drag of its top edge
    draw_timeline(s);
    ImGui::End();

    if (!s.pending_method.empty()) {
        const std::string name = std::move(s.pending_method);
        s.pending_method.clear();
        set_method(name);
    }
}

void Workbench::set_frame(int frame) {
    s_->frame = std::clamp(frame, 0, s_->scene.frame_count - 1);
}
std::vector<std::pair<float, float>> Workbench::probe_marks() const {
    std::vector<std::pair<float, float>> out;
    for (const ImVec2& p : s_->probe_marks) out.emplace_back(p.x, p.y);
    return out;
}

void Workbench::set_view(float zoom, float cx, float cy) {
    s_->zoom = std::clamp(zoom, 1.0f, 64.0f);
    s_->centre = ImVec2(cx, cy);
}

const std::string& Workbench::reference_note() const {
    return s_->reference_note;
}

const std::vector<std::string>& Workbench::trace_lines() const {
    return s_->trace_lines;
}
int Workbench::frame() const {
    return s_->frame;
}
bool Workbench::busy() const {
    auto running = [](const std::unique_ptr<Job>& j) { return j && !j->done(); };
    const State& s = *s_;
    return s.playing || running(s.job) || running(s.reference_job) ||
           running(s.env_bandwidth_job) || bake_busy(s) || (s.view_dirty && s.shown) ||
           (s.shown && s.shown->partial) || !s.frame_reader->idle() ||
           (s.error.empty() && s.cancelled_frame != s.frame && !frame_shown());
}

void Workbench::cancel_render() {
    if (s_->job) s_->job->cancel();
}

std::vector<int> Workbench::recorded_frames() const {
    std::lock_guard<std::mutex> lock(s_->results_mutex);
    std::vector<int> frames;
    for (const auto& [f, stats] : s_->recorded) frames.push_back(f);
    return frames;
}
void Workbench::keep_run_as_a() {
    pin_run_a(*s_);
}
void Workbench::forget_run_a() {
    unpin_run_a(*s_);
}
bool Workbench::comparing_runs() const {
    return ::freqlab::ui::comparing_runs(*s_);
}
int Workbench::frame_count() const {
    return s_->scene.frame_count;
}
std::string Workbench::run_directory() const {
    return s_->run_dir.string();
}
Workbench::DecodedMemory Workbench::decoded_memory() const {
    std::lock_guard<std::mutex> lock(s_->results_mutex);
    return {s_->results.frames(), s_->results.bytes(), s_->results.cap()};
}
int Workbench::resumed_from() const {
    return s_->job_resumed_from;
}

bool Workbench::set_layer(const std::string& name) {
    complete_shown(*s_);
    if (s_->shown && !s_->shown->layers.find(name)) return false;
    s_->layer_name = name;
    s_->view_dirty = true;
    return true;
}

void Workbench::apply_setting(const std::string& assignment) {
    if (s_->bake && assignment.rfind("bake.", 0) == 0) return apply_bake_setting(*s_, assignment);
    SettingsGroup group = s_->config.settings_group();
    apply_render_invalidation(
        *s_, group.apply_assignment(assignment, "workbench") | kInvalidatesDisplay);
}

bool Workbench::first_image_shown() const {
    return s_->shown && s_->shown->preview && s_->shown->frame == s_->frame && !s_->view_dirty;
}

bool Workbench::frame_shown() const {
    // A bake is shown once its last pass is (earlier passes are progressive previews).
    if (bake_busy(*s_)) return !s_->error.empty();
    const bool env_view = s_->show_env_bandwidth && s_->shown && s_->shown->environment_view;
    return (s_->shown && !s_->shown->preview && (s_->shown->frame == s_->frame || env_view) &&
            !s_->view_dirty) ||
           !s_->error.empty();
}

bool Workbench::frame_complete() const {
    return frame_shown() && s_->shown && !s_->shown->partial;
}

void Workbench::wait_for_render() {
    if (s_->job) s_->job->wait();
    wait_for_bake(*s_);
}

const LayerSet* Workbench::layers() const {
    complete_shown(*s_);
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
    complete_shown(*s_);
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
const std::string& Workbench::status() const {
    return s_->status;
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
        for (int i = 0; i < 100000 && !wb.tables_ready() && wb.error().empty(); ++i) {
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
        host.set_idle(!wb.busy());
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

int run_on_host(GlHost& host, const WorkbenchOptions& options, bool interactive) {
    apply_ui_scale(options.ui_scale > 0.0f ? options.ui_scale : host.content_scale());
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

ImGuiSession::ImGuiSession() {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;
    ImGui::StyleColorsDark();
}
ImGuiSession::~ImGuiSession() {
    ImGui::DestroyContext();
}

void apply_ui_scale(float scale) {
    if (!(scale > 0.0f) || scale == 1.0f) return;
    ImGui::GetStyle().ScaleAllSizes(scale);
    ImGuiIO& io = ImGui::GetIO();
    const char* font = "/usr/share/fonts/truetype/dejavu/DejaVuSansMono.ttf";  // fonts-dejavu-core
    if (fs::exists(font)) {
        io.Fonts->AddFontFromFileTTF(font, 13.0f * scale);
    } else {
        ImFontConfig config;
        config.SizePixels = 13.0f * scale;
        io.Fonts->AddFontDefault(&config);
    }
}

int run_workbench(const WorkbenchOptions& options) {
    keep_freed_memory_for_reuse();
    ImGuiSession imgui;
    GlfwHost host(options.width, options.height, "freqlab — " + options.scene);
    return run_on_host(host, options, true);
}

int run_headless(const WorkbenchOptions& options) {
    if (options.screenshot.empty())
        throw Error("--headless", "--screenshot",
                    "the headless workbench needs --screenshot OUT.png");
    keep_freed_memory_for_reuse();
    ImGuiSession imgui;
    OsMesaHost host(options.width, options.height);
    return run_on_host(host, options, false);
}

}  // namespace freqlab::ui
