// The workbench's state, shared by its translation units (workbench.cpp draws the panels and
// hosts; workbench_tools.cpp compares, exports and saves sessions). Private to ui/.
#pragma once

#include <imgui.h>

#include <atomic>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "base/job.h"
#include "image/figure.h"
#include "image/metrics.h"
#include "layer_view.h"
#include "render/background_frame_reader.h"
#include "render/frame_renderer.h"
#include "render/frame_store.h"
#include "scene/json_reader.h"
#include "scene/scene.h"
#include "session/session_file.h"
#include "tables_panel.h"
#include "volume/lightmap_baker.h"
#include "workbench.h"

namespace freqlab::ui {

// Method B's bake in the workbench (workbench_bake.cpp).
struct BakeSession;
struct BakeSessionDeleter {
    void operator()(BakeSession* b) const;  // cancels and joins its job first
};
using BakeSessionPtr = std::unique_ptr<BakeSession, BakeSessionDeleter>;

// A/B (workbench_ab.cpp): run A, kept to compare the run shown (B) with.
struct RunA {
    nlohmann::json key;
    std::filesystem::path dir;
    std::string method;
    std::map<int, nlohmann::json> stats;  // A's recorded frames
    int rescanned_for = -1;               // the frame A's folder was last read again for
};
constexpr const char* kRunALayer = "run_a";

struct Workbench::State {
    WorkbenchOptions options;
    Scene scene;
    RenderConfig config;
    std::unique_ptr<EmbreeDevice> device;
    std::unique_ptr<FrameRenderer> renderer;
    std::unique_ptr<Job> job;
    int job_frame = -1;
    // Method cache (render/frame_checkpoint.h): the frame the renderer's state comes before
    // (set by the job), the run's key and its folder in the run store, where the job saves the
    // cache before every cache.checkpoint_every-th frame and a jump resumes from.
    std::atomic<int> state_next{0};
    nlohmann::json run_key;
    std::filesystem::path run_dir;
    int job_resumed_from = -1;  // the checkpoint the running job restored (-1: none)
    // Radiance points the runs of this session shaded (render/shading_memo.h), kept while the
    // settings that shade them stay: a cache.* change re-runs the cache without shading again.
    std::shared_ptr<ShadingMemo> shading_memo;
    nlohmann::json shading_memo_key;
    size_t shading_memo_cap = 0;            // $FREQLAB_SHADING_MEMO_MB, read when the scene opens
    long shading_memo_recalled_before = 0;  // its count when this run started (status line)
    // A render cancelled by the user stays cancelled: no job starts for this frame again until
    // the frame or a setting changes, or the status line's "render" is pressed.
    int cancelled_frame = -1;

    mutable std::mutex results_mutex;
    // Frames decoded in memory (capped, render/frame_store.h); the run store on disk keeps every
    // frame the run rendered (`recorded`: their stats), read back when shown again.
    DecodedFrames results{0};
    std::map<int, nlohmann::json> recorded;
    std::string store_failure;  // why the last frame could not be kept on disk (shown)
    // The stages of the last frame the job rendered, and how long each took: the next frame's
    // progress plan (base/job.h: fractions by time, an ETA that only falls).
    std::vector<StageTime> last_stage_times;
    // The first image of the frame the job renders (render/sparse_pass.h), until it is kept.
    std::shared_ptr<FrameResult> preview;
    // Whole frames read after a jump showed their on-screen layers (recorded_result).
    std::unique_ptr<BackgroundFrameReader> frame_reader = std::make_unique<BackgroundFrameReader>();

    int frame = 0;
    bool playing = false;
    int play_ticks = 0;
    std::string layer_name = "color";
    bool overlay_on_color = false;
    float overlay_opacity = 0.6f;
    bool fixed_range = false;
    DisplayRange range{0, 1};
    int stat_index = 0;

    LayerView view, base_view;  // shown layer; colour under an overlay
    int shown_frame = -1;
    bool view_dirty = true;
    DisplayRange shown_range;
    std::shared_ptr<const FrameResult> shown;

    float left_w = 0.0f, right_w = 0.0f, bottom_h = 0.0f;  // panel sizes (px; 0: not yet set)
    float zoom = 1.0f;                                     // 1 = fit
    ImVec2 centre{0.5f, 0.5f};                             // uv at the viewport centre
    int pick_x = -1, pick_y = -1;
    ScreenRect image_rect, colorbar_rect;
    std::vector<std::pair<std::string, ScreenRect>> legend;
    std::string error, status;

