// The workbench's tools: comparison against the reference (split view, error layers,
// RMSE / relMSE / SSIM), exports (layer PNG at a chosen magnification, all layers as EXR,
// figures with insets, stats CSV) and sessions (save / load as JSON).
#include <imgui.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>

#include "base/error.h"
#include "base/file_io.h"
#include "image/image_io.h"
#include "scene/json_reader.h"
#include "scene/provenance.h"
#include "scene/scene_loader.h"
#include "workbench_state.h"

namespace freqlab::ui {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const fs::path kExportDir = fs::path("freqlab-out") / "exports";

}  // namespace

// Adds reference, error and relative_error layers to a frame's result and measures it.
void attach_reference(Workbench::State& s, int frame) {
    const std::shared_ptr<FrameResult> result = s.results.find(frame);
    auto ref = s.references.find(frame);
    if (!result || ref == s.references.end()) return;
    LayerSet& L = result->layers;
    const Layer* ref_color = ref->second.find("color");
    if (!ref_color || ref->second.width() != L.width() || ref->second.height() != L.height())
        return;
    const Layer& test = L.get("color");
    const bool ab = comparing_runs(s);
    const std::string name = ab ? kRunALayer : "reference";
    Layer& r = L.add(name, LayerKind::Color, 3,
                     ab ? "run A's colour of this frame (A/B)" : "reference render of this frame");
    r.data = ref_color->data;
    Layer& err =
        L.add("error", LayerKind::Signed, 1, "luminance(colour) - luminance(" + name + ")");
    Layer& rel = L.add("relative_error", LayerKind::Continuous, 1,
                       "mean over RGB of |colour - " + name + "| / (" + name + " + 0.01)");
    for (size_t p = 0; p < L.pixel_count(); ++p) {
        const vec3 t(test.data[3 * p], test.data[3 * p + 1], test.data[3 * p + 2]);
        const vec3 q(r.data[3 * p], r.data[3 * p + 1], r.data[3 * p + 2]);
        err.data[p] = luminance(t) - luminance(q);
        rel.data[p] = (std::fabs(t.x - q.x) / (q.x + 0.01f) + std::fabs(t.y - q.y) / (q.y + 0.01f) +
                       std::fabs(t.z - q.z) / (q.z + 0.01f)) /
                      3.0f;
    }
    LayerSet test_only(L.width(), L.height()), ref_only(L.width(), L.height());
    test_only.add("color", LayerKind::Color, 3).data = test.data;
    ref_only.add("color", LayerKind::Color, 3).data = ref_color->data;
    s.metrics[frame] = compare_layers(test_only, ref_only);
}

namespace {

// Letters, digits, '.', '_' and '-' only: "builtin:default" made names with ':' that some file
// systems and tools refuse.
std::string portable_name(std::string name) {
    for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-')
            c = '_';
    return name;
}

std::string file_stem(const Workbench::State& s) {
    // The environment view is no frame of the animation: its files say what they hold.
    if (s.shown && s.shown->environment_view)
        return portable_name(s.scene.name + "_environment_bandwidth_" + s.layer_name);
    char stem[128];
    std::snprintf(stem, sizeof stem, "%s_frame%04d_%s", s.scene.name.c_str(),
                  s.shown ? s.shown->frame : s.frame, s.layer_name.c_str());
    return portable_name(stem);
}

// What made the exported frame: scene, method, every setting, seed, media, version.
json export_provenance(const Workbench::State& s) {
    json p;
    if (s.bake) {
        p = bake_provenance(s);
    } else {
        RenderConfig config = s.config;  // settings_group() binds to a mutable config
        p = output_provenance(s.scene, render_method_info(config.method).name,
                              config.settings_group().to_json(), long(config.frame.seed));
    }
    if (s.shown && !s.bake) p["frame"] = s.shown->frame;
    return p;
}

// A stats object as flat columns: nested objects by dotted keys ("stages.gbuffer",
// "discards.temporal"); numbers and booleans only (lists and text stay in stats.json).
void flatten_stats(const json& stats, const std::string& prefix,
                   std::map<std::string, double>& out) {
    for (const auto& [key, value] : stats.items()) {
        if (value.is_object())
            flatten_stats(value, prefix + key + ".", out);
        else if (value.is_number() || value.is_boolean())
            out[prefix + key] =
                value.is_boolean() ? double(value.get<bool>()) : value.get<double>();
    }
}

}  // namespace

std::string Workbench::export_stem() const {
    return file_stem(*s_);
}

nlohmann::json Workbench::export_provenance() const {
    return ::freqlab::ui::export_provenance(*s_);
}

void Workbench::export_exr(const std::string& path) const {
    complete_shown(*s_);
    if (!s_->shown) throw Error(path, "export", "no result is shown yet");
    write_exr(path, s_->shown->layers, ::freqlab::ui::export_provenance(*s_));
}

