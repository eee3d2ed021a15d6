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

#include "base/byte_stream.h"

namespace freqlab {

constexpr uint32_t kFrameCheckpointVersion = 1;

// DIR/checkpoints/state_before_NNNN.bin
std::filesystem::path frame_checkpoint_path(const std::filesystem::path& dir, int frame);

// The key of a run from its provenance record (scene/provenance.h): the fields a resumed state
// depends on (freqlab, scene_hash, method, settings, seed; not the scene's path), without the
// settings that change no result (SettingsGroup::affecting_results: frame.exposure,
// cache.checkpoint_every, ...).
nlohmann::json frame_checkpoint_key(const nlohmann::json& provenance);

// Throws Error naming `source` and the first key field (freqlab, scene_hash, method, settings,
// seed) where `found` differs from `key`: a file another run wrote.
void check_run_key(const nlohmann::json& found, const nlohmann::json& key,
                   const std::string& source);

// The frame of a run-store file (checkpoint, recorded frame): `magic`, then `version`, ..., a
// 64-bit trailer. Checks the size, magic and version (Error naming `source`, fields "header" /
// "version"; `what` names the kind of file), returns the trailer; `r` is left after the version.
uint64_t read_run_file_frame(ByteReader& r, std::string_view bytes, const std::string& source,
                             uint32_t magic, uint32_t version, const std::string& what);

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

// Where the workbench keeps a run's frames and checkpoints: <store>/<hash of the key>, the store
// being $FREQLAB_RUN_STORE_DIR, else $FREQLAB_CACHE_DIR/runs (base/file_io.h).
std::filesystem::path run_store_directory(const nlohmann::json& key);

// The newest checkpoint in DIR at or before `frame` (-1 when there is none).
int latest_frame_checkpoint(const std::filesystem::path& dir, int frame);

}  // namespace freqlab
