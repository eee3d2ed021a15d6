// Whole recorded frames read on a thread of their own (issue "The timeline as a recorded run",
// acceptance 1: any frame in 50 ms). A timeline jump shows the frame's on-screen layer first
// (read_recorded_frame with only that layer: ~2.8 MB of a 55 MB frame at 640 x 360) and asks
// this reader for the whole frame, which the workbench swaps in when it is read.
//
// | choice                          | why                                                   |
// |---------------------------------|-------------------------------------------------------|
// | one read at a time              | a whole frame is 55 MB: reads side by side only share |
// |                                 | the disk and the 2 cores with the UI                  |
// | a new request replaces a queued | a scrub asks for many frames; the one it stops on is  |
// | one (not one being read)        | the one wanted                                        |
// | one thread for the reader's life| it keeps its heap arena, whose freed memory the next  |
// |                                 | frame reuses (base/heap_reuse.h: a fresh page ~10 us) |
#pragma once

#include <condition_variable>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/frame_renderer.h"

namespace freqlab {

class BackgroundFrameReader {
  public:
    struct Read {
        std::filesystem::path dir;  // the run it belongs to
        int frame = -1;
        std::shared_ptr<FrameResult> result;  // null when the read failed
        std::string error;                    // why (Error's text naming file and field)
    };

    BackgroundFrameReader();
    ~BackgroundFrameReader();  // waits for the read in flight (at most one frame)
    BackgroundFrameReader(const BackgroundFrameReader&) = delete;
    BackgroundFrameReader& operator=(const BackgroundFrameReader&) = delete;

    void request(const std::filesystem::path& dir, const nlohmann::json& key, int frame);
    std::vector<Read> take();  // the reads finished since the last call, oldest first
    bool idle() const;         // nothing queued, nothing being read, nothing to take
    bool wanted(const std::filesystem::path& dir, int frame) const;  // queued or being read
    void wait_until_idle_or_done();  // blocks until something can be taken or nothing is left

  private:
    struct Request {
        std::filesystem::path dir;
        nlohmann::json key;
        int frame = -1;
    };
    void run();

    mutable std::mutex mutex_;
    std::condition_variable wake_, finished_;
    std::optional<Request> queued_, reading_;
    std::vector<Read> done_;
    bool stop_ = false;
    std::thread thread_;  // last: started once the members it uses exist
};

}  // namespace freqlab
