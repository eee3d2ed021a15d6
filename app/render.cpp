// `freqlab render`: frames of one method to DIR/frame_NNNN.exr/.png and DIR/stats.json, in one
// process or split (app/cluster.h): under `mpirun -np N` rank r renders frames first + r,
// first + r + N, ... and sends each to rank 0, the only writer (a second thread there writes
// them while its own frames render); with `--part I/N` one Slurm array task renders its share
// into its own folder for `freqlab merge`. Method cache renders in order, so it is split into
// contiguous chunks, each warmed over `--warm-frames` frames before the first one it keeps
// (the one run where the split changes pixels: every chunk but the first starts a cache afresh).
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <mutex>
#include <regex>
#include <thread>

#include "base/error.h"
#include "base/file_io.h"
#include "base/stopwatch.h"
#include "cluster.h"
#include "commands.h"
#include "image/colormap.h"
#include "image/image_io.h"
#include "image/layer_codec.h"
#include "render/frame_checkpoint.h"
#include "render/frame_renderer.h"
#include "scene/provenance.h"
#include "scene/scene_loader.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kFrameTag = 11, kSummaryTag = 12;

std::pair<int, int> parse_pixel(const std::string& text, int w, int h) {
    std::smatch m;
    if (!std::regex_match(text, m, std::regex(R"((\d+),(\d+))")))
        throw Error("--debug-pixel", text, "expected X,Y");
    const int x = parse_count(m[1], "--debug-pixel", text),
              y = parse_count(m[2], "--debug-pixel", text);
    if (x >= w || y >= h)
        throw Error("--debug-pixel", text,
                    "outside the image (" + std::to_string(w) + "x" + std::to_string(h) + ")");
    return {x, y};
}

void print_debug_pixel(const FrameResult& r, int x, int y) {
    std::printf("debug pixel (%d, %d), frame %d, t = %.4f s\n", x, y, r.frame, r.time_s);
    for (const Layer& l : r.layers.layers()) {
        std::printf("  %-10s [%s]", l.name.c_str(), to_string(l.kind));
        for (int c = 0; c < l.channels; ++c) std::printf(" %.6g", l.at(r.layers.width(), x, y, c));
        if (l.kind == LayerKind::Categorical) {
            const int v = int(l.at(r.layers.width(), x, y));
            if (v >= 0 && v < int(l.legend.size())) std::printf("  (%s)", l.legend[v].c_str());
        }
        std::printf("\n");
    }
}

// What a process renders: the frames it keeps, and (method cache) the frame it starts at.
struct FramePlan {
    std::vector<int> keep;
    int start = 0;  // first frame rendered (< keep.front() when warming a cache)
};

FramePlan plan_frames(int first, int last, WorkPart part, bool stateful, int warm_frames) {
    FramePlan plan;
    if (!stateful) {
        plan.keep = round_robin_items(first, last, part);
        plan.start = plan.keep.empty() ? first : plan.keep.front();
        return plan;
    }
    const auto [a, b] = contiguous_items(first, last, part);
    for (int f = a; f < b; ++f) plan.keep.push_back(f);
    plan.start = std::max(first, a - warm_frames);
    return plan;
}

// One rendered frame as the writer needs it.
struct RenderedFrame {
    int frame = 0;
    float time_s = 0.0f;
    json stats;
    LayerSet layers;
};

std::string encode_frame(const RenderedFrame& f) {
    ByteWriter w;
    w.put<int32_t>(f.frame);
    w.put<float>(f.time_s);
    w.put_string(f.stats.dump());
    w.put_string(encode_layers(f.layers));
    return std::move(w.bytes());
}

RenderedFrame decode_frame(const std::string& bytes, int rank) {
    const std::string source = "MPI message from rank " + std::to_string(rank);
    ByteReader r(bytes, source);
    RenderedFrame f;
    f.frame = r.get<int32_t>();
    f.time_s = r.get<float>();
    f.stats = json::parse(r.get_string());
    f.layers = decode_layers(r.get_string(), source);
    return f;
}