void poll_reference(Workbench::State& s) {
    if (!s.reference_job || !s.reference_job->done()) return;
    const ProgressSnapshot snap = s.reference_job->snapshot();
    if (!snap.error.empty()) s.error = snap.error;
    s.reference_job.reset();
    std::lock_guard<std::mutex> lock(s.results_mutex);
    attach_reference(s, s.reference_job_frame);
    s.view_dirty = true;
}

void start_reference(Workbench::State& s) {
    if (s.reference_job || !s.shown || !s.device) return;
    if (s.shown->environment_view) {
        // It has no reference image: rendering "its frame" would render an animation frame
        // that does not exist.
        s.status = "the environment bandwidth view has no reference";
        return;
    }
    if (s.bake) {  // method B: the reference is a VPT bake seen from the same camera
        start_bake_reference(s);
        return;
    }
    const int frame = s.shown->frame;
    if (!s.reference_renderer) {
        RenderConfig rc = s.config;
        rc.method = RenderMethod::Reference;
        s.reference_renderer = std::make_unique<FrameRenderer>(s.scene, rc, *s.device);
    }
    s.reference_job_frame = frame;
    Workbench::State* sp = &s;
    s.reference_job = std::make_unique<Job>([sp, frame](Progress& progress) {
        progress.set_stage_count(2);
        FrameResult r = sp->reference_renderer->render(frame, progress);
        std::lock_guard<std::mutex> lock(sp->results_mutex);
        sp->references[frame] = std::move(r.layers);
    });
}

void Workbench::request_reference() {
    start_reference(*s_);
}
bool Workbench::reference_busy() const {
    return s_->reference_job != nullptr;
}
const ImageMetrics* Workbench::metrics() const {
    auto it = s_->metrics.find(s_->shown ? s_->shown->frame : -1);
    return it == s_->metrics.end() ? nullptr : &it->second;
}

void draw_compare_panel(Workbench::State& s) {
    if (!s.bake) draw_run_ab_panel(s);
    if (comparing_runs(s)) {  // the metrics are against run A
        const int frame = s.shown ? s.shown->frame : -1;
        auto m = s.metrics.find(frame);
        if (m != s.metrics.end()) {
            ImGui::Text("B against A: RMSE %.5f  relMSE %.5f  SSIM %.4f", m->second.rmse,
                        m->second.relmse, m->second.ssim);
            ImGui::Checkbox("split view (A right)", &s.split);
            if (s.split) ImGui::SliderFloat("split", &s.split_position, 0.0f, 1.0f);
        }
        return;
    }
    if (!ImGui::CollapsingHeader("Compare with reference",
                                 s.split ? ImGuiTreeNodeFlags_DefaultOpen : 0))
        return;
    const int frame = s.shown ? s.shown->frame : -1;
    bool have = false;
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        have = s.references.count(frame) > 0;
        // A reference that arrived before its frame's result: attach it now.
        if (have && s.shown && !s.shown->layers.find("reference")) attach_reference(s, frame);
    }
    if (s.reference_job) {
        const ProgressSnapshot p = s.reference_job->snapshot();
        ImGui::Text("reference of frame %d: %.0f%%", s.reference_job_frame, 100 * p.fraction);
        ImGui::SameLine();
        if (ImGui::SmallButton("cancel##ref")) s.reference_job->cancel();
    } else if (!have && frame >= 0 && ImGui::Button("Render reference of this frame")) {
        start_reference(s);
    }
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "reference.spp samples per pixel; cached on disk, so a second request "
            "of the same frame and settings is instant");
    auto m = s.metrics.find(frame);
    if (m != s.metrics.end()) {
        ImGui::Text("RMSE   %.5f", m->second.rmse);
        ImGui::Text("relMSE %.5f", m->second.relmse);
        ImGui::Text("SSIM   %.4f", m->second.ssim);
        if (!s.reference_note.empty()) ImGui::TextWrapped("%s", s.reference_note.c_str());
        ImGui::Checkbox("split view", &s.split);
        if (s.split) ImGui::SliderFloat("split", &s.split_position, 0.0f, 1.0f);
        ImGui::TextDisabled("layers: reference, error, relative_error");
    }
}

void render_reference_view(Workbench::State& s, const DisplayParams& params) {
    auto it = s.references.find(s.shown ? s.shown->frame : -1);
    if (it != s.references.end())
        s.reference_view.render(it->second, it->second.get("color"), params);
}

