#include "render/frame_store.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <regex>

#include "base/byte_stream.h"
#include "base/error.h"
#include "base/file_io.h"
#include "image/layer_codec.h"
#include "render/frame_checkpoint.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr uint32_t kMagic = 0x52464c46;  // "FLFR"

fs::path stats_path(const fs::path& dir, int frame) {
    return fs::path(recorded_frame_path(dir, frame)).replace_extension(".json");
}

template <class T>
size_t vector_bytes(const std::shared_ptr<const std::vector<T>>& v) {
    return v ? v->size() * sizeof(T) : 0;
}

void check_records(const std::vector<CacheRecord>& records, const std::string& source) {
    for (size_t i = 0; i < records.size(); ++i) {
        const int d = int(records[i].decision);
        if (d < 0 || d >= kCacheDecisionCount)
            throw Error(source, "cache_records[" + std::to_string(i) + "].decision",
                        "unknown decision " + std::to_string(d));
    }
}

}  // namespace

fs::path recorded_frame_path(const fs::path& dir, int frame) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d.bin", frame);
    return dir / "frames" / name;
}

void write_recorded_frame(const fs::path& dir, const json& key, const FrameResult& r) {
    // Streamed to the file: at 640x360 a frame is ~55 MB, and building it in memory first
    // (three copies, fresh pages each frame) took about as long as the frame's render without
    // its shading (perf: memmove and page faults ~20 % of a recording workbench).
    long on_image = 0;
    if (r.cache_records)
        for (const CacheRecord& c : *r.cache_records) on_image += c.pixel >= 0;
    ByteCounter layer_bytes;
    encode_layers(r.layers, layer_bytes);
    const std::string file = recorded_frame_path(dir, r.frame).string();
    std::error_code ec;
    fs::create_directories(dir / "frames", ec);
    write_atomically(file, [&](const fs::path& tmp) {
        std::ofstream out(tmp, std::ios::binary);
        StreamByteWriter w(out);
        w.put(kMagic);
        w.put(kRecordedFrameVersion);
        w.put_string(key.dump());
        w.put<int32_t>(r.frame);
        w.put<float>(r.time_s);
        w.put<uint64_t>(layer_bytes.counted());
        encode_layers(r.layers, w);
        w.put_string(r.stats.dump());
        w.put<uint8_t>(r.cache_records ? 1 : 0);
        if (r.cache_records) {
            // Only the entries landing on the image: a frame read back serves the inspector,
            // which lists the entries near a pixel (a third of rotor's records land outside).
            w.put<uint64_t>(uint64_t(on_image));
            for (const CacheRecord& c : *r.cache_records)
                if (c.pixel >= 0) w.put(c);
        }
        w.put<uint8_t>(r.sample_positions ? 1 : 0);
        if (r.sample_positions) w.put_vector(*r.sample_positions);
        w.put<uint64_t>(w.written());
        out.close();
        if (!out)
            throw Error(file, "", "could not write file: " + describe_write_failure(file, ""));
    });
    write_text_atomically(stats_path(dir, r.frame), r.stats.dump());
}

namespace {

// Every layer, records and positions when `only_layers` is null.
FrameResult read_frame(const fs::path& dir, const json& key, int frame,
                       const std::vector<std::string>* only_layers) {
    const fs::path file = recorded_frame_path(dir, frame);
    const std::string source = file.string();
    const MappedFile mapped(file, only_layers ? MapPages::OnTouch : MapPages::Populate);
    const std::string_view bytes = mapped.bytes();
    ByteReader r(bytes, source, "frame");
    const uint64_t stored =
        read_run_file_frame(r, bytes, source, kMagic, kRecordedFrameVersion, "recorded frame");
    if (stored != bytes.size() - sizeof stored)
        throw Error(source, "size", "the file is truncated or damaged");
    try {
        check_run_key(json::parse(r.get_string()), key, source);
    } catch (const json::exception& e) {
        throw Error(source, "key", std::string("unreadable: ") + e.what());
    }
    FrameResult result;
    result.frame = r.get<int32_t>();
    if (result.frame != frame)
        throw Error(
            source, "frame",
            "holds frame " + std::to_string(result.frame) + ", expected " + std::to_string(frame));
    result.time_s = r.get<float>();
    if (only_layers) {
        result.layers = decode_layers(r.get_view(), source, *only_layers, result.unread_layers);
        result.partial = true;
    } else {
        result.layers = decode_layers(r.get_view(), source);
    }
    try {
        result.stats = json::parse(r.get_string());
    } catch (const json::exception& e) {
        throw Error(source, "stats", std::string("unreadable: ") + e.what());
    }
    if (only_layers) return result;  // the file's size was checked: the rest is there
    if (r.get<uint8_t>()) {
        auto records = std::make_shared<std::vector<CacheRecord>>(r.get_vector<CacheRecord>());
        check_records(*records, source);
        result.cache_records = std::move(records);
    }
    if (r.get<uint8_t>())
        result.sample_positions = std::make_shared<const std::vector<std::pair<int, vec3>>>(
            r.get_vector<std::pair<int, vec3>>());
    if (r.remaining() != sizeof(uint64_t))
        throw Error(source, "frame",
                    std::to_string(r.remaining() - sizeof(uint64_t)) + " bytes past the end");
    return result;
}

}  // namespace

FrameResult read_recorded_frame(const fs::path& dir, const json& key, int frame) {
    return read_frame(dir, key, frame, nullptr);
}