// The files of one frame, exactly as a one-process render writes them.
class FrameWriter {
  public:
    FrameWriter(const RenderArgs& args, const Scene& scene, const RenderConfig& config,
                const SettingsGroup& settings)
        : args_(args),
          config_(config),
          provenance_(
              output_provenance(scene, args.method, settings.to_json(), long(config.frame.seed))) {}

    void write(const RenderedFrame& f) {
        if (f.stats.value("nonfinite", 0L) > 0)
            std::fprintf(stderr, "\nwarning: frame %d has %ld non-finite values (shown magenta)\n",
                         f.frame, f.stats["nonfinite"].get<long>());
        char name[32];
        std::snprintf(name, sizeof name, "frame_%04d", f.frame);
        json provenance = provenance_;
        provenance["frame"] = f.frame;
        provenance["time_s"] = f.time_s;
        write_exr(fs::path(args_.out) / (std::string(name) + ".exr"), f.layers, provenance);
        DisplayParams display;
        display.exposure_ev = config_.frame.exposure;
        write_png(fs::path(args_.out) / (std::string(name) + ".png"), f.layers.width(),
                  f.layers.height(), layer_to_rgb8(f.layers, f.layers.get("color"), display),
                  provenance);
        std::lock_guard<std::mutex> lock(mutex_);
        frames_.push_back(f.stats);
    }
    // Per-frame stats in frame order (parts and ranks finish out of order).
    json frames() const {
        std::vector<json> sorted = frames_;
        std::sort(sorted.begin(), sorted.end(), [](const json& a, const json& b) {
            return a["frame"].get<int>() < b["frame"].get<int>();
        });
        return json(sorted);
    }

  private:
    const RenderArgs& args_;
    const RenderConfig& config_;
    json provenance_;
    std::mutex mutex_;
    std::vector<json> frames_;
};

// Rank 0's second thread: the other ranks' frames, written as they arrive.
class FrameReceiver {
  public:
    FrameReceiver(FrameWriter& writer, int expected)
        : thread_([this, &writer, expected] {
              try {
                  for (int i = 0; i < expected; ++i) {
                      auto [rank, bytes] = Cluster::world().receive_any(kFrameTag);
                      writer.write(decode_frame(bytes, rank));
                  }
              } catch (...) {
                  error_ = std::current_exception();
              }
          }) {}
    void join() {
        thread_.join();
        if (error_) std::rethrow_exception(error_);
    }

  private:
    std::exception_ptr error_;
    std::thread thread_;
};

// --checkpoint-every and --resume-from: a stateful method, rendered by one process.
void check_checkpoint_args(const RenderArgs& args, const RenderConfig& config,
                           const WorkPart& part) {
    if (args.checkpoint_every < 0)
        throw Error("--checkpoint-every", std::to_string(args.checkpoint_every),
                    "expected >= 0 (0: no checkpoints)");
    auto stateful_and_whole = [&](const char* flag, const std::string& value) {
        if (!config.needs_previous_frames())
            throw Error(flag, value,
                        "method " + args.method +
                            " keeps nothing across frames (checkpoints are method cache's)");
        if (!part.whole())
            throw Error(flag, value, "one process renders the run: not with --part or mpirun");
    };
    if (args.checkpoint_every > 0)
        stateful_and_whole("--checkpoint-every", std::to_string(args.checkpoint_every));
    if (!args.resume_from.empty()) stateful_and_whole("--resume-from", args.resume_from);
    if (!args.resume_from.empty() && !std::filesystem::is_directory(args.resume_from))
        throw Error("--resume-from", args.resume_from,
                    "expected the output directory of a run with --checkpoint-every");
}

}  // namespace

