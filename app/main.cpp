// freqlab: the workbench and its command line (DESIGN.md "Command line").
#include <CLI/CLI.hpp>

#include <csignal>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "base/error.h"
#include "base/job.h"
#include "cluster.h"
#include "commands.h"
#include "render/method.h"
#include "volume/bake_estimators.h"
#include "volume/impulse_query.h"
#ifdef FREQLAB_HAS_UI
#include "workbench.h"
#endif

namespace {

// No display: say so and take the headless route, naming the PNG it writes.
int headless_fallback(const std::string& scene, int frame) {
    std::string stem = std::filesystem::path(scene).stem().string();
    for (char& c : stem)
        if (c == ':') c = '_';  // builtin:default -> builtin_default
#ifdef FREQLAB_HAS_UI
    const std::string png = "freqlab-out/workbench_" + stem + ".png";
    std::fprintf(stderr,
                 "freqlab: no display (DISPLAY is unset), so the workbench window cannot open.\n"
                 "Rendering the workbench offscreen (OSMesa) instead: %s\n"
                 "(for a window, run under X or `xvfb-run -a freqlab`; scripted: `freqlab gui "
                 "SCENE --headless --screenshot OUT.png`)\n",
                 png.c_str());
    std::filesystem::create_directories("freqlab-out");
    freqlab::ui::WorkbenchOptions options;
    options.scene = scene;
    options.frame = frame;
    options.screenshot = png;
    return freqlab::ui::run_headless(options);
#else
    const std::string out = "freqlab-out/" + stem;
    std::fprintf(stderr,
                 "freqlab: built without the UI and no display: rendering %s/frame_0000.png\n",
                 out.c_str());
    freqlab::RenderArgs args;
    args.scene = scene;
    args.out = out;
    return freqlab::run_render(args);
#endif
}

#ifdef FREQLAB_HAS_UI
// `bench --study scrub`: method cache on the scene at --size, --set applied.
int run_scrub_study(const freqlab::BenchArgs& a, int jumps, int cache_change_trials) {
    const auto [w, h] = freqlab::parse_size(a.size, "--size");
    freqlab::ui::ScrubBenchOptions o;
    o.workbench.scene = a.scene;
    o.workbench.method = "cache";
    o.workbench.settings = {"frame.width=" + std::to_string(w),
                            "frame.height=" + std::to_string(h)};
    o.workbench.settings.insert(o.workbench.settings.end(), a.sets.begin(), a.sets.end());
    o.jumps = jumps;
    o.cache_change_trials = cache_change_trials;
    o.out = a.out;
    return freqlab::ui::run_scrub_bench(o);
}
#endif

}  // namespace

// Ctrl-C / SIGTERM: the command stops at its next checkpoint (files written so far are
// complete, the one being written is finished or never appears); a second one kills at once.
extern "C" void cancel_on_signal(int signal_number) {
    freqlab::request_process_cancel();
    std::signal(signal_number, SIG_DFL);
}

