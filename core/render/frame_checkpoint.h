// A stateful method's state between two frames as a file (issue "The timeline as a recorded
// run": cache checkpoints). Method A's cache is serialised before frame F (after F - 1) every
// K frames; a render that starts at frame A resumes from the newest checkpoint at or before A
// and re-renders the frames in between, so every frame it keeps is byte-identical to the
// sequential run's.
//
// | field    | content                                                                      |
// |----------|------------------------------------------------------------------------------|
// | magic    | "FLCK", then the format version (kFrameCheckpointVersion)                    |
// | key      | JSON: freqlab version, scene content hash, method, settings, seed (what must |
// |          | match for the state to be the one the run would have): a mismatch is refused |
// |          | naming the field                                                             |
// | frame    | the frame the state comes before                                             |
// | state    | FrameRenderer::save_state(): the method's bytes                              |
// | checksum | FNV-1a of everything before it                                               |
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace freqlab {

constexpr uint32_t kFrameCheckpointVersion = 1;

// DIR/checkpoints/state_before_NNNN.bin
std::filesystem::path frame_checkpoint_path(const std::filesystem::path& dir, int frame);

// The key of a run from its provenance record (scene/provenance.h): the fields a resumed state
// depends on (freqlab, scene_hash, method, settings, seed; not the scene's path).
nlohmann::json frame_checkpoint_key(const nlohmann::json& provenance);

// Written atomically (no half-written file under the name).
void write_frame_checkpoint(const std::filesystem::path& file, const nlohmann::json& key, int frame,
                            const std::string& state);

struct FrameCheckpoint {
    int frame = 0;
    std::string state;
};
// Throws Error naming the file and the field: damaged, truncated, another format version, or
// a key that differs from `key` (the field that differs is named).
FrameCheckpoint read_frame_checkpoint(const std::filesystem::path& file, const nlohmann::json& key);

// Where the workbench keeps a run's checkpoints: $FREQLAB_CACHE_DIR/runs/<hash of the key>.
std::filesystem::path run_store_directory(const nlohmann::json& key);

// Keeps the run store under its cap ($FREQLAB_RUN_STORE_MB, default 4096): removes the least
// recently written runs other than `keep` until the rest fit. Returns the runs removed.
int trim_run_store(const std::filesystem::path& keep);

// The newest checkpoint in DIR at or before `frame` (-1 when there is none).
int latest_frame_checkpoint(const std::filesystem::path& dir, int frame);

}  // namespace freqlab