int run_render(const RenderArgs& args) {
    RenderConfig config;
    config.method = parse_render_method(args.method);
    SettingsGroup settings = config.settings_group();
    for (const std::string& s : args.sets) settings.apply_assignment(s);
    if (!args.size.empty()) {
        const auto [w, h] = parse_size(args.size, "--size");
        config.frame.width = w, config.frame.height = h;
    }
    if (args.spp > 0) {
        // What --spp sets is the method's (render/method.h): method A's points / sparse / cache
        // choose every radiance point's sample count themselves and refuse it.
        const RenderMethodInfo& info = render_method_info(config.method);
        if (info.spp_setting.empty())
            throw Error(
                "--spp", std::to_string(args.spp),
                "method " + args.method + " " +
                    (info.spp_refusal.empty() ? "takes no sample count" : info.spp_refusal));
        const std::string& key = info.spp_setting;
        settings.apply_assignment(key + "=" + std::to_string(args.spp), "--spp");
    }
    if (args.seed >= 0)
        settings.apply_assignment("frame.seed=" + std::to_string(args.seed), "--seed");
    if (args.out.empty()) throw Error("--out", "", "expected an output directory");

    // The split: MPI ranks, or one Slurm array task's part.
    Cluster& cluster = Cluster::world();
    WorkPart part = cluster.part();
    if (!args.part.empty()) {
        if (cluster.distributed())
            throw Error("--part", args.part, "not under mpirun: the ranks split the work there");
        part = parse_work_part(args.part, "--part");
    }
    if (!part.whole() && !args.debug_pixel.empty())
        throw Error("--debug-pixel", args.debug_pixel,
                    "traces one process's renderer: run it without mpirun / --part");
    if (args.warm_frames < 0)
        throw Error("--warm-frames", std::to_string(args.warm_frames), "expected >= 0");
    check_checkpoint_args(args, config, part);
    // What is reported is what runs: on the command line, checkpoints only when asked for.
    if (config.needs_previous_frames())
        settings.apply_assignment("cache.checkpoint_every=" + std::to_string(args.checkpoint_every),
                                  "--checkpoint-every");

    // Everything that can be wrong with the input is checked before any output exists.
    const Scene scene = load_scene(args.scene);
    if (cluster.rank() == 0) print_load_notes(scene);
    const auto [first, last] = parse_frame_range(args.frames, scene.frame_count);
    std::pair<int, int> debug{-1, -1};
    if (!args.debug_pixel.empty())
        debug = parse_pixel(args.debug_pixel, config.frame.width, config.frame.height);
    FramePlan plan =
        plan_frames(first, last, part, config.needs_previous_frames(), args.warm_frames);
    const json checkpoint_key = frame_checkpoint_key(
        output_provenance(scene, args.method, settings.to_json(), long(config.frame.seed)));
    // The state before the first frame: the newest checkpoint at or before it, or a cold
    // start at frame 0 (what the sequential run had there).
    FrameCheckpoint resumed;
    if (!args.resume_from.empty()) {
        const int at = latest_frame_checkpoint(args.resume_from, first);
        if (at > 0)
            resumed =
                read_frame_checkpoint(frame_checkpoint_path(args.resume_from, at), checkpoint_key);
        plan.start = std::max(0, at);
    }
    cluster.set_work("frames " + describe_items(plan.keep));

    std::unique_ptr<tbb::global_control> limit;
    if (args.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      size_t(args.threads));
    EmbreeDevice device(args.threads);
    FrameRenderer renderer(scene, config, device);
    renderer.keep_cache_details(!args.debug_pixel.empty());  // the trace lists entry tuples
    if (!resumed.state.empty())
        renderer.restore_state(resumed.state,
                               frame_checkpoint_path(args.resume_from, resumed.frame).string());

    const bool writer = cluster.rank() == 0;
    if (writer) {
        std::error_code ec;
        fs::create_directories(args.out, ec);
        if (ec || !fs::is_directory(args.out))
            throw Error(args.out, "--out", "cannot create the output directory: " + ec.message());
    }
    FrameWriter frames(args, scene, config, settings);
    // Progress of this process's own frames (warm-up included); rank 0's bar shows its own.
    const int end = plan.keep.empty() ? plan.start : plan.keep.back() + 1;
    Progress progress;
    progress.set_stage_count(
        std::max(1, config.needs_previous_frames() ? end - plan.start : int(plan.keep.size())));
    const auto t0 = Clock::now();
    {
        TerminalProgressBar bar(progress, writer && !args.quiet && stderr_is_terminal());
        std::unique_ptr<FrameReceiver> receiver;
        if (writer && cluster.distributed())
            receiver =
                std::make_unique<FrameReceiver>(frames, (last - first) - int(plan.keep.size()));
        try {
            auto checkpoint = [&](int rendered) {
                const int every =
                    config.needs_previous_frames() ? config.cache.checkpoint_every : 0;
                if (every > 0 && (rendered + 1) % every == 0)
                    write_frame_checkpoint(frame_checkpoint_path(args.out, rendered + 1),
                                           checkpoint_key, rendered + 1, renderer.save_state());
            };
            for (int f = plan.start; f < end; ++f) {
                if (!std::binary_search(plan.keep.begin(), plan.keep.end(), f)) {
                    if (config.needs_previous_frames()) {
                        renderer.render(f, progress);  // warm-up
                        checkpoint(f);
                    }
                    continue;
                }
                FrameResult r = renderer.render(f, progress);
                checkpoint(f);
                RenderedFrame out{f, r.time_s, r.stats, std::move(r.layers)};
                if (writer)
                    frames.write(out);
                else
                    cluster.send(0, kFrameTag, encode_frame(out));
                if (debug.first >= 0) {
                    r.layers = std::move(out.layers);
                    print_debug_pixel(r, debug.first, debug.second);
                    if (config.method != RenderMethod::GBuffer)
                        for (const std::string& line :
                             renderer.trace_pixel(r, debug.first, debug.second))
                            std::printf("  %s\n", line.c_str());
                }
            }
        } catch (const std::exception& e) {
            // A receiving thread may be blocked in MPI: end every rank from here.
            if (cluster.distributed())
                cluster.abort(dynamic_cast<const Cancelled*>(&e) ? 130 : 1,
                              std::string("error: ") + e.what());
            throw;
        }
        if (receiver) receiver->join();
    }
    const double own_ms = ms_since(t0);
    json stats = {{"scene", args.scene},
                  {"method", args.method},
                  {"threads", args.threads},
                  {"settings", settings.to_json()},
                  {"load_notes", scene.load_notes},
                  {"frames", frames.frames()}};
    if (cluster.distributed()) {
        // Per-rank times (ms from the start of rendering to the last frame sent) and balance.
        const json mine = {{"rank", cluster.rank()}, {"frames", plan.keep}, {"time_ms", own_ms}};
        const std::vector<std::string> all = cluster.gather(mine.dump(), kSummaryTag);
        if (!writer) return 0;
        json ranks = json::array();
        double slowest = 0.0, sum = 0.0;
        for (const std::string& s : all) {
            ranks.push_back(json::parse(s));
            slowest = std::max(slowest, ranks.back()["time_ms"].get<double>());
            sum += ranks.back()["time_ms"].get<double>();
        }
        stats["ranks"] = ranks;
        stats["load_balance"] = slowest > 0.0 ? sum / (double(all.size()) * slowest) : 1.0;
    } else if (!part.whole()) {
        stats["part"] = {{"index", part.index},           {"count", part.count},
                         {"frames_range", {first, last}}, {"warm_frames", args.warm_frames},
                         {"frames_kept", plan.keep},      {"time_ms", own_ms}};
    }
    write_text_atomically(fs::path(args.out) / "stats.json", stats.dump(2) + "\n");
    if (!args.quiet)
        std::fprintf(stderr, "wrote %d frame(s) to %s\n",
                     cluster.distributed() ? last - first : int(plan.keep.size()),
                     args.out.c_str());
    return 0;
}

}  // namespace freqlab
