// `freqlab bench --study scrub` (issue "The timeline as a recorded run", acceptances 1 and 4):
// the workbench on an offscreen host (OSMesa), as a researcher scrubs.
//   1. record: the run's last frame is asked for; the workbench renders every frame in order
//      into the run store (skipped when the store holds them already: reported);
//   2. reopen: a new workbench on the same run, time to its first frame on screen;
//   3. jumps: --jumps random frames (seeded, never the frame shown), each timed from
//      set_frame() to the UI frame that draws it, GL finished (the workbench loop), and to the
//      UI frame after which every layer of it is in memory (the next jump waits for that);
//   4. a cache.* change (method cache, acceptance 3): at frame F = min(60, last) of a run just
//      rendered, cache.q_eps_x set to another value: time until frame F (rendered again from
//      frame 0) is on screen, by a workbench with its shading memo (render/shading_memo.h) and
//      by one without (FREQLAB_SHADING_MEMO_MB=0: the run from scratch, scene and Embree
//      already loaded); interleaved, --cache-change-trials times, into temporary run stores;
//      then a new workbench on the memo's run store (a later session: the points read from
//      the run store, render/shading_memo_store.h) and one more value.
// Reported: the jumps' p50 / p95 / max, how many were read from the run store, resident memory
// (now and peak) after recording and after the jumps, the decoded frames' bytes, the run
// store's size on disk; the cache change's times and their ratio.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <random>
#include <string>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/file_io.h"
#include "base/heap_reuse.h"
#include "osmesa_host.h"
#include "workbench.h"

#include <imgui_impl_opengl3.h>

namespace freqlab::ui {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// VmRSS / VmHWM of this process in MB (Linux; 0 elsewhere).
double status_mb(const char* field) {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind(field, 0) == 0) return std::atof(line.c_str() + std::strlen(field)) / 1024.0;
    return 0.0;
}

double percentile(std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    const double at = q * double(v.size() - 1);
    const size_t i = size_t(at);
    return i + 1 < v.size() ? v[i] + (at - double(i)) * (v[i + 1] - v[i]) : v[i];
}

uint64_t folder_bytes(const fs::path& dir) {
    uint64_t bytes = 0;
    std::error_code ec;
    for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
        if (it->is_regular_file()) bytes += it->file_size();
    return bytes;
}

// UI frames until the workbench shows the frame asked for (a render job waited for, not polled).
void until_shown(OsMesaHost& host, Workbench& wb) {
    for (int i = 0; i < 100000 && !wb.frame_shown(); ++i) {
        if (!wb.error().empty()) throw Error("bench --study scrub", "", wb.error());
        render_ui_frame(host, wb);
        host.end_frame();
        if (!wb.frame_shown()) wb.wait_for_render();
    }
    if (!wb.frame_shown()) throw Error("bench --study scrub", "", "the frame was never shown");
}

// Sets $name to value for this scope, then puts back what was there.
class ScopedEnvironment {
  public:
    ScopedEnvironment(const char* name, const std::string& value) : name_(name) {
        if (const char* old = std::getenv(name)) old_ = old;
        ::setenv(name, value.c_str(), 1);
    }
    ScopedEnvironment(const ScopedEnvironment&) = delete;
    ScopedEnvironment& operator=(const ScopedEnvironment&) = delete;
    ~ScopedEnvironment() {
        if (old_)
            ::setenv(name_, old_->c_str(), 1);
        else
            ::unsetenv(name_);
    }

  private:
    const char* name_;
    std::optional<std::string> old_;
};

// A temporary run store for this scope: $FREQLAB_RUN_STORE_DIR points at it while `use()`'s
// guard lives; the folder is removed at the end, also when the bench throws.
class TemporaryRunStore {
  public:
    explicit TemporaryRunStore(const std::string& name)
        : dir_(fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()))) {}
    TemporaryRunStore(const TemporaryRunStore&) = delete;
    TemporaryRunStore& operator=(const TemporaryRunStore&) = delete;
    ~TemporaryRunStore() {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }
    ScopedEnvironment use() const { return {"FREQLAB_RUN_STORE_DIR", dir_.string()}; }

  private:
    fs::path dir_;
};

