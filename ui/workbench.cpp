#include "workbench.h"

#include <glad/gl.h>
#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>

#include "base/error.h"
#include "base/job.h"
#include "glfw_host.h"
#include "image/image_io.h"
#include "layer_texture.h"
#include "render/frame_renderer.h"
#include "scene/scene_loader.h"
#include "settings_panel.h"

namespace freqlab::ui {

namespace {

// Everything the workbench knows; the render job only touches `renderer` and `results`.
struct WorkbenchState {
    std::string scene_path;
    Scene scene;
    RenderConfig config;
    EmbreeDevice device;
    std::unique_ptr<FrameRenderer> renderer;
    std::unique_ptr<Job> job;
    int job_frame = -1;

    std::mutex results_mutex;
    std::map<int, FrameResult> results;  // rendered frames: scrubbing back is instant

    int frame = 0;
    bool playing = false;
    double play_clock = 0.0;
    int layer_index = 0;
    bool texture_dirty = true;
    int shown_frame = -1;
    int inspect_x = -1, inspect_y = -1;
    std::string error;
};

void restart_renderer(WorkbenchState& s) {
    s.job.reset();  // cancels and joins
    std::lock_guard<std::mutex> lock(s.results_mutex);
    s.results.clear();
    s.renderer = std::make_unique<FrameRenderer>(s.scene, s.config, s.device);
    s.texture_dirty = true;
}

void start_job_if_needed(WorkbenchState& s) {
    if (s.job && !s.job->done()) return;
    if (s.job) {
        const ProgressSnapshot snap = s.job->snapshot();
        if (!snap.error.empty()) s.error = snap.error;
        s.job.reset();
    }
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        if (s.results.count(s.frame)) return;
    }
    if (!s.error.empty()) return;  // do not retry a failing render every frame
    const int frame = s.frame;
    s.job_frame = frame;
    s.job = std::make_unique<Job>([&s, frame](Progress& progress) {
        progress.set_stage_count(1);
        FrameResult r = s.renderer->render(frame, progress);
        std::lock_guard<std::mutex> lock(s.results_mutex);
        s.results[frame] = std::move(r);
    });
}

void draw_inspector(WorkbenchState& s, const FrameResult* result) {
    ImGui::TextUnformatted("Pixel inspector");
    ImGui::Separator();
    if (!result || s.inspect_x < 0) {
        ImGui::TextWrapped("Click a pixel in the viewport to see every layer's value there.");
        return;
    }
    const LayerSet& L = result->layers;
    ImGui::Text("pixel (%d, %d), frame %d", s.inspect_x, s.inspect_y, result->frame);
    for (const Layer& l : L.layers()) {
        std::string values;
        char buf[32];
        for (int c = 0; c < l.channels; ++c) {
            std::snprintf(buf, sizeof buf, "%s%.4g", c ? ", " : "",
                          l.at(L.width(), s.inspect_x, s.inspect_y, c));
            values += buf;
        }
        if (l.kind == LayerKind::Categorical) {
            const int v = int(l.at(L.width(), s.inspect_x, s.inspect_y));
            if (v >= 0 && v < int(l.legend.size())) values += "  " + l.legend[v];
        }
        ImGui::Text("%-9s %s", l.name.c_str(), values.c_str());
        if (ImGui::IsItemHovered() && !l.description.empty())
            ImGui::SetTooltip("%s", l.description.c_str());
    }
}

void draw_timeline(WorkbenchState& s) {
    if (ImGui::Button(s.playing ? "Pause" : "Play")) s.playing = !s.playing;
    ImGui::SameLine();
    if (ImGui::Button("<")) s.frame = std::max(0, s.frame - 1);
    ImGui::SameLine();
    if (ImGui::Button(">")) s.frame = std::min(s.scene.frame_count - 1, s.frame + 1);
    ImGui::SameLine();
    ImGui::SetNextItemWidth(-1);
    ImGui::SliderInt("##frame", &s.frame, 0, s.scene.frame_count - 1, "frame %d");
    // Stats strip: frame time of every rendered frame (0 where not rendered yet).
    std::vector<float> times(size_t(s.scene.frame_count), 0.0f);
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        for (const auto& [f, r] : s.results) times[size_t(f)] = r.stats["time_ms"].get<float>();
    }
    const float peak = *std::max_element(times.begin(), times.end());
    ImGui::PlotHistogram("##times", times.data(), int(times.size()), 0, "frame time (ms)", 0.0f,
                         peak > 0 ? peak : 1.0f, ImVec2(ImGui::GetContentRegionAvail().x, 48));
}

