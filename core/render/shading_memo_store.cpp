#include "render/shading_memo_store.h"

#include <algorithm>
#include <cstdio>
#include <type_traits>

#include "base/byte_stream.h"
#include "base/error.h"
#include "base/file_io.h"
#include "base/hash.h"
#include "render/frame_checkpoint.h"
#include "render/frame_store.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr uint32_t kMagic = 0x4d534c46;  // "FLSM"

// One memo entry as stored: every field a recalled point carries (its cone samples are never
// kept by shading: render/sparse_pass.cpp clears them).
struct StoredEntry {
    uint32_t pixel;
    uint8_t pass, planned, own_distances, pad = 0;
    double plan[4];  // occluded_fraction, sigma_V, t_min_occluded, B_t_occluded
    float radiance[3], variance;
    int64_t rays;
    double values[11];  // B_L, sigma_rho, N_L, N_omega, sigma_V, occlusion_ratio, t_min, B_S,
                        // B_x, B_theta, B_t
    int32_t pilot_rays, pilot_occluded;
    double footprint_radius, mu_o[2], sigma_o[3];
};
static_assert(std::is_trivially_copyable_v<StoredEntry>);

// StoredEntry::values, in order.
constexpr double RadiancePoint::*kValueFields[11] = {
    &RadiancePoint::B_L,     &RadiancePoint::sigma_rho, &RadiancePoint::N_L,
    &RadiancePoint::N_omega, &RadiancePoint::sigma_V,   &RadiancePoint::occlusion_ratio,
    &RadiancePoint::t_min,   &RadiancePoint::B_S,       &RadiancePoint::B_x,
    &RadiancePoint::B_theta, &RadiancePoint::B_t};

StoredEntry stored(const ShadingMemo::Entry& e) {
    StoredEntry s{};
    s.pixel = e.pixel;
    s.pass = e.pass;
    s.planned = e.planned;
    s.own_distances = e.plan.own_distances;
    s.plan[0] = e.plan.occluded_fraction;
    s.plan[1] = e.plan.sigma_V;
    s.plan[2] = e.plan.t_min_occluded;
    s.plan[3] = e.plan.B_t_occluded;
    const RadiancePoint& p = e.point;
    for (int c = 0; c < 3; ++c) s.radiance[c] = p.radiance[c];
    s.variance = p.variance;
    s.rays = p.rays;
    for (size_t i = 0; i < 11; ++i) s.values[i] = p.*kValueFields[i];
    s.pilot_rays = p.pilot_rays;
    s.pilot_occluded = p.pilot_occluded;
    s.footprint_radius = p.footprint_radius;
    std::copy(p.mu_o, p.mu_o + 2, s.mu_o);
    std::copy(p.sigma_o, p.sigma_o + 3, s.sigma_o);
    return s;
}

ShadingMemo::Entry entry(const StoredEntry& s) {
    ShadingMemo::Entry e;
    e.pixel = s.pixel;
    e.pass = s.pass;
    e.planned = s.planned != 0;
    e.plan.own_distances = s.own_distances != 0;
    e.plan.occluded_fraction = s.plan[0];
    e.plan.sigma_V = s.plan[1];
    e.plan.t_min_occluded = s.plan[2];
    e.plan.B_t_occluded = s.plan[3];
    RadiancePoint& p = e.point;
    p.radiance = vec3(s.radiance[0], s.radiance[1], s.radiance[2]);
    p.variance = s.variance;
    p.rays = long(s.rays);
    for (size_t i = 0; i < 11; ++i) p.*kValueFields[i] = s.values[i];
    p.pilot_rays = s.pilot_rays;
    p.pilot_occluded = s.pilot_occluded;
    p.footprint_radius = s.footprint_radius;
    std::copy(s.mu_o, s.mu_o + 2, p.mu_o);
    std::copy(s.sigma_o, s.sigma_o + 3, p.sigma_o);
    return e;
}

fs::path key_path(const fs::path& run_dir) {
    return run_dir / "memo" / "key.json";
}

}  // namespace

fs::path memo_frame_path(const fs::path& run_dir, int frame) {
    // The recorded frame's name: trim_run_store drops the two together.
    return run_dir / "memo" / recorded_frame_path(run_dir, frame).filename();
}

