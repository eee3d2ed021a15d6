#include "base/job.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "base/error.h"

namespace freqlab {

Progress::Progress() : Progress([] { return Clock::now(); }) {}

Progress::Progress(std::function<Clock::time_point()> clock)
    : clock_(std::move(clock)), start_(clock_()) {}

void Progress::set_expected_stages(std::vector<StageTime> plan) {
    std::lock_guard<std::mutex> lock(mutex_);
    plan_ = std::move(plan);
}

std::vector<StageTime> Progress::stage_times() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<StageTime> times;
    const Clock::time_point now = clock_();
    for (size_t i = 0; i < begun_.size(); ++i) {
        const Clock::time_point end = i + 1 < begun_.size() ? begun_[i + 1].second : now;
        times.push_back(
            {begun_[i].first, std::chrono::duration<double>(end - begun_[i].second).count()});
    }
    return times;
}

double Progress::planned_seconds(size_t stage) const {
    if (stage < plan_.size()) return plan_[stage].seconds;
    double sum = 0.0;
    for (const StageTime& t : plan_) sum += t.seconds;
    return plan_.empty() ? 0.0 : sum / double(plan_.size());
}

void Progress::set_stage_count(int n) {
    std::lock_guard<std::mutex> lock(mutex_);
    stages_total_ = std::max(1, n);
}

void Progress::begin_stage(const std::string& name, long units) {
    std::lock_guard<std::mutex> lock(mutex_);
    stage_ = name;
    stage_index_ = std::min(stage_index_ + 1, stages_total_ - 1);
    units_total_ = std::max(1L, units);
    units_done_.store(0);
    begun_.emplace_back(name, clock_());
}

void Progress::advance(long units) {
    units_done_.fetch_add(units, std::memory_order_relaxed);
}

namespace {
std::atomic<bool> process_cancel{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler stores it");
}  // namespace

void request_process_cancel() {
    process_cancel.store(true, std::memory_order_relaxed);
}
bool process_cancel_requested() {
    return process_cancel.load(std::memory_order_relaxed);
}
void process_checkpoint() {
    if (process_cancel_requested()) throw Cancelled();
}

void Progress::checkpoint() const {
    if (cancel_.load(std::memory_order_relaxed)) throw Cancelled();
    process_checkpoint();
}

ProgressSnapshot Progress::snapshot() const {
    std::lock_guard<std::mutex> lock(mutex_);
    ProgressSnapshot s;
    s.stage = stage_;
    const double within = std::clamp(double(units_done_.load()) / double(units_total_), 0.0, 1.0);
    const int index = std::max(stage_index_, 0);
    s.fraction = done_ ? 1.0 : (index + within) / stages_total_;
    const Clock::time_point now = clock_();
    s.elapsed_s = std::chrono::duration<double>(now - start_).count();
    s.eta_s = s.fraction > 0.01 ? s.elapsed_s * (1.0 - s.fraction) / s.fraction : -1.0;
    if (!plan_.empty() && !done_) {
        // Stages by position in the plan (a frame's stages come in the same order).
        const size_t current = begun_.empty() ? 0 : begun_.size() - 1;
        const size_t stages = std::max(plan_.size(), begun_.size());
        double total = 0.0, before = 0.0, later = 0.0;
        for (size_t i = 0; i < stages; ++i) {
            const double t = planned_seconds(i);
            total += t;
            if (i < current) before += t;
            if (i > current) later += t;
        }
        const double expected = planned_seconds(current);
        double left = expected;
        if (!begun_.empty()) {
            const double spent = std::chrono::duration<double>(now - begun_.back().second).count();
            left = std::min(expected * (1.0 - within), std::max(0.0, expected - spent));
        }
        s.eta_s = later + left;
        s.fraction = total > 0.0 ? std::clamp((before + expected - left) / total, 0.0, 1.0) : 0.0;
    }
    s.done = done_;
    s.cancelled = cancelled_;
    s.error = error_;
    return s;
}

void Progress::finish(const std::string& error, bool cancelled) {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
    cancelled_ = cancelled;
    error_ = error;
}

Job::Job(std::function<void(Progress&)> body) {
    thread_ = std::thread([this, body = std::move(body)] {
        try {
            body(progress_);
            progress_.finish("", false);
        } catch (const Cancelled&) {
            progress_.finish("", true);
        } catch (const std::exception& e) {
            progress_.finish(e.what(), false);
        }
    });
}

Job::~Job() {
    cancel();
    wait();
}

void Job::wait() {
    if (thread_.joinable()) thread_.join();
}

bool stderr_is_terminal() {
    return isatty(STDERR_FILENO) == 1;
}

TerminalProgressBar::TerminalProgressBar(const Progress& progress, bool enabled)
    : progress_(progress), enabled_(enabled) {
    if (enabled_) thread_ = std::thread([this] { loop(); });
}

TerminalProgressBar::~TerminalProgressBar() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
    if (enabled_) std::fprintf(stderr, "\r\033[K");
}

void TerminalProgressBar::loop() {
    while (!stop_.load()) {
        const ProgressSnapshot s = progress_.snapshot();
        const int width = 30;
        const int filled = int(s.fraction * width + 0.5);
        std::string bar(filled, '#');
        bar.resize(width, '.');
        char eta[32] = "  --";
        if (s.eta_s >= 0) std::snprintf(eta, sizeof eta, "%5.1fs", s.eta_s);
        std::fprintf(stderr, "\r\033[K[%s] %5.1f%% %-24.24s ETA %s", bar.c_str(),
                     100.0 * s.fraction, s.stage.c_str(), eta);
        std::fflush(stderr);
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
}

}  // namespace freqlab
