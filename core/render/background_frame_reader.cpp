#include "render/background_frame_reader.h"

#include "base/error.h"
#include "render/frame_store.h"

namespace freqlab {

BackgroundFrameReader::BackgroundFrameReader() : thread_([this] { run(); }) {}

BackgroundFrameReader::~BackgroundFrameReader() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
        queued_.reset();
    }
    wake_.notify_all();
    thread_.join();
}

void BackgroundFrameReader::request(const std::filesystem::path& dir, const nlohmann::json& key,
                                    int frame) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (reading_ && reading_->dir == dir && reading_->frame == frame) {
            queued_.reset();  // already on its way
            return;
        }
        queued_ = Request{dir, key, frame};
    }
    wake_.notify_all();
}

std::vector<BackgroundFrameReader::Read> BackgroundFrameReader::take() {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::exchange(done_, {});
}

bool BackgroundFrameReader::idle() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return !queued_ && !reading_ && done_.empty();
}

bool BackgroundFrameReader::wanted(const std::filesystem::path& dir, int frame) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto is = [&](const std::optional<Request>& r) {
        return r && r->dir == dir && r->frame == frame;
    };
    return is(queued_) || is(reading_);
}

void BackgroundFrameReader::wait_until_idle_or_done() {
    std::unique_lock<std::mutex> lock(mutex_);
    finished_.wait(lock, [&] { return !done_.empty() || (!queued_ && !reading_); });
}

void BackgroundFrameReader::run() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
        wake_.wait(lock, [&] { return stop_ || queued_.has_value(); });
        if (stop_) return;
        reading_ = std::move(queued_);
        queued_.reset();
        const Request r = *reading_;
        lock.unlock();
        Read read{r.dir, r.frame, nullptr, ""};
        try {
            read.result = std::make_shared<FrameResult>(read_recorded_frame(r.dir, r.key, r.frame));
        } catch (const Error& e) {
            read.error = e.what();
        } catch (const std::exception& e) {  // e.g. bad_alloc: reported, not lost with the thread
            read.error = std::string("reading frame ") + std::to_string(r.frame) + ": " + e.what();
        }
        lock.lock();
        reading_.reset();
        done_.push_back(std::move(read));
        finished_.notify_all();
    }
}

}  // namespace freqlab
