// The workbench: settings panels generated from core's declarations, a viewport showing the
// colour or any layer (GPU colormap by kind, colorbar or legend, overlay on colour with an
// opacity, pan/zoom), a pixel inspector, and a timeline with a per-frame stats strip.
// Rendering runs as a cancellable background job; the UI thread never waits for it.
//
// The same Workbench draws into a GLFW window or an OSMesa context (gl_host.h); tests drive it
// through the public methods below rather than through pixels alone.
#pragma once

#include <nlohmann/json.hpp>

#include <memory>
#include <string>
#include <vector>

#include "image/colormap.h"
#include "image/layers.h"
#include "image/metrics.h"

namespace freqlab {
struct Scene;
}

namespace freqlab::ui {

class GlHost;

struct WorkbenchOptions {
    std::string scene = "builtin:default";  // a file or builtin:default
    std::string method = "gbuffer";
    int frame = 0;
    std::string layer;  // layer shown ("" = color)
    std::string
        screenshot;  // when set: once the frame is shown, write the workbench as PNG and exit
    int width = 1280, height = 760;
    // Scale of fonts, widgets and panels (--ui-scale): 0 takes the monitor's content scale
    // (GLFW; 1 offscreen). Refused outside [0.5, 4] by the command line.
    float ui_scale = 0.0f;
    std::vector<std::string> settings;   // "key=value", as --set
    int inspect_x = -1, inspect_y = -1;  // pixel selected in the inspector
    bool inspect_trace = false;          // the inspector opens on its trace tab
    int warm_from = -1;                  // render frames warm_from .. frame-1 first (stats strip)
    // Wall-clock timings on screen (status line, stats strip, inspector). Off gives pictures
    // that depend only on the state: what tests compare across hosts.
    bool show_timings = true;
    std::string session;       // a session JSON to load at start (overrides the fields above)
    bool compare = false;      // render the reference of the frame and show the split view
    bool show_tables = false;  // open the method B tables panel (and wait for the tables)
    bool show_env_bandwidth = false;  // the environment bandwidth hierarchy in the viewport
    int tables_emitter = 0;           // EmitterKind shown there first
    bool play = false;                // start playing the timeline
    std::string hint;                 // one line under the viewport: what the view shows
};

struct ScreenRect {
    float x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool contains(float x, float y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
};

struct InspectorRow {
    std::string layer;
    std::vector<float> values;
    std::string note;  // legend entry of a categorical value
};

class Workbench {
  public:
    explicit Workbench(const WorkbenchOptions& options);  // needs a current GL + ImGui context
    ~Workbench();

    void draw(int framebuffer_width, int framebuffer_height);  // inside ImGui::NewFrame/Render

    // State, for hosts and tests.
    void set_frame(int frame);
    int frame() const;
    bool set_layer(const std::string& name);
    void apply_setting(const std::string& assignment);  // "prefix.key=value"; re-renders as needed
    bool frame_shown() const;                           // the current frame's result is on screen
    // ... and every layer of it is in memory (a frame read back from the run store shows its
    // layers on screen first, the rest follows from a background read).
    bool frame_complete() const;
    bool first_image_shown() const;  // the current frame's first image (it still renders)
    // Something on screen changes without input: a job runs, playback, a frame not shown yet.
    bool busy() const;
    std::vector<int> recorded_frames() const;  // frames rendered and kept, in order
    int frame_count() const;                   // the scene's
    // A/B: the run shown becomes A; after a settings change each frame shown (B) gains the
    // layers run_a, error, relative_error and metrics() against A's recording of it.
    void keep_run_as_a();
    void forget_run_a();
    bool comparing_runs() const;  // A kept and another run shown
    // The run store folder of the run shown (render/frame_store.h; empty for bakes).
    std::string run_directory() const;
    struct DecodedMemory {
        std::vector<int> frames;  // decoded in memory now
        size_t bytes = 0, cap = 0;
    };
    DecodedMemory decoded_memory() const;
    void cancel_render();  // as the status line's cancel: stops the job, starts none again
    // The checkpoint the last render job of a stateful method started from (-1: none).
    int resumed_from() const;
    void wait_for_render();  // blocks until no render job is running (tests, headless)
    const LayerSet* layers() const;
    DisplayRange shown_range() const;
    void select_pixel(int x, int y);
    std::vector<InspectorRow> inspect() const;  // every layer at the selected pixel
    // The inspector's trace of the selected pixel as drawn (empty until it is computed).
    const std::vector<std::string>& trace_lines() const;
    ScreenRect image_rect() const;     // where the viewport image was drawn
    ScreenRect colorbar_rect() const;  // the colorbar's gradient (empty if none)
    std::vector<std::pair<float, float>> probe_marks() const;  // probes drawn (screen)
    // The viewport's zoom (1 = fit) about the image's uv (cx, cy), as the wheel and drag set.
    void set_view(float zoom, float cx, float cy);
    std::vector<std::pair<std::string, ScreenRect>> legend_swatches() const;
    const std::string& error() const;