    // Compare against the reference (workbench_tools.cpp).
    std::unique_ptr<FrameRenderer> reference_renderer;
    std::unique_ptr<Job> reference_job;
    int reference_job_frame = -1;
    std::map<int, LayerSet> references;   // guarded by results_mutex
    std::map<int, ImageMetrics> metrics;  // of the frame's colour against its reference
    bool split = false;
    float split_position = 0.5f;
    LayerView reference_view;
    std::string reference_note;       // how the reference was chosen (bakes: its measured noise)
    std::optional<RunA> run_a;        // A/B: frames are compared with A's instead
    std::vector<FigureInset> insets;  // for Export > Figure
    std::vector<std::string> trace_lines;      // the inspector's pixel trace
    std::optional<RadiancePoint> trace_point;  // method points: the pixel's radiance point
    std::pair<int, int> trace_pixel{-1, -1};
    int trace_frame = -1;
    bool trace_partial = false;     // the lines are the frame's recorded decisions only
    bool select_trace_tab = false;  // --inspect-tab trace, sessions: open the inspector on it
    std::unique_ptr<TablesPanelState> tables = make_tables_panel();
    // Method A's environment bandwidth hierarchy, shown in the viewport instead of the frame.
    bool show_env_bandwidth = false;
    std::unique_ptr<Job> env_bandwidth_job;
    std::shared_ptr<FrameResult> env_bandwidth;  // guarded by results_mutex
    std::string session_path = "freqlab-out/session.json";
    std::string scene_path;           // File > Open scene's field (the scene's file at start)
    BakeSessionPtr bake;              // set when the method is a bake method (surface ... vpt)
    std::vector<ImVec2> probe_marks;  // where draw_probe_lobes put each probe (screen)
    // The method menu's choice, taken after the panels are drawn (Workbench::set_method).
    std::string pending_method;
    uint64_t tables_media_version = ~uint64_t(0);  // the bake media the tables panel follows
};

// Throws Error on a bad bake setting; needs s.scene and s.device.
void make_bake_session(Workbench::State& s, const std::string& method,
                       const std::vector<std::string>& assignments);
void start_bake(Workbench::State& s);
bool bake_busy(const Workbench::State& s);
void wait_for_bake(Workbench::State& s);
// The bake's jobs read its settings and media: stop them before either changes (needs s.bake).
void stop_bake_jobs(Workbench::State& s);
// Starts the bake again after a change, dropping the VPT comparison of what was baked before.
void restart_bake(Workbench::State& s);
void draw_bake_panel(Workbench::State& s);
// The bake's atlas notes (densities not honoured), in the notes' colour at the panel's top.
void draw_bake_notes(const Workbench::State& s);
// The inspector's record of a pixel of the lightmapped preview: its texel's trace.
std::vector<std::string> bake_trace(Workbench::State& s, int x, int y);
// Probes' SH lobes over the viewport image (call inside the viewport window).
void draw_probe_lobes(Workbench::State& s);
BakeMethod bake_method(const Workbench::State& s);  // needs s.bake
// Another bake method in the same session (media sliders, camera and settings kept).
void switch_bake_method(Workbench::State& s, BakeMethod method);
// The Method B tables panel's sliders take the bake's first medium's coefficients whenever
// they change (the media sliders, a session), so the lobes shown are the bake's.
void follow_bake_media(Workbench::State& s);
// A bake.* assignment (Workbench::apply_setting): the bake restarts with it.
void apply_bake_setting(Workbench::State& s, const std::string& assignment);
// What an export of the bake says made it (scene/provenance.h): its method, bake.* settings,
// seed and the media coefficients in use.
nlohmann::json bake_provenance(const Workbench::State& s);
// A bake's part of the session file (its state now).
BakeSessionFile bake_session_file(const Workbench::State& s);
// Stops the bake and takes the file's state (needs s.bake; the caller restarts it).
void apply_bake_session(Workbench::State& s, const BakeSessionFile& f);
// Compare for a bake: a VPT bake whose measured noise is below a quarter of the error it
// measures (workbench_bake.cpp), its preview as the frame's reference.
void start_bake_reference(Workbench::State& s);
// Adds reference, error, relative_error to results[frame] and measures (results_mutex held).
void attach_reference(Workbench::State& s, int frame);
// A frame's result: decoded in memory, else read from the run store (results_mutex held; null
// when the frame is not recorded, or its file went: then it is no longer listed as recorded).
// Read from the store, it holds the layers on screen only (`partial`: ~2.8 MB of a 55 MB frame
// at 640 x 360) and the whole frame is asked of s.frame_reader, which poll_frame_reader swaps in.
std::shared_ptr<FrameResult> recorded_result(Workbench::State& s, int frame);
// Keeps the whole frames s.frame_reader has read; the one shown partially replaces it
// (results_mutex held).
void poll_frame_reader(Workbench::State& s);
// The frame shown, whole (exports, traces, the inspector's rows need every layer): waits for or
// reads what a jump left for later. When the file went meanwhile, nothing is shown (the frame
// renders again) and the status line says why.
void complete_shown(Workbench::State& s);
// Keeps a frame just rendered or baked (results_mutex held).
void keep_result(Workbench::State& s, FrameResult result);

void restart_renderer(Workbench::State& s);
// A/B of two recorded runs (workbench_ab.cpp). comparing_runs: A is kept and B (shown) is
// another run; then the "reference" of a frame is A's recording of it.
bool comparing_runs(const Workbench::State& s);
void pin_run_a(Workbench::State& s);
void unpin_run_a(Workbench::State& s);
void poll_run_a(Workbench::State& s);  // loads A's frame for the frame shown
void draw_run_ab_panel(Workbench::State& s);
// A's per-frame statistic `stat` (0 where A has no frame; empty when not comparing runs).
std::vector<float> run_a_strip(const Workbench::State& s, const char* stat);
// Compare, exports and sessions (workbench_tools.cpp).
void poll_reference(Workbench::State& s);
void start_reference(Workbench::State& s);
void render_reference_view(Workbench::State& s, const DisplayParams& params);
void draw_compare_panel(Workbench::State& s);
// The viewport (workbench_viewport.cpp).
void draw_viewport(Workbench::State& s);
// Method A's cache: reused / new / discards per reason over the rendered frames
// (workbench_cache_panel.cpp).
void draw_cache_panel(Workbench::State& s);
// The inspector panel (workbench_inspector.cpp).
void draw_inspector(Workbench& wb, Workbench::State& s);
void draw_export_menu(Workbench::State& s);
void draw_session_menu(Workbench& wb, Workbench::State& s);
// View and Help menus: the viewport's toggles, the shortcuts.
void draw_view_menu(Workbench::State& s);
void draw_help_menu();
nlohmann::json session_to_json(const Workbench::State& s);

}  // namespace freqlab::ui