// Step 4 (see the top). Two workbenches on the run, each with its own temporary run store, one
// with a shading memo and one without (FREQLAB_SHADING_MEMO_MB=0), both first render frames
// 0..F as recorded (the memo then holds what a researcher who rendered them has: nothing is
// read from the run store), then each trial sets another cache.q_eps_x on both, in turn.
json cache_change_study(OsMesaHost& host, const WorkbenchOptions& wo, int trials) {
    struct Arm {
        bool memo;
        TemporaryRunStore store;
        std::unique_ptr<Workbench> wb;
        std::vector<double> ms;
    };
    Arm arms[2] = {{true, TemporaryRunStore("freqlab_scrub_memo"), nullptr, {}},
                   {false, TemporaryRunStore("freqlab_scrub_scratch"), nullptr, {}}};
    int target = 0;
    for (Arm& arm : arms) {
        const ScopedEnvironment dir = arm.store.use();
        std::optional<ScopedEnvironment> cap;
        if (!arm.memo) cap.emplace("FREQLAB_SHADING_MEMO_MB", "0");
        WorkbenchOptions so = wo;
        so.frame = 0;
        arm.wb = std::make_unique<Workbench>(so);
        until_shown(host, *arm.wb);
        target = std::min(60, int(arm.wb->frame_count()) - 1);
        arm.wb->set_frame(target);
        until_shown(host, *arm.wb);
    }
    json values = json::array();
    for (int t = 0; t < trials; ++t) {
        const std::string value = "cache.q_eps_x=" + std::to_string(2e-4 * (t + 1));
        values.push_back(value);
        for (Arm& arm : arms) {
            const ScopedEnvironment dir = arm.store.use();
            const auto t0 = Clock::now();
            arm.wb->apply_setting(value);
            until_shown(host, *arm.wb);
            arm.ms.push_back(ms_since(t0));
            if (arm.wb->frame() != target) throw Error("bench --study scrub", "", "frame moved");
        }
        std::fprintf(stderr, "%s at frame %d: %.1f s with the memo, %.1f s from scratch\n",
                     value.c_str(), target, arms[0].ms.back() / 1000.0, arms[1].ms.back() / 1000.0);
    }
    // A later session: a new workbench on the memo arm's run store (nothing in memory), its
    // recorded frame shown, then another value: the points come from the run store's files.
    double reopened_ms = -1.0;
    if (trials > 0) {
        const ScopedEnvironment dir = arms[0].store.use();
        arms[0].wb.reset();
        WorkbenchOptions so = wo;
        so.frame = target;
        Workbench later(so);
        until_shown(host, later);
        const auto t0 = Clock::now();
        later.apply_setting("cache.q_eps_x=" + std::to_string(2e-4 * (trials + 1)));
        until_shown(host, later);
        reopened_ms = ms_since(t0);
        std::fprintf(stderr, "reopened in a new workbench, another value: %.1f s\n",
                     reopened_ms / 1000.0);
    }
    const double a = percentile(arms[0].ms, 0.5), b = percentile(arms[1].ms, 0.5);
    return {{"frame", target},
            {"reopened_with_memo_on_disk_ms", reopened_ms},
            {"values", values},
            {"with_memo_ms", arms[0].ms},
            {"from_scratch_ms", arms[1].ms},
            {"with_memo_median_ms", a},
            {"from_scratch_median_ms", b},
            {"ratio_of_medians", a / b}};
}

json memory_now(const Workbench& wb) {
    const Workbench::DecodedMemory m = wb.decoded_memory();
    return {{"resident_mb", status_mb("VmRSS:")},
            {"peak_resident_mb", status_mb("VmHWM:")},
            {"decoded_frames", m.frames.size()},
            {"decoded_frames_mb", double(m.bytes) / 1048576.0},
            {"decoded_frames_cap_mb", double(m.cap) / 1048576.0}};
}

}  // namespace

