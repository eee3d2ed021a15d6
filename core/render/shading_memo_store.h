// The shading memo on disk (render/shading_memo.h; issue "The timeline as a recorded run",
// acceptance 3): every run writes the radiance points its frames hold in the memo to its folder
// of the run store, so that a cache.* change of a run reopened in a later session recalls them
// as a change in the session that rendered it does.
//
// | file                      | content                                                      |
// |---------------------------|--------------------------------------------------------------|
// | memo/key.json             | the memo key (ShadingMemo::key_of: the run key without       |
// |                           | cache.*): runs sharing it share their points                 |
// | memo/frame_NNNN.bin       | "FLSM", version, memo key, frame, the frame's table (sorted  |
// |                           | pixel / pass keys, entries), FNV-1a of all before it         |
//
// Checksummed (unlike recorded frames): a damaged point would be recalled into an image
// silently, where a damaged frame shows. ~7 MB a frame at 640 x 360 (cache method, rotor).
// Written by the run that rendered the frame; the run store's cap (frame_store.h) counts them
// and drops a frame's points with the frame.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/shading_memo.h"

namespace freqlab {

constexpr uint32_t kMemoFrameVersion = 1;

std::filesystem::path memo_frame_path(const std::filesystem::path& run_dir, int frame);

// Writes the table atomically (and memo/key.json when missing).
void write_memo_frame(const std::filesystem::path& run_dir, const nlohmann::json& memo_key,
                      int frame, const ShadingMemo::FrameTable& table);
// Throws Error naming the file and field: damaged, another memo key, another version, keys not
// ascending, a pass or plan flag out of range.
std::shared_ptr<const ShadingMemo::FrameTable> read_memo_frame(const std::filesystem::path& file,
                                                               const nlohmann::json& memo_key,
                                                               int frame);

// The run folders beside `run_dir` (and itself) whose memo/key.json is `memo_key`, the most
// recently written first.
std::vector<std::filesystem::path> runs_sharing_memo(const std::filesystem::path& run_dir,
                                                     const nlohmann::json& memo_key);

// A loader for ShadingMemo::set_loader: frame f's table from the first of `runs` that holds a
// readable one (a damaged file is skipped: the points are shaded again).
std::function<std::shared_ptr<const ShadingMemo::FrameTable>(int)> memo_loader(
    std::vector<std::filesystem::path> runs, nlohmann::json memo_key);

}  // namespace freqlab