std::string stats_csv(const Workbench::State& s) {
    // Every per-frame stat a frame has (a column per dotted key; empty where a frame lacks
    // it), under the provenance as "# key: value" lines.
    std::map<int, std::map<std::string, double>> rows;
    std::set<std::string> columns;
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        for (const auto& [f, stats] : s.recorded) {
            flatten_stats(stats, "", rows[f]);
            for (const auto& [key, v] : rows[f]) columns.insert(key);
        }
    }
    columns.erase("frame");
    std::string csv = provenance_csv_header(export_provenance(s)) + "frame";
    for (const std::string& c : columns) csv += "," + c;
    csv += "\n";
    for (const auto& [f, row] : rows) {
        csv += std::to_string(f);
        for (const std::string& c : columns) {
            auto it = row.find(c);
            // The shortest text that reads back as the same double.
            csv += "," + (it != row.end() ? json(it->second).dump() : std::string());
        }
        csv += "\n";
    }
    return csv;
}

void draw_export_menu(Workbench::State& s) {
    if (!ImGui::BeginMenu("Export")) return;
    try {
        complete_shown(s);  // every layer, and the layer on screen when it was not read yet
        if (s.shown) {
            const LayerSet& L = s.shown->layers;
            const Layer& layer = L.get(s.layer_name);
            DisplayParams params;
            params.exposure_ev = s.config.frame.exposure;
            params.auto_range = !s.fixed_range;
            params.range = s.range;
            for (int scale : {1, 2, 4}) {
                char label[48];
                std::snprintf(label, sizeof label, "Layer as PNG (%dx%d)", L.width() * scale,
                              L.height() * scale);
                if (!ImGui::MenuItem(label)) continue;
                // Rendered offscreen at the requested size by the same shader as the screen.
                LayerView offscreen;
                offscreen.render(L, layer, params, L.width() * scale, L.height() * scale);
                const std::vector<unsigned char> rgba = offscreen.read_rgba();
                std::vector<unsigned char> rgb(rgba.size() / 4 * 3);
                for (size_t p = 0; p < rgba.size() / 4; ++p)
                    for (int c = 0; c < 3; ++c) rgb[3 * p + c] = rgba[4 * p + c];
                fs::create_directories(kExportDir);
                const fs::path out =
                    kExportDir / (file_stem(s) + "_x" + std::to_string(scale) + ".png");
                write_png(out, offscreen.width(), offscreen.height(), rgb, export_provenance(s));
                s.status = "wrote " + out.string();
            }
            if (ImGui::MenuItem("All layers as EXR")) {
                fs::create_directories(kExportDir);
                const fs::path out = kExportDir / (file_stem(s) + ".exr");
                write_exr(out, L, export_provenance(s));  // as Workbench::export_exr
                s.status = "wrote " + out.string();
            }
            if (ImGui::MenuItem("Add inset at the inspected pixel", nullptr, false,
                                s.pick_x >= 0 && s.insets.size() < 4)) {
                const int w = std::max(8, L.width() / 10), h = std::max(8, L.height() / 10);
                s.insets.push_back({std::clamp(s.pick_x - w / 2, 0, L.width() - w),
                                    std::clamp(s.pick_y - h / 2, 0, L.height() - h), w, h});
            }
            if (ImGui::MenuItem("Clear insets", nullptr, false, !s.insets.empty()))
                s.insets.clear();
            char fig_label[64];
            std::snprintf(fig_label, sizeof fig_label, "Figure (%zu inset%s)", s.insets.size(),
                          s.insets.size() == 1 ? "" : "s");
            if (ImGui::MenuItem(fig_label)) {
                FigureSpec spec;
                spec.layer = s.layer_name;
                spec.display = params;
                spec.insets = s.insets;
                spec.title = s.scene.name + ", frame " + std::to_string(s.shown->frame) + ", " +
                             s.layer_name;
                fs::create_directories(kExportDir);
                const fs::path out = kExportDir / (file_stem(s) + "_figure.png");
                write_figure(out, L, spec, export_provenance(s));
                s.status = "wrote " + out.string();
            }
        }
        if (ImGui::MenuItem("Stats as CSV")) {
            const fs::path out = kExportDir / (portable_name(s.scene.name) + "_stats.csv");
            fs::create_directories(kExportDir);
            write_text_atomically(out, stats_csv(s));
            s.status = "wrote " + out.string();
        }
    } catch (const Error& e) {
        s.error = e.what();
    }
    ImGui::EndMenu();
}

json session_to_json(const Workbench::State& s) {
    RenderConfig config = s.config;
    SessionFile f;
    f.scene = s.options.scene;
    f.method =
        s.bake ? std::string(to_string(bake_method(s))) : render_method_info(s.config.method).name;
    f.frame = s.frame;
    f.layer = s.layer_name;
    f.overlay_on_color = s.overlay_on_color;
    f.overlay_opacity = s.overlay_opacity;
    f.fixed_range = s.fixed_range;
    f.range_lo = s.range.lo, f.range_hi = s.range.hi;
    f.zoom = s.zoom;
    f.centre_x = s.centre.x, f.centre_y = s.centre.y;
    f.pick_x = s.pick_x, f.pick_y = s.pick_y;
    for (const FigureInset& in : s.insets) f.insets.push_back({in.x, in.y, in.width, in.height});
    f.settings = config.settings_group().to_json();
    if (s.bake) f.bake = bake_session_file(s);
    return session_json(f);
}

