#include "render/shading_memo.h"

#include <algorithm>
#include <cstring>
#include <iterator>

#include "base/file_io.h"

namespace freqlab {

namespace {

uint64_t table_key(uint32_t pixel, uint8_t pass) {
    return uint64_t(pixel) * 4 + pass;
}

// Bit for bit: a plan upsampled from other values shades another point.
bool same_plan(const VisibilityPlan& a, const VisibilityPlan& b) {
    return std::memcmp(&a.occluded_fraction, &b.occluded_fraction, sizeof(double)) == 0 &&
           std::memcmp(&a.sigma_V, &b.sigma_V, sizeof(double)) == 0 &&
           std::memcmp(&a.t_min_occluded, &b.t_min_occluded, sizeof(double)) == 0 &&
           std::memcmp(&a.B_t_occluded, &b.B_t_occluded, sizeof(double)) == 0 &&
           a.own_distances == b.own_distances;
}

}  // namespace

const RadiancePoint* ShadingMemo::FrameTable::find(uint32_t pixel, uint8_t pass,
                                                   const VisibilityPlan* plan) const {
    const uint64_t k = table_key(pixel, pass);
    const auto it = std::lower_bound(keys.begin(), keys.end(), k);
    if (it == keys.end() || *it != k) return nullptr;
    const Entry& e = entries[size_t(it - keys.begin())];
    if (e.planned != (plan != nullptr)) return nullptr;
    if (plan && !same_plan(e.plan, *plan)) return nullptr;
    return &e.point;
}

size_t ShadingMemo::FrameTable::bytes() const {
    return keys.capacity() * sizeof(uint64_t) + entries.capacity() * sizeof(Entry);
}

ShadingMemo::ShadingMemo(size_t max_bytes) : max_bytes_(max_bytes) {}

size_t ShadingMemo::default_max_bytes() {
    return megabytes_from_environment("FREQLAB_SHADING_MEMO_MB", 512);
}

nlohmann::json ShadingMemo::key_of(const nlohmann::json& run_key) {
    nlohmann::json key = run_key;
    if (key.contains("settings") && key["settings"].is_object()) key["settings"].erase("cache");
    return key;
}

std::shared_ptr<const ShadingMemo::FrameTable> ShadingMemo::frame(int frame) {
    Loader loader;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        const auto it = frames_.find(frame);
        if (it != frames_.end()) return it->second;
        if (!loader_ || max_bytes_ == 0 || !asked_.insert(frame).second) return nullptr;
        loader = loader_;
    }
    std::shared_ptr<const FrameTable> loaded = loader(frame);  // reads a file: not under the lock
    if (!loaded) return nullptr;
    std::lock_guard<std::mutex> lock(mutex_);
    if (frames_.count(frame)) return frames_[frame];  // added meanwhile
    ++counts_.loaded_frames;
    bytes_ += loaded->bytes();
    frames_[frame] = loaded;
    fit_within_cap();
    return loaded;
}

void ShadingMemo::set_loader(Loader loader) {
    std::lock_guard<std::mutex> lock(mutex_);
    loader_ = std::move(loader);
    asked_.clear();
}

void ShadingMemo::add(int frame, std::vector<Entry> entries) {
    if (entries.empty() || max_bytes_ == 0) return;
    std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
        return table_key(a.pixel, a.pass) < table_key(b.pixel, b.pass);
    });
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = frames_.find(frame);
    const FrameTable* old = it != frames_.end() ? it->second.get() : nullptr;
    // Merge: the old table's entries, then the new keys it lacks (a point shaded again with
    // another plan keeps the first: either is exact for its own plan).
    auto table = std::make_shared<FrameTable>();
    const size_t old_n = old ? old->keys.size() : 0;
    table->keys.reserve(old_n + entries.size());
    table->entries.reserve(old_n + entries.size());
    size_t a = 0, b = 0;
    long stored = 0;
    while (a < old_n || b < entries.size()) {
        const uint64_t kb =
            b < entries.size() ? table_key(entries[b].pixel, entries[b].pass) : UINT64_MAX;
        if (a < old_n && old->keys[a] <= kb) {
            if (old->keys[a] == kb) ++b;
            table->keys.push_back(old->keys[a]);
            table->entries.push_back(old->entries[a++]);
        } else {
            if (table->keys.empty() || table->keys.back() != kb) {
                table->keys.push_back(kb);
                table->entries.push_back(std::move(entries[b]));
                ++stored;
            }
            ++b;
        }
    }
    if (old) bytes_ -= old->bytes();
    bytes_ += table->bytes();
    frames_[frame] = std::move(table);
    counts_.stored += stored;
    fit_within_cap();
}

void ShadingMemo::fit_within_cap() {
    while (bytes_ > max_bytes_ && !frames_.empty()) {
        const auto latest = std::prev(frames_.end());
        bytes_ -= latest->second->bytes();
        frames_.erase(latest);
        ++counts_.evicted_frames;
    }
}

void ShadingMemo::count_recalled(long n) {
    std::lock_guard<std::mutex> lock(mutex_);
    counts_.recalled += n;
}

ShadingMemo::Counts ShadingMemo::counts() const {
    std::lock_guard<std::mutex> lock(mutex_);
    Counts c = counts_;
    c.frames = long(frames_.size());
    c.bytes = bytes_;
    c.max_bytes = max_bytes_;
    return c;
}

}  // namespace freqlab
