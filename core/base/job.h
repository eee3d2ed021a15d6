// Cancellable jobs with progress (DESIGN.md "Jobs"). A job body receives a Progress it
// reports stages and fractions to; observers (the terminal bar, the GUI status bar) poll
// snapshot() from any thread. Cancellation is cooperative: the body calls checkpoint(),
// which throws Cancelled once cancel() was requested.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace freqlab {

struct ProgressSnapshot {
    std::string stage;
    double fraction = 0.0;  // of the whole job, in [0, 1]
    double elapsed_s = 0.0;
    double eta_s = -1.0;  // < 0 while unknown
    bool done = false;
    bool cancelled = false;
    std::string error;  // non-empty when the body threw
};

// Process-wide cancellation: the CLI's SIGINT / SIGTERM handler raises it (async-signal-safe:
// one lock-free atomic store), and every checkpoint (Progress::checkpoint, or
// process_checkpoint() where a body runs without a Progress) then throws Cancelled. Outputs are
// written atomically (base/file_io.h), so a cancelled command leaves complete files only.
void request_process_cancel();
bool process_cancel_requested();
void process_checkpoint();  // throws Cancelled once request_process_cancel() was called

// How long a stage took (Progress::stage_times), or is expected to take (set_expected_stages).
struct StageTime {
    std::string name;
    double seconds = 0.0;
};

class Progress {
  public:
    using Clock = std::chrono::steady_clock;
    Progress();
    explicit Progress(std::function<Clock::time_point()> clock);  // tests: a clock of their own
    // Starts a named stage; `units` is how many advance() calls complete it. Fractions of the
    // whole job are the mean over `stages_total` stages declared with set_stage_count().
    void set_stage_count(int n);
    // The stages a job like this one took (the workbench's previous frame): fractions weigh
    // each stage by its time, and the ETA is the plan's time left, which only falls: within a
    // stage the smaller of its time left by units done and by time spent (a stage of one unit
    // still counts down; one running over its time waits at 0 instead of growing), at a stage's
    // start what the stage before had left drops out. A stage not in the plan weighs the plan's
    // mean. Without a plan: stages weigh the same and ETA = elapsed (1 - f) / f.
    void set_expected_stages(std::vector<StageTime> plan);
    std::vector<StageTime> stage_times() const;  // the stages so far, the current one until now
    void begin_stage(const std::string& name, long units);
    void advance(long units = 1);
    void checkpoint() const;  // throws Cancelled when cancel() was requested
    void cancel() { cancel_.store(true); }
    bool cancel_requested() const { return cancel_.load() || process_cancel_requested(); }
    ProgressSnapshot snapshot() const;
    void finish(const std::string& error, bool cancelled);

  private:
    double planned_seconds(size_t stage) const;  // mutex_ held
    std::function<Clock::time_point()> clock_;
    mutable std::mutex mutex_;
    std::string stage_;
    int stages_total_ = 1;
    int stage_index_ = -1;
    std::vector<StageTime> plan_;
    std::vector<std::pair<std::string, Clock::time_point>> begun_;  // every stage's start
    std::atomic<long> units_done_{0};
    long units_total_ = 1;
    std::atomic<bool> cancel_{false};
    bool done_ = false, cancelled_ = false;
    std::string error_;
    Clock::time_point start_;
};

// A job running its body on a background thread (the GUI's route). The CLI runs bodies
// synchronously on its own thread with a TerminalProgressBar watching.
class Job {
  public:
    explicit Job(std::function<void(Progress&)> body);
    ~Job();  // cancels and joins
    Job(const Job&) = delete;
    Job& operator=(const Job&) = delete;

    void cancel() { progress_.cancel(); }
    ProgressSnapshot snapshot() const { return progress_.snapshot(); }
    bool done() const { return progress_.snapshot().done; }
    void wait();

  private:
    Progress progress_;
    std::thread thread_;
};

// Draws a one-line progress bar on stderr while a body runs; silent when `enabled` is false
// (--quiet, or stderr is not a TTY).
class TerminalProgressBar {
  public:
    TerminalProgressBar(const Progress& progress, bool enabled);
    ~TerminalProgressBar();

  private:
    void loop();
    const Progress& progress_;
    bool enabled_;
    std::atomic<bool> stop_{false};
    std::thread thread_;
};

bool stderr_is_terminal();

}  // namespace freqlab