    // Sessions: scene, method, settings, frame, layer, display, view, inspector, insets as JSON.
    void save_session(const std::string& path) const;
    void load_session(const std::string& path);   // throws Error naming file and field
    void reset(const WorkbenchOptions& options);  // reloads the scene; errors show in the UI
    // Another scene with the method and settings chosen now, in the panels or by --set (File >
    // Open scene); a scene that does not load is an error shown in the UI, the workbench as it
    // was.
    void open_scene(const std::string& path);
    // The method menu: a render method (gbuffer ... cache) or a bake method (surface ... vpt,
    // which opens the bake session); the settings chosen so far are kept.
    void set_method(const std::string& name);
    std::string method() const;

    // Compare: render the reference of the shown frame in the background; when it arrives the
    // frame gains layers reference, error, relative_error and metrics() answers.
    void request_reference();
    bool reference_busy() const;
    const ImageMetrics* metrics() const;
    // How the reference was chosen (bakes: its samples and measured noise against the error).
    const std::string& reference_note() const;
    bool tables_ready() const;  // the tables panel has its tables
    void show_env_bandwidth();  // switches the viewport to it (waits for the hierarchy)
    // The name exported files of the shown result start with: scene, frame (or the
    // environment view) and layer.
    std::string export_stem() const;
    // Export > All layers as EXR, to `path`: the shown result's layers with the provenance of
    // what made them (scene/provenance.h: method, settings, seed, media coefficients in use).
    void export_exr(const std::string& path) const;
    nlohmann::json export_provenance() const;
    const std::string& status() const;

    struct State;  // defined in workbench.cpp; public so its helper functions can name it

  private:
    // reset() with the scene already loaded from options.scene (moved from; null: load it).
    void reset(const WorkbenchOptions& options, Scene* loaded);
    // reset() onto `scene_path` with `method`, keeping the settings the panels hold now.
    void reopen(const std::string& scene_path, const std::string& method, Scene* loaded);
    std::unique_ptr<State> s_;
};

// An ImGui context for a host's lifetime (dark style, no ini file).
struct ImGuiSession {
    ImGuiSession();
    ~ImGuiSession();
    ImGuiSession(const ImGuiSession&) = delete;
    ImGuiSession& operator=(const ImGuiSession&) = delete;
};

// Scales ImGui's style and loads its font at 13 px x scale (DejaVu Sans Mono when the scale is
// not 1; the default font otherwise). Call before the first frame.
void apply_ui_scale(float scale);

// One UI frame on a host: platform frame, ImGui frame, the workbench, GL draw.
void render_ui_frame(GlHost& host, Workbench& workbench);

int run_workbench(const WorkbenchOptions& options);  // a GLFW window (needs a display)
int run_headless(const WorkbenchOptions& options);   // OSMesa; writes options.screenshot

// `freqlab bench --study scrub` (ui/scrub_bench.cpp): records a run in the headless workbench,
// opens it again, and times random jumps across it; writes OUT/bench_scrub.json.
struct ScrubBenchOptions {
    WorkbenchOptions workbench;  // scene, method, settings
    int jumps = 100;
    int cache_change_trials = 3;  // step 4: cache.q_eps_x changes timed (0: skipped)
    uint64_t seed = 1;
    std::string out = "freqlab-out/bench";
};
int run_scrub_bench(const ScrubBenchOptions& options);

}  // namespace freqlab::ui