int run_scrub_bench(const ScrubBenchOptions& o) {
    if (o.jumps < 1) throw Error("--jumps", std::to_string(o.jumps), "expected at least 1");
    keep_freed_memory_for_reuse();  // as the workbench does
    ImGuiSession imgui;
    OsMesaHost host(o.workbench.width, o.workbench.height);
    ImGui_ImplOpenGL3_Init("#version 330");
    json report;
    {
        WorkbenchOptions wo = o.workbench;
        wo.show_timings = false;
        Workbench recorder(wo);
        if (!recorder.error().empty()) throw Error(wo.scene, "", recorder.error());
        const int frames = int(recorder.frame_count());
        const size_t before = recorder.recorded_frames().size();
        const auto t0 = Clock::now();
        recorder.set_frame(frames - 1);
        until_shown(host, recorder);
        const double record_ms = ms_since(t0);
        const fs::path run = recorder.run_directory();
        report["scene"] = wo.scene;
        report["method"] = recorder.method();
        report["frames"] = frames;
        report["record"] = {{"frames_already_recorded", before},
                            {"ms", record_ms},
                            {"memory", memory_now(recorder)},
                            {"run_store", run.string()},
                            {"run_store_mb", double(folder_bytes(run)) / 1048576.0}};
        std::fprintf(stderr, "recorded %d frames in %.1f s (%zu were in the run store)\n", frames,
                     record_ms / 1000.0, before);
    }
    WorkbenchOptions wo = o.workbench;
    wo.show_timings = false;
    wo.frame = 0;
    const auto t_open = Clock::now();
    Workbench wb(wo);
    until_shown(host, wb);
    const double reopen_ms = ms_since(t_open);
    const int frames = int(wb.frame_count());
    std::mt19937_64 rng(o.seed);
    std::vector<double> times, complete;
    int from_store = 0;
    for (int k = 0; k < o.jumps; ++k) {
        int target = wb.frame();
        while (target == wb.frame())
            target = int(std::uniform_int_distribution<int>(0, frames - 1)(rng));
        const std::vector<int> held = wb.decoded_memory().frames;
        from_store += std::find(held.begin(), held.end(), target) == held.end();
        const auto t0 = Clock::now();
        wb.set_frame(target);
        until_shown(host, wb);
        times.push_back(ms_since(t0));
        // A researcher looks at the frame before the next jump: its other layers arrive
        // meanwhile (render/background_frame_reader.h), timed from the jump too.
        for (int i = 0; i < 100000 && !wb.frame_complete() && wb.error().empty(); ++i) {
            render_ui_frame(host, wb);
            host.end_frame();
        }
        if (!wb.frame_complete())
            throw Error("bench --study scrub", "", "the frame never completed");
        complete.push_back(ms_since(t0));
    }
    report["reopen_ms"] = reopen_ms;
    report["jumps"] = {{"count", o.jumps},
                       {"seed", o.seed},
                       {"read_from_run_store", from_store},
                       {"p50_ms", percentile(times, 0.5)},
                       {"p95_ms", percentile(times, 0.95)},
                       {"max_ms", percentile(times, 1.0)},
                       {"ms", times},
                       {"whole_frame_p50_ms", percentile(complete, 0.5)},
                       {"whole_frame_p95_ms", percentile(complete, 0.95)},
                       {"whole_frame_ms", complete}};
    report["after_jumps"] = memory_now(wb);
    if (o.cache_change_trials > 0 && wb.method() == "cache")
        report["cache_change"] = cache_change_study(host, o.workbench, o.cache_change_trials);
    // A new frame (acceptance 5): frame 0 of a run not recorded (another cache.q_eps_x), from the
    // change to its first image on screen and to the frame; UI frames polled, not waited.
    wb.set_frame(0);
    until_shown(host, wb);
    std::vector<double> first, full;
    // Their frames go to a temporary run store: a second bench would find them recorded.
    const TemporaryRunStore new_store("freqlab_scrub_new");
    const ScopedEnvironment new_dir = new_store.use();
    for (int k = 0; k < 5; ++k) {
        const auto t0 = Clock::now();
        wb.apply_setting("cache.q_eps_x=" + std::to_string(2e-4 + 1e-5 * k));
        double first_ms = -1.0;
        while (!wb.frame_shown() && wb.error().empty()) {
            render_ui_frame(host, wb);
            host.end_frame();
            if (first_ms < 0.0 && (wb.first_image_shown() || wb.frame_shown()))
                first_ms = ms_since(t0);
        }
        first.push_back(first_ms);
        full.push_back(ms_since(t0));
    }
    report["new_frame"] = {{"first_image_ms", first},
                           {"frame_ms", full},
                           {"first_image_median_ms", percentile(first, 0.5)},
                           {"frame_median_ms", percentile(full, 0.5)}};
    ImGui_ImplOpenGL3_Shutdown();
    fs::create_directories(o.out);
    write_text_atomically(fs::path(o.out) / "bench_scrub.json", report.dump(2));
    std::printf(
        "scrub: %d jumps over %d recorded frames (%d read from the run store): p50 %.1f ms, "
        "p95 %.1f ms, max %.1f ms (every layer in memory: p50 %.1f ms, p95 %.1f ms); reopen "
        "%.0f ms; resident %.0f MB (peak %.0f MB), decoded frames %.0f MB; run store %.0f MB\n",
        o.jumps, frames, from_store, percentile(times, 0.5), percentile(times, 0.95),
        percentile(times, 1.0), percentile(complete, 0.5), percentile(complete, 0.95), reopen_ms,
        report["after_jumps"]["resident_mb"].get<double>(),
        report["after_jumps"]["peak_resident_mb"].get<double>(),
        report["after_jumps"]["decoded_frames_mb"].get<double>(),
        report["record"]["run_store_mb"].get<double>());
    std::printf("new frame (5 runs of cache.q_eps_x): first image median %.0f ms, frame %.0f ms\n",
                percentile(first, 0.5), percentile(full, 0.5));
    if (report.contains("cache_change")) {
        const json& c = report["cache_change"];
        std::printf(
            "cache.q_eps_x changed at frame %d (%zu trials): %.1f s with the shading memo, "
            "%.1f s from scratch (medians): ratio %.2f\n",
            c["frame"].get<int>(), c["values"].size(),
            c["with_memo_median_ms"].get<double>() / 1000.0,
            c["from_scratch_median_ms"].get<double>() / 1000.0,
            c["ratio_of_medians"].get<double>());
        std::printf(
            "a run reopened by a new workbench (the memo read from the run store): %.1f s\n",
            c["reopened_with_memo_on_disk_ms"].get<double>() / 1000.0);
    }
    std::printf("wrote %s\n", (fs::path(o.out) / "bench_scrub.json").c_str());
    return 0;
}

}  // namespace freqlab::ui