FrameResult read_recorded_frame(const fs::path& dir, const json& key, int frame,
                                const std::vector<std::string>& only_layers) {
    return read_frame(dir, key, frame, &only_layers);
}

std::map<int, json> recorded_frame_stats(const fs::path& dir) {
    std::map<int, json> stats;
    const std::regex name(R"(frame_(\d+)\.json)");
    std::error_code ec;
    for (fs::directory_iterator it(dir / "frames", ec), end; !ec && it != end; it.increment(ec)) {
        std::smatch m;
        const std::string file = it->path().filename().string();
        if (!std::regex_match(file, m, name)) continue;
        const int frame = int(std::stol(m[1]));
        if (!fs::exists(recorded_frame_path(dir, frame))) continue;
        try {
            stats[frame] = json::parse(read_text_file(it->path()));
        } catch (const std::exception&) {
            // An unreadable record is as good as none: the frame renders again.
        }
    }
    return stats;
}

size_t frame_result_bytes(const FrameResult& r) {
    size_t bytes = sizeof(FrameResult);
    for (const Layer& l : r.layers.layers()) bytes += l.data.size() * sizeof(float);
    bytes += vector_bytes(r.cache_records) + vector_bytes(r.sample_positions);
    if (r.cache_snapshot) bytes += r.cache_snapshot->bytes();
    return bytes;
}

size_t decoded_frames_cap() {
    return megabytes_from_environment("FREQLAB_FRAME_MEMORY_MB", 256);
}

void touch_recorded_frame(const fs::path& dir, int frame) {
    std::error_code ec;
    fs::last_write_time(stats_path(dir, frame), fs::file_time_type::clock::now(), ec);
}

RunStoreTrim trim_run_store(const fs::path& keep) {
    const uint64_t cap = megabytes_from_environment("FREQLAB_RUN_STORE_MB", 16384);
    struct Entry {
        fs::path path;  // a run's folder, or a frame's .json in `keep`
        fs::file_time_type used;
        uint64_t bytes = 0;
    };
    std::vector<Entry> runs, frames;
    uint64_t total = 0;
    std::error_code ec;
    for (fs::directory_iterator it(keep.parent_path(), ec), end; !ec && it != end;
         it.increment(ec)) {
        if (!it->is_directory()) continue;
        const bool own = fs::equivalent(it->path(), keep, ec);
        Entry run{it->path(), fs::file_time_type::min(), 0};
        for (fs::recursive_directory_iterator f(run.path, ec), fend; !ec && f != fend;
             f.increment(ec)) {
            if (!f->is_regular_file()) continue;
            run.bytes += f->file_size();
            run.used = std::max(run.used, f->last_write_time());
            if (own && f->path().extension() == ".json" &&
                f->path().parent_path().filename() == "frames") {
                const fs::path bin = fs::path(f->path()).replace_extension(".bin");
                const fs::path memo =
                    f->path().parent_path().parent_path() / "memo" / bin.filename();
                std::error_code mec;  // most frames have no memo file
                const uint64_t memo_bytes = fs::exists(memo, mec) ? fs::file_size(memo, mec) : 0;
                frames.push_back({f->path(), f->last_write_time(),
                                  f->file_size() + fs::file_size(bin, ec) + memo_bytes});
            }
        }
        total += run.bytes;
        if (!own) runs.push_back(run);
    }
    auto by_use = [](const Entry& a, const Entry& b) { return a.used < b.used; };
    std::sort(runs.begin(), runs.end(), by_use);
    std::sort(frames.begin(), frames.end(), by_use);
    RunStoreTrim removed;
    for (const Entry& run : runs) {
        if (total <= cap) break;
        fs::remove_all(run.path, ec);
        total -= run.bytes;
        ++removed.runs;
    }
    for (const Entry& frame : frames) {
        if (total <= cap) break;
        fs::remove(frame.path, ec);  // first: the frame is no longer listed as recorded
        const fs::path bin = fs::path(frame.path).replace_extension(".bin");
        fs::remove(bin, ec);
        fs::remove(frame.path.parent_path().parent_path() / "memo" / bin.filename(),
                   ec);  // its points
        total -= std::min(total, frame.bytes);
        ++removed.frames;
    }
    return removed;
}

std::shared_ptr<FrameResult> DecodedFrames::find(int frame) {
    auto it = frames_.find(frame);
    if (it == frames_.end()) return nullptr;
    it->second.used = ++clock_;
    return it->second.result;
}

void DecodedFrames::keep(std::shared_ptr<FrameResult> result) {
    const int frame = result->frame;
    auto old = frames_.find(frame);
    if (old != frames_.end()) {
        bytes_ -= old->second.bytes;
        frames_.erase(old);
    }
    Held held{std::move(result), 0, ++clock_};
    held.bytes = frame_result_bytes(*held.result);
    bytes_ += held.bytes;
    frames_[frame] = std::move(held);
    while (bytes_ > cap_ && frames_.size() > 1) {
        auto lru = frames_.end();
        for (auto it = frames_.begin(); it != frames_.end(); ++it)
            if (it->first != frame && (lru == frames_.end() || it->second.used < lru->second.used))
                lru = it;
        bytes_ -= lru->second.bytes;
        frames_.erase(lru);
    }
}

void DecodedFrames::clear() {
    frames_.clear();
    bytes_ = 0;
}

std::vector<int> DecodedFrames::frames() const {
    std::vector<int> out;
    for (const auto& [f, held] : frames_) out.push_back(f);
    return out;
}

}  // namespace freqlab