void write_memo_frame(const fs::path& run_dir, const json& memo_key, int frame,
                      const ShadingMemo::FrameTable& table) {
    std::vector<StoredEntry> entries;
    entries.reserve(table.entries.size());
    for (const ShadingMemo::Entry& e : table.entries) entries.push_back(stored(e));
    ByteWriter w;
    w.put(kMagic);
    w.put(kMemoFrameVersion);
    w.put_string(memo_key.dump());
    w.put<int32_t>(frame);
    w.put_vector(entries);
    w.put<uint64_t>(fnv1a_words(w.bytes().data(), w.bytes().size()));
    std::error_code ec;
    fs::create_directories(run_dir / "memo", ec);
    if (!fs::exists(key_path(run_dir))) write_text_atomically(key_path(run_dir), memo_key.dump());
    write_text_atomically(memo_frame_path(run_dir, frame), w.bytes());
}

std::shared_ptr<const ShadingMemo::FrameTable> read_memo_frame(const fs::path& file,
                                                               const json& memo_key, int frame) {
    const MappedFile mapped(file);
    const std::string_view bytes = mapped.bytes();
    const std::string source = file.string();
    ByteReader r(bytes, source, "memo");
    const uint64_t stored_sum =
        read_run_file_frame(r, bytes, source, kMagic, kMemoFrameVersion, "shading memo frame");
    if (stored_sum != fnv1a_words(bytes.data(), bytes.size() - sizeof stored_sum))
        throw Error(source, "checksum", "the file is damaged or truncated");
    json found;
    try {
        found = json::parse(r.get_string());
    } catch (const json::exception& e) {
        throw Error(source, "key", std::string("unreadable: ") + e.what());
    }
    if (found != memo_key) throw Error(source, "key", "written by runs of other settings");
    if (r.get<int32_t>() != frame) throw Error(source, "frame", "another frame's points");
    const std::vector<StoredEntry> entries = r.get_vector<StoredEntry>();
    if (r.remaining() != sizeof(uint64_t))
        throw Error(source, "memo", std::to_string(r.remaining()) + " bytes past the end");
    auto table = std::make_shared<ShadingMemo::FrameTable>();
    table->keys.reserve(entries.size());
    table->entries.reserve(entries.size());
    for (size_t i = 0; i < entries.size(); ++i) {
        const StoredEntry& s = entries[i];
        const std::string where = "entries[" + std::to_string(i) + "]";
        if (s.pass > 3 || s.planned > 1 || s.own_distances > 1)
            throw Error(source, where, "pass or flag out of range");
        const uint64_t key = uint64_t(s.pixel) * 4 + s.pass;
        if (!table->keys.empty() && key <= table->keys.back())
            throw Error(source, where, "keys not ascending");
        table->keys.push_back(key);
        table->entries.push_back(entry(s));
    }
    return table;
}

std::vector<fs::path> runs_sharing_memo(const fs::path& run_dir, const json& memo_key) {
    std::vector<std::pair<fs::file_time_type, fs::path>> found;
    std::error_code ec;
    const std::string wanted = memo_key.dump();
    for (fs::directory_iterator it(run_dir.parent_path(), ec), end; !ec && it != end;
         it.increment(ec)) {
        const fs::path key = key_path(it->path());
        std::error_code kec;
        if (!fs::is_regular_file(key, kec)) continue;
        try {
            if (read_text_file(key) == wanted)
                found.emplace_back(fs::last_write_time(it->path() / "memo", kec), it->path());
        } catch (const Error&) {
            // An unreadable key is no run to share with.
        }
    }
    std::sort(found.begin(), found.end(),
              [](const auto& a, const auto& b) { return a.first > b.first; });
    std::vector<fs::path> runs;
    for (auto& [time, path] : found) runs.push_back(std::move(path));
    return runs;
}

std::function<std::shared_ptr<const ShadingMemo::FrameTable>(int)> memo_loader(
    std::vector<fs::path> runs, json memo_key) {
    return [runs = std::move(runs), memo_key = std::move(memo_key)](
               int frame) -> std::shared_ptr<const ShadingMemo::FrameTable> {
        for (const fs::path& run : runs) {
            const fs::path file = memo_frame_path(run, frame);
            std::error_code ec;
            if (!fs::is_regular_file(file, ec)) continue;
            try {
                return read_memo_frame(file, memo_key, frame);
            } catch (const Error&) {
                // Damaged or another version: those points are shaded again.
            }
        }
        return nullptr;
    };
}

}  // namespace freqlab
