// A recorded run's frames (issue "The timeline as a recorded run": recorded runs). Every frame a
// run renders is kept in its folder of the run store (render/frame_checkpoint.h), and a small
// in-memory set of decoded frames, capped in bytes, holds the ones looked at last: scrubbing
// reads a frame back instead of rendering it, and reopening the run later is instant.
//
// | file                    | content                                                       |
// |-------------------------|---------------------------------------------------------------|
// | frames/frame_NNNN.bin   | "FLFR", version, the run's key (JSON), frame, time, layers    |
// |                         | (image/layer_codec.h: exact), stats, cache records, reused    |
// |                         | samples' positions; the size of all before it                 |
// |                         | (records: the entries landing on the image, what the          |
// |                         | inspector lists)                                              |
// | frames/frame_NNNN.json  | the frame's stats, written after the .bin: a frame is         |
// |                         | recorded when its .json exists (the timeline's strip reads    |
// |                         | these alone)                                                  |
//
// No checksum over the payload: hashing 55 MB from memory took 25-30 ms of a 44 ms read (perf),
// the one cost a jump of the timeline pays; files are written atomically by this process, every
// length and enum is checked, and a truncated file is refused by its size.
// Layers are stored raw, not as EXR: reading 37 channels at 640 x 360 back took 205-350 ms
// through OpenImageIO (uncompressed or ZIP) where the encoded bytes read in a few ms; Export
// writes the EXR of any frame shown. Not stored: the cache snapshot (the cache before the
// frame, a copy of the whole cache): a frame read back lists its entries' recorded tests
// without their stored tuples. A jump reads only the layers on screen first (~2.8 MB: 34 ms
// from the jump to the frame on screen, p50 of 100 jumps at 640 x 360 where the whole frame
// took 49 ms, 40 ms with the page cache dropped where it took 54-64) and the rest in the
// background (render/background_frame_reader.h).
//
// | setting                  | default | meaning                                          |
// |--------------------------|---------|--------------------------------------------------|
// | $FREQLAB_FRAME_MEMORY_MB | 256     | decoded frames kept in memory (least recently    |
// |                          |         | used dropped first; the run store keeps them):   |
// |                          |         | 4 frames of method cache at 640 x 360. Memory    |
// |                          |         | first touched costs ~10 us a page here: every    |
// |                          |         | frame decoded before the cap is reached took     |
// |                          |         | 130-220 ms, after it (freed memory reused,       |
// |                          |         | base/heap_reuse.h) 40-50 ms. A random jump finds |
// |                          |         | its frame in memory rarely whatever the cap.     |
// | $FREQLAB_RUN_STORE_MB    | 16384   | the run store on disk (all runs): 120 frames of  |
// |                          |         | method cache at 640 x 360 take ~4.5 GB           |
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/frame_renderer.h"

namespace freqlab {

constexpr uint32_t kRecordedFrameVersion = 2;

// DIR/frames/frame_NNNN.bin (and .json beside it).
std::filesystem::path recorded_frame_path(const std::filesystem::path& dir, int frame);

// Writes both files atomically (a reader never sees half a frame).
void write_recorded_frame(const std::filesystem::path& dir, const nlohmann::json& key,
                          const FrameResult& result);
// Throws Error naming the file and field: damaged, truncated, another version, another run.
FrameResult read_recorded_frame(const std::filesystem::path& dir, const nlohmann::json& key,
                                int frame);
// The frame with only the layers named (those it has) and its stats: `partial`, the others in
// `unread_layers`. A timeline jump reads this first (the layer on screen: ~2.8 MB of a 55 MB
// frame at 640 x 360), then the whole frame in the background (BackgroundFrameReader).
FrameResult read_recorded_frame(const std::filesystem::path& dir, const nlohmann::json& key,
                                int frame, const std::vector<std::string>& only_layers);
// Marks a recorded frame used now (its .json's time): trim_run_store drops the least recently
// used frames first.
void touch_recorded_frame(const std::filesystem::path& dir, int frame);
// Every recorded frame's stats (frames whose .json is unreadable are left out).
std::map<int, nlohmann::json> recorded_frame_stats(const std::filesystem::path& dir);

struct RunStoreTrim {
    int runs = 0, frames = 0;  // removed
};
// Keeps the run store (the folder holding `keep`) under $FREQLAB_RUN_STORE_MB (default 16384):
// removes the least recently used runs other than `keep`, then `keep`'s least recently used
// frames with their shading memo points (render/shading_memo_store.h; never its checkpoints:
// they are how its frames come back), until the rest fit.
RunStoreTrim trim_run_store(const std::filesystem::path& keep);

// What a decoded frame holds in memory: layers, records, positions and cache snapshot.
size_t frame_result_bytes(const FrameResult& result);

// $FREQLAB_FRAME_MEMORY_MB in bytes (default 256 MB); throws Error naming the variable when it
// is not a number >= 0.
size_t decoded_frames_cap();

// Decoded frames in memory, least recently used dropped first past the cap. The frame kept
// last always stays (a cap below one frame still shows it); frames handed out stay alive with
// their holders after they are dropped.
class DecodedFrames {
  public:
    explicit DecodedFrames(size_t cap_bytes) : cap_(cap_bytes) {}
    std::shared_ptr<FrameResult> find(int frame);  // null when not in memory; marks it used
    bool contains(int frame) const { return frames_.count(frame) > 0; }
    void keep(std::shared_ptr<FrameResult> result);  // replaces a frame of the same number
    void clear();
    size_t bytes() const { return bytes_; }
    size_t cap() const { return cap_; }
    std::vector<int> frames() const;

  private:
    struct Held {
        std::shared_ptr<FrameResult> result;
        size_t bytes = 0;
        uint64_t used = 0;
    };
    std::map<int, Held> frames_;
    size_t cap_ = 0, bytes_ = 0;
    uint64_t clock_ = 0;
};

}  // namespace freqlab