void draw_session_menu(Workbench& wb, Workbench::State& s) {
    if (!ImGui::BeginMenu("File")) return;
    char path[512];
    std::snprintf(path, sizeof path, "%s", s.scene_path.c_str());
    if (ImGui::InputText("scene file", path, sizeof path)) s.scene_path = path;
    if (ImGui::MenuItem("Open scene")) {
        wb.open_scene(s.scene_path);  // a bad file shows its error in the UI
        ImGui::EndMenu();
        return;
    }
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "a scene JSON (scenes/README.md) or builtin:default; the method and "
            "settings stay");
    ImGui::Separator();
    std::snprintf(path, sizeof path, "%s", s.session_path.c_str());
    if (ImGui::InputText("session file", path, sizeof path)) s.session_path = path;
    try {
        if (ImGui::MenuItem("Save session")) {
            wb.save_session(s.session_path);
            s.status = "saved " + s.session_path;
        }
        if (ImGui::MenuItem("Load session")) wb.load_session(s.session_path);
    } catch (const Error& e) {
        s.error = e.what();
    }
    ImGui::EndMenu();
}

void Workbench::save_session(const std::string& path) const {
    const fs::path p(path);
    if (p.has_parent_path()) fs::create_directories(p.parent_path());
    write_text_atomically(p, session_to_json(*s_).dump(2) + "\n");
}

void Workbench::load_session(const std::string& path) {
    // Everything is read and checked first (core): a bad file leaves the workbench as it was.
    const SessionFile f = read_session_file(read_text_file(path), path);
    WorkbenchOptions o = s_->options;
    o.scene = f.scene;
    o.method = f.method;
    o.frame = f.frame;
    o.layer = f.layer;
    o.settings.clear();
    std::optional<Scene> scene;  // loaded once: checked against here, then reset() takes it
    if (f.bake) {
        scene = load_scene(o.scene);
        check_session_media(f, *scene);
    }
    reset(o, scene ? &*scene : nullptr);
    State& s = *s_;
    s.config.settings_group().from_json(f.settings, path, "settings");
    if (!f.bake_method) s.config.method = parse_render_method(o.method);
    if (f.bake && s.bake) apply_bake_session(s, *f.bake);
    restart_renderer(s);
    s.overlay_on_color = f.overlay_on_color;
    s.overlay_opacity = f.overlay_opacity;
    s.fixed_range = f.fixed_range;
    s.range = {f.range_lo, f.range_hi};
    s.zoom = f.zoom;
    s.centre = ImVec2(f.centre_x, f.centre_y);
    s.pick_x = f.pick_x;
    s.pick_y = f.pick_y;
    s.insets.clear();
    for (const SessionFile::Inset& in : f.insets)
        s.insets.push_back({in.x, in.y, in.width, in.height});
    s.session_path = path;
    s.view_dirty = true;
}

void draw_view_menu(Workbench::State& s) {
    if (!ImGui::BeginMenu("View")) return;
    if (ImGui::MenuItem("Fit image", "F")) s.zoom = 1.0f, s.centre = ImVec2(0.5f, 0.5f);
    if (ImGui::MenuItem("Overlay over colour", nullptr, &s.overlay_on_color)) s.view_dirty = true;
    if (ImGui::MenuItem("Fixed range", nullptr, &s.fixed_range)) s.view_dirty = true;
    ImGui::MenuItem("Split view against the reference", nullptr, &s.split);
    if (!s.bake) {
        if (ImGui::MenuItem("Environment bandwidth", nullptr, &s.show_env_bandwidth))
            s.view_dirty = true;
    }
    ImGui::EndMenu();
}

void draw_help_menu() {
    if (!ImGui::BeginMenu("Help")) return;
    ImGui::TextUnformatted("Space        play / pause the timeline");
    ImGui::TextUnformatted("Left, Right  previous / next frame");
    ImGui::TextUnformatted("F            fit the image to the viewport");
    ImGui::TextUnformatted("D            method cache: its decisions over the colour, and back");
    ImGui::TextUnformatted("Wheel        zoom at the cursor");
    ImGui::TextUnformatted("Right-drag   pan");
    ImGui::TextUnformatted("Click        inspect a pixel (every layer, the pixel's trace)");
    ImGui::Separator();
    ImGui::TextUnformatted("Settings: hover a control for its tooltip; the same keys work as");
    ImGui::TextUnformatted("--set prefix.key=value on the command line (README.md).");
    ImGui::EndMenu();
}

}  // namespace freqlab::ui