// Reads the window's back buffer (after drawing, before present) into a PNG.
void write_window_png(const std::string& path, int w, int h) {
    std::vector<unsigned char> rgba(size_t(w) * h * 4), rgb(size_t(w) * h * 3);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadBuffer(GL_BACK);
    glFinish();
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    for (int y = 0; y < h; ++y)  // GL rows start at the bottom
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                rgb[(size_t(h - 1 - y) * w + x) * 3 + c] = rgba[(size_t(y) * w + x) * 4 + c];
    write_png(path, w, h, rgb);
}

int run_workbench_in(GlHost& host, const WorkbenchOptions& options) {
    const std::string& scene_path = options.scene;
    const int frame = options.frame;
    int exit_code = 0;
    {
        WorkbenchState s;
        s.scene_path = scene_path;
        try {
            s.scene = load_scene(scene_path);
            s.frame = std::clamp(frame, 0, s.scene.frame_count - 1);
            restart_renderer(s);
        } catch (const Error& e) {
            s.error = e.what();
            s.scene.frame_count = 1;
        }
        LayerTexture texture;
        bool layer_chosen = options.layer.empty();
        int screenshot_countdown = -1;
        auto last = std::chrono::steady_clock::now();

        while (!host.should_close()) {
            host.begin_frame();
            ImGui_ImplOpenGL3_NewFrame();
            ImGui::NewFrame();
            const auto now = std::chrono::steady_clock::now();
            const double dt = std::chrono::duration<double>(now - last).count();
            last = now;

            int fb_w, fb_h;
            host.framebuffer_size(&fb_w, &fb_h);
            const float left_w = 300, right_w = 300, bottom_h = 120;
            const ImGuiWindowFlags fixed =
                ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse;

            // Left: settings generated from the declarations.
            ImGui::SetNextWindowPos(ImVec2(0, 0));
            ImGui::SetNextWindowSize(ImVec2(left_w, fb_h - bottom_h));
            ImGui::Begin("Settings", nullptr, fixed);
            ImGui::Text("scene: %s", s.scene.name.c_str());
            ImGui::Text("method: gbuffer");
            uint32_t changed = 0;
            if (s.renderer) {
                SettingsGroup group = s.config.settings_group();
                changed = draw_settings(group);
            }
            ImGui::End();
            if (changed & (kInvalidatesGBuffer | kInvalidatesShading)) {
                s.error.clear();
                restart_renderer(s);
            } else if (changed & kInvalidatesDisplay) {
                s.texture_dirty = true;
            }

            if (s.playing) {
                s.play_clock += dt;
                std::lock_guard<std::mutex> lock(s.results_mutex);
                if (s.play_clock >= 1.0 / s.scene.fps && s.results.count(s.frame)) {
                    s.play_clock = 0.0;
                    s.frame = (s.frame + 1) % s.scene.frame_count;
                }
            }
            if (s.renderer) start_job_if_needed(s);

            const FrameResult* result = nullptr;
            {
                std::lock_guard<std::mutex> lock(s.results_mutex);
                auto it = s.results.find(s.frame);
                if (it != s.results.end()) result = &it->second;
                // Keep showing the latest rendered frame at or before the current one.
                if (!result && !s.results.empty()) {
                    auto lb = s.results.upper_bound(s.frame);
                    if (lb != s.results.begin()) result = &std::prev(lb)->second;
                }
            }
            if (result && !layer_chosen) {
                layer_chosen = true;
                int i = 0;
                for (const Layer& l : result->layers.layers()) {
                    if (l.name == options.layer) s.layer_index = i, s.texture_dirty = true;
                    ++i;
                }
            }
            if (result && (s.texture_dirty || s.shown_frame != result->frame)) {
                const auto& layers = result->layers.layers();
                s.layer_index = std::clamp(s.layer_index, 0, int(layers.size()) - 1);
                DisplayParams params;
                params.exposure_ev = s.config.frame.exposure;
                texture.upload(result->layers, layers[size_t(s.layer_index)], params);
                s.texture_dirty = false;
                s.shown_frame = result->frame;
            }

            // Centre: viewport.
            ImGui::SetNextWindowPos(ImVec2(left_w, 0));
            ImGui::SetNextWindowSize(ImVec2(fb_w - left_w - right_w, fb_h - bottom_h));
            ImGui::Begin("Viewport", nullptr, fixed);
            if (!s.error.empty()) {
                ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1, 0.4f, 0.4f, 1));
                ImGui::TextWrapped("error: %s", s.error.c_str());
                ImGui::PopStyleColor();
            }
            if (result) {
                std::string names;
                for (const Layer& l : result->layers.layers()) names += l.name + '\0';
                ImGui::SetNextItemWidth(160);
                if (ImGui::Combo("layer", &s.layer_index, names.c_str())) s.texture_dirty = true;
                const Layer& shown = result->layers.layers()[size_t(s.layer_index)];
                ImGui::SameLine();
                ImGui::TextDisabled("[%s] %s", to_string(shown.kind), shown.description.c_str());
                const ImVec2 avail = ImGui::GetContentRegionAvail();
                const float scale = std::min(avail.x / texture.width(), avail.y / texture.height());
                const ImVec2 size(texture.width() * scale, texture.height() * scale);
                const ImVec2 origin = ImGui::GetCursorScreenPos();
                ImGui::Image(reinterpret_cast<ImTextureID>(intptr_t(texture.id())), size);
                if (ImGui::IsItemClicked()) {
                    const ImVec2 m = ImGui::GetMousePos();
                    s.inspect_x = std::clamp(int((m.x - origin.x) / scale), 0, texture.width() - 1);
                    s.inspect_y =
                        std::clamp(int((m.y - origin.y) / scale), 0, texture.height() - 1);
                }
            }
            ImGui::End();

            // Right: inspector.
            ImGui::SetNextWindowPos(ImVec2(fb_w - right_w, 0));
            ImGui::SetNextWindowSize(ImVec2(right_w, fb_h - bottom_h));
            ImGui::Begin("Inspector", nullptr, fixed);
            draw_inspector(s, result);
            ImGui::End();

            // Bottom: timeline and status.
            ImGui::SetNextWindowPos(ImVec2(0, fb_h - bottom_h));
            ImGui::SetNextWindowSize(ImVec2(float(fb_w), bottom_h));
            ImGui::Begin("Timeline", nullptr, fixed | ImGuiWindowFlags_NoTitleBar);
            draw_timeline(s);
            if (s.job && !s.job->done()) {
                const ProgressSnapshot p = s.job->snapshot();
                ImGui::Text("rendering frame %d: %s %.0f%%", s.job_frame, p.stage.c_str(),
                            100 * p.fraction);
                ImGui::SameLine();
                if (ImGui::SmallButton("cancel")) s.job->cancel();
            } else if (result) {
                ImGui::Text("frame %d: %.1f ms, %ld rays", result->frame,
                            result->stats["time_ms"].get<double>(),
                            result->stats["rays"].get<long>());
            }
            ImGui::End();

            ImGui::Render();
            glViewport(0, 0, fb_w, fb_h);
            glClearColor(0.1f, 0.1f, 0.1f, 1.0f);
            glClear(GL_COLOR_BUFFER_BIT);
            ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
            if (!options.screenshot.empty()) {
                // A couple of frames after the requested frame is on screen, so layout settled.
                const bool ready = (result && result->frame == s.frame) || !s.error.empty();
                if (ready && screenshot_countdown < 0) screenshot_countdown = 2;
                if (screenshot_countdown == 0) {
                    write_window_png(options.screenshot, fb_w, fb_h);
                    std::fprintf(stderr, "wrote %s (%dx%d)\n", options.screenshot.c_str(), fb_w,
                                 fb_h);
                    exit_code = s.error.empty() ? 0 : 1;
                    break;
                }
                if (screenshot_countdown > 0) --screenshot_countdown;
            }
            host.end_frame();
        }
        s.job.reset();
    }
    return exit_code;
}

}  // namespace

int run_workbench(const WorkbenchOptions& options) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;
    ImGui::StyleColorsDark();
    int code = 0;
    {
        GlfwHost host(options.width, options.height, "freqlab — " + options.scene);
        ImGui_ImplOpenGL3_Init("#version 330");
        code = run_workbench_in(host, options);
        ImGui_ImplOpenGL3_Shutdown();
    }
    ImGui::DestroyContext();
    return code;
}

}  // namespace freqlab::ui