int main(int argc, char** argv) {
    // Under mpirun every rank parses the same command line; MPI ends with main (MpiSession).
    struct MpiSession {
        MpiSession(int* argc, char*** argv) { freqlab::Cluster::world().start(argc, argv); }
        ~MpiSession() { freqlab::Cluster::world().finish(); }
    } mpi_session(&argc, &argv);
    const freqlab::Cluster& cluster = freqlab::Cluster::world();
    CLI::App app{"freqlab — a workbench for frequency-space light-transport caching"};
    app.require_subcommand(0, 1);

    std::string gui_scene = "builtin:default";
    bool headless = false;
    std::string screenshot, overlay, gui_size;
    int gui_frame = 0;
    auto* gui = app.add_subcommand("gui", "open the workbench (default: the built-in scene)");
    gui->add_option("scene", gui_scene, "scene file or builtin:default");
    gui->add_flag("--headless", headless, "render offscreen (OSMesa) without a display");
    gui->add_option("--screenshot", screenshot, "write the workbench to this PNG and exit");
    gui->add_option("--frame", gui_frame, "frame to show");
    gui->add_option("--overlay", overlay, "layer to overlay");
    gui->add_option("--size", gui_size, "window size WxH");
    std::string gui_ui_scale;
    gui->add_option("--ui-scale", gui_ui_scale,
                    "scale of fonts, widgets and panels, 0.5 to 4 (default: the monitor's "
                    "content scale; 1 offscreen)");
    std::string gui_method = "gbuffer";
    std::vector<std::string> gui_sets;
    gui->add_option("--method", gui_method, freqlab::render_method_list());
    gui->add_option("--set", gui_sets, "key=value setting (repeatable)");
    std::string gui_inspect, gui_warm, gui_session;
    bool gui_compare = false, gui_tables = false;
    gui->add_flag("--tables", gui_tables, "open the method B tables panel");
    bool gui_env_bandwidth = false;
    gui->add_flag("--env-bandwidth", gui_env_bandwidth,
                  "show the environment's bandwidth hierarchy (method A) in the viewport");
    std::string tables_emitter = "point";
    gui->add_option("--tables-emitter", tables_emitter,
                    "emitter shown in the tables panel: point, directional or area");
    gui->add_flag("--compare", gui_compare, "render the frame's reference and show the split view");
    gui->add_option("--session", gui_session,
                    "session JSON to load (File > Save session writes one)");
    gui->add_option("--inspect", gui_inspect, "X,Y: select this pixel in the inspector");
    bool gui_inspect_trace = false;
    gui->add_flag("--inspect-trace", gui_inspect_trace,
                  "open the inspector on its trace tab (the method's record of the pixel)");
    gui->add_option("--warm-from", gui_warm, "render frames from this one up to --frame first");

    freqlab::RenderArgs r;
    auto* render = app.add_subcommand("render", "render frames to EXR + PNG + stats.json");
    render->add_option("scene", r.scene, "scene file or builtin:default")->required();
    render->add_option("--method", r.method, freqlab::render_method_list());
    render->add_option("--frames", r.frames, "A:B renders frames A..B-1 (default 0:1)");
    render->add_option("--size", r.size, "WxH");
    render->add_option("--spp", r.spp, "samples per pixel of the method");
    render->add_option("--seed", r.seed, "random seed");
    render->add_option("--threads", r.threads, "worker threads (0 = all cores)");
    render->add_option("--set", r.sets, "key=value setting (repeatable)");
    render->add_option("--debug-pixel", r.debug_pixel, "X,Y: print this pixel's trace");
    render->add_flag("--quiet", r.quiet, "no progress bar");
    render->add_option("--out", r.out, "output directory")->required();
    render->add_option("--part", r.part,
                       "I/N: render part I of N (a Slurm array task; `freqlab merge` joins the "
                       "parts); under mpirun the ranks split the frames themselves");
    render->add_option("--warm-frames", r.warm_frames,
                       "method cache split into parts or ranks: frames each part renders to warm "
                       "its cache before the first frame it keeps (default 10)");
    render->add_option("--checkpoint-every", r.checkpoint_every,
                       "method cache: write the cache before every K-th frame to "
                       "OUT/checkpoints/state_before_NNNN.bin");
    render->add_option("--resume-from", r.resume_from,
                       "DIR: continue from its newest checkpoint at or before the first of "
                       "--frames (the frames kept are byte-identical to a run from frame 0)");

    std::string merge_out;
    std::vector<std::string> merge_parts;
    auto* merge = app.add_subcommand(
        "merge",
        "join the parts of a split run (render / bench --study bake-thickness --part I/N)");
    merge->add_option("out", merge_out, "output directory of the whole run")->required();
    merge->add_option("parts", merge_parts, "the parts' output directories")->required();

    freqlab::CompareArgs c;
    auto* compare = app.add_subcommand("compare", "error metrics of TEST against REF as JSON");
    compare->add_option("test", c.test, "test EXR")->required();
    compare->add_option("ref", c.ref, "reference EXR")->required();
    compare->add_option("--metrics", c.metrics,
                        "comma-separated: rmse,relmse,ssim,max_abs,nonfinite");
    compare->add_option("--layer", c.layer, "layer to compare (default color)");

    freqlab::FigureArgs fa;
    auto* figure =
        app.add_subcommand("figure", "a paper figure from an EXR: image, insets, colorbar");
    figure->add_option("input", fa.input, "EXR written by render")->required();
    figure->add_option("--layer", fa.layer, "layer to show (default color)");
    figure->add_option("--inset", fa.insets, "X,Y,W,H zoomed inset (up to 4)");
    figure->add_option("--scale", fa.scale, "magnification of the main image (default 2)");
    figure->add_option("--exposure", fa.exposure, "EV for colour layers");
    figure->add_option("--title", fa.title, "title text");
    figure->add_option("--out", fa.out, "output PNG")->required();

    freqlab::TablesQueryArgs tq;
    bool tables_query = false;
    auto* tables = app.add_subcommand("tables", "query the impulse-response tables (method B)");
    tables->add_flag("--query", tables_query, "print the ZH coefficients for one configuration");
    tables->add_option("--emitter", tq.emitter, "point|directional|area");
    tables->add_option("--distance", tq.distance, "to the point emitter / to the medium boundary");
    tables->add_option("--sigma-s", tq.sigma_s, "scattering coefficient");
    tables->add_option("--sigma-a", tq.sigma_a, "absorption coefficient");
    tables->add_option("--g", tq.g,
                       "Henyey-Greenstein anisotropy, |g| <= 0.95 (the tables' range)");
    tables->add_option("--shift", tq.shift,
                       "area emitters: sin of the angle between the emitter normal and the "
                       "direction to the receiver, in [0, 1]");
    tables->add_option("--variant", tq.variant,
                       "infinite (pure infinite medium) or surface (back-scatter shift 0.125)");
    tables->add_option("--receiver", tq.receiver,
                       "medium (a probe: medium all around) or surface (a lightmap texel: "
                       "directional multiple scattering of the slab whose bottom holds it)");
    tables->add_option("--bounces", tq.bounces,
                       "1, N or all (multiple scattering: point emitters)");
    std::string tables_out;
    tables->add_option("--out", tables_out, "table file to write (default: the cache)");
    freqlab::BakeArgs bk;
    auto* bake = app.add_subcommand("bake", "method B: lightmap baking with participating media");
    bake->add_option("scene", bk.scene, "scene file");
    bake->add_option("--method", bk.method, freqlab::bake_method_list());
    bake->add_option("--spp", bk.spp, "paths per texel (bake.spp)");
    bake->add_option("--seed", bk.seed, "random seed (bake.seed)");
    bake->add_option("--threads", bk.threads, "worker threads (0 = all cores)");
    bake->add_option("--set", bk.sets, "key=value setting (repeatable)");
    bake->add_option("--reference", bk.reference,
                     "directory of a reference bake: relMSE / RMSE per lightmap layer; given "
                     "twice (two seeds of one bake), their mean, and the noise it leaves in "
                     "the relMSE")
        ->expected(1, 2);
    bake->add_flag("--compare-surface", bk.compare_surface,
                   "also run a surface bake at equal samples and report the overhead");
    bake->add_option("--debug-texel", bk.debug_texel,
                     "[LIGHTMAP:]X,Y: print the texel and every method's estimate there");
    bake->add_option("--preview-size", bk.preview_size,
                     "WxH of preview.exr / preview.png, the lightmapped scene from its camera");
    bake->add_flag("--quiet", bk.quiet, "no progress bar");
    bake->add_option("--out", bk.out, "output directory")->required();
    freqlab::BenchArgs ba;
    auto* bench = app.add_subcommand("bench",
                                     "time-vs-error studies: method A against MIS (points, sparse, "
                                     "cache), method B's baker (bake)");
    bench->add_option("scene", ba.scene, "scene file");
    bench->add_option(
        "--study", ba.study,
        "points: adaptive radiance points vs fixed-N MIS; sparse: sparse vs points and "
        "equal-time MIS on one frame (time, rays, RMSE); cache: the cache vs sparse and "
        "equal-time MIS over frames; cache-ablation: temporal test on/off; bake: method B; "
        "bake-thickness: method B's error against VPT as the media thicken; stability: every "
        "setting and scene extreme over all methods, counting non-finite values per layer; "
        "scrub: the workbench (offscreen) records a run of method cache and times --jumps "
        "random jumps across it");
    int scrub_jumps = 100;
    bench->add_option("--jumps", scrub_jumps, "scrub study: random jumps timed");
    int scrub_cache_changes = 3;
    bench
        ->add_option("--cache-change-trials", scrub_cache_changes,
                     "scrub study: cache.q_eps_x changes at frame 60 timed with the shading "
                     "memo and from scratch (0: none)")
        ->check(CLI::NonNegativeNumber);
    bench->add_option("--frames", ba.frames, "cache studies: A:B (default: all frames)");
    bench->add_option("--error-every", ba.error_every,
                      "cache studies: RMSE against the reference every k-th frame");
    bench->add_option("--frame", ba.frame, "frame");
    bench->add_option("--size", ba.size, "WxH");
    bench->add_option("--runs", ba.runs,
                      "points: independent adaptive renders per pixel error; sparse: timed runs");
    bench->add_option("--reference-spp", ba.reference_spp,
                      "points: stratified reference samples; bake study: VPT reference samples");
    bench->add_option("--max-spp", ba.max_spp, "bake study: impulse / extinction curve length");
    bench->add_option("--overhead-spp", ba.overhead_spp,
                      "bake study: samples of the overhead and re-bake runs");
    bench->add_option("--set", ba.sets, "key=value setting (repeatable)");
    bench->add_flag("--full", ba.full,
                    "stability study: every declared extreme, incl. the largest sample counts");
    bench->add_flag("--quiet", ba.quiet, "stability study: no line per case");
    bench->add_option("--out", ba.out, "output directory (bench_points.json)");
    bench->add_option("--part", ba.part,
                      "bake-thickness: I/N, compute part I of N of the configurations (a Slurm "
                      "array task; `freqlab merge` joins the parts)");

    CLI11_PARSE(app, argc, argv);
    if (cluster.distributed() && !*render && !*bake && !*bench) {
        if (cluster.rank() == 0)
            std::fprintf(stderr, "error: only render, bake and bench split over MPI ranks\n");
        return 1;
    }
    const bool command_line =
        *render || *compare || *figure || *tables || *bake || *bench || *merge;
    if (command_line) {
        std::signal(SIGINT, cancel_on_signal);
        std::signal(SIGTERM, cancel_on_signal);
    }
    try {
        if (*render) return freqlab::run_render(r);
        if (*merge) return freqlab::run_merge(merge_out, merge_parts);
        if (*compare) return freqlab::run_compare(c);
        if (*figure) return freqlab::run_figure(fa);
        if (*tables) {
            if (!tables_query)
                return freqlab::run_tables_generate(tables_out, freqlab::kDefaultTableBounces);
            return freqlab::run_tables_query(tq);
        }
        if (*bake) return freqlab::run_bake(bk);
        if (*bench && ba.study == "scrub") {
#ifdef FREQLAB_HAS_UI
            return run_scrub_study(ba, scrub_jumps, scrub_cache_changes);
#else
            throw freqlab::Error("--study", "scrub", "needs the workbench (built without UI)");
#endif
        }
        if (*bench) return freqlab::run_bench(ba);
            // `freqlab` alone, or `freqlab gui ...`
#ifdef FREQLAB_HAS_UI
        freqlab::ui::WorkbenchOptions options;
        options.scene = gui_scene;
        options.method = gui_method;
        options.frame = gui_frame;
        options.layer = overlay;
        options.screenshot = screenshot;
        options.settings = gui_sets;
        options.session = gui_session;
        options.compare = gui_compare;
        options.show_tables = gui_tables;
        options.inspect_trace = gui_inspect_trace;
        options.show_env_bandwidth = gui_env_bandwidth;
        options.tables_emitter = int(freqlab::parse_emitter(tables_emitter));
        if (!gui_inspect.empty()) {
            if (std::sscanf(gui_inspect.c_str(), "%d,%d", &options.inspect_x, &options.inspect_y) !=
                2)
                throw freqlab::Error("--inspect", gui_inspect, "expected X,Y");
        }
        if (!gui_warm.empty()) options.warm_from = freqlab::parse_count(gui_warm, "--warm-from");
        if (!gui_ui_scale.empty()) {
            char* end = nullptr;
            const double scale = std::strtod(gui_ui_scale.c_str(), &end);
            if (end == gui_ui_scale.c_str() || *end != '\0' || !(scale >= 0.5 && scale <= 4.0))
                throw freqlab::Error("--ui-scale", gui_ui_scale, "expected a number from 0.5 to 4");
            options.ui_scale = float(scale);
        }
        if (!gui_size.empty()) {
            const auto [w, h] = freqlab::parse_size(gui_size, "--size");
            options.width = w, options.height = h;
        }
        if (argc == 1) {
            // First start: what the tool is for, not an unlit preview. Method A's cache on the
            // built-in scene's animation, playing.
            options.method = "cache";
            options.play = true;
            options.hint =
                "Method A: a frequency-chosen subset of pixels shaded, radiance points reused "
                "across frames from an object-space cache. D: each entry's reuse / discard reason; "
                "click a pixel: why; Space: pause; the Help menu: the rest.";
        }
        if (headless) return freqlab::ui::run_headless(options);
        const char* display = std::getenv("DISPLAY");
        if (!display || !*display) return headless_fallback(gui_scene, gui_frame);
        return freqlab::ui::run_workbench(options);
#else
        std::fprintf(stderr, "freqlab was built without the UI (FREQLAB_BUILD_UI=OFF)\n");
        return headless_fallback(gui_scene, gui_frame);
#endif
    } catch (const freqlab::Error& e) {
        // One rank's error ends every rank (none waits for it), naming the rank and its work.
        if (cluster.distributed()) cluster.abort(1, std::string("error: ") + e.what());
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    } catch (const freqlab::Cancelled&) {
        if (cluster.distributed()) cluster.abort(130, "cancelled");
        std::fprintf(stderr,
                     "\ncancelled: the files written before are complete; nothing "
                     "half-written was left\n");
        return 130;
    } catch (const std::exception& e) {
        if (cluster.distributed()) cluster.abort(1, std::string("error: ") + e.what());
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}
