#include "cache/radiance_cache.h"

#include <algorithm>
#include <cmath>

#include <Imath/half.h>

#include "base/error.h"

namespace freqlab {

namespace {

enum Flags : uint8_t {
    kLive = 1,
    kMoving = 2,
    kOccluded = 4,
    kMirror = 8,
    kKeyLightShift = 4,  // bits 4..6: visibility towards key lights 0..2
    kKeyLightKnown = 128
};

// Half floats for the merge weight and the observed-change references; clamped to the
// largest half (a weight past 65504 samples, a log luminance past it: neither changes a test).
uint16_t to_half(float v) {
    return Imath::half(std::isnan(v) ? v : std::clamp(v, -65504.0f, 65504.0f)).bits();
}
float from_half(uint16_t bits) {
    Imath::half h;
    h.setBits(bits);
    return float(h);
}

}  // namespace

vec2 octahedral_encode(const vec3& n) {
    const float l1 = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
    vec2 p(n.x / l1, n.y / l1);
    if (n.z < 0.0f) {
        const vec2 folded((1.0f - std::abs(p.y)) * (p.x >= 0.0f ? 1.0f : -1.0f),
                          (1.0f - std::abs(p.x)) * (p.y >= 0.0f ? 1.0f : -1.0f));
        p = folded;
    }
    return p;
}

vec3 octahedral_decode(const vec2& e) {
    vec3 n(e.x, e.y, 1.0f - std::abs(e.x) - std::abs(e.y));
    if (n.z < 0.0f) {
        const float x = (1.0f - std::abs(e.y)) * (e.x >= 0.0f ? 1.0f : -1.0f);
        const float y = (1.0f - std::abs(e.x)) * (e.y >= 0.0f ? 1.0f : -1.0f);
        n.x = x;
        n.y = y;
    }
    return glm::normalize(n);
}

uint32_t octahedral_encode_half(const vec3& n) {
    const vec2 e = octahedral_encode(n);
    return uint32_t(Imath::half(e.x).bits()) | (uint32_t(Imath::half(e.y).bits()) << 16);
}

vec3 octahedral_decode_half(uint32_t packed) {
    Imath::half x, y;
    x.setBits(uint16_t(packed & 0xffffu));
    y.setBits(uint16_t(packed >> 16));
    return octahedral_decode(vec2(float(x), float(y)));
}

size_t ObjectCache::bytes_per_slot() {
    return 4 * sizeof(vec3) + sizeof(vec2) + 2 * sizeof(uint32_t) + 6 * sizeof(float) +
           4 * sizeof(uint16_t) + sizeof(int16_t) + sizeof(uint8_t);
}

size_t ObjectCache::bytes() const {
    return capacity() * bytes_per_slot();
}

void ObjectCache::grow_to(size_t n) {
    const size_t old = capacity();
    if (n <= old) return;
    for (auto* v : {&position_, &created_position_, &shading_, &reflected_position_}) v->resize(n);
    view_.resize(n);
    normal_.resize(n);
    reflected_normal_.resize(n);
    for (auto* v : {&created_, &occlusion_, &sigma_v_, &t_min_}) v->resize(n);
    weight_.resize(n);
    for (auto* v : {&B_x_, &B_t_}) v->resize(n);
    for (auto* v : {&B_theta_, &occlusion_field_, &shading_field_}) v->resize(n);
    reflected_object_.resize(n, -1);
    flags_.resize(n, 0);
    // Lowest slots first out of the free list (it is popped from the back).
    ++reallocations_;
}

void ObjectCache::reserve_for(size_t count) {
    if (capacity() - live_count_ >= count) return;
    const size_t needed = live_count_ + count;
    grow_to(std::max(needed, size_t(std::ceil(1.5 * double(capacity())))));
}

int ObjectCache::insert(const CacheEntry& e) {
    if (live_count_ == capacity()) reserve_for(1);
    // The free slots are the ones without the live flag: the lowest first, found by a cursor
    // that restarts after a removal (no free list to store).
    while (flags_[next_free_] & kLive) ++next_free_;
    const int s = int(next_free_++);
    const size_t i = size_t(s);
    position_[i] = e.position;
    created_position_[i] = e.created_position;
    view_[i] = octahedral_encode(e.view);
    normal_[i] = octahedral_encode_half(e.normal);
    shading_[i] = e.shading;
    weight_[i] = to_half(e.weight);
    created_[i] = e.created;
    B_x_[i] = e.B_x;
    B_theta_[i] = to_half(e.B_theta);
    B_t_[i] = e.B_t;
    occlusion_[i] = e.occlusion_ratio;
    occlusion_field_[i] = to_half(e.occlusion_field);
    shading_field_[i] = to_half(e.shading_field);
    sigma_v_[i] = e.sigma_v;
    t_min_[i] = e.t_min;
    flags_[i] = uint8_t(kLive | (e.moving ? kMoving : 0) | (e.occluded ? kOccluded : 0) |
                        (e.mirror ? kMirror : 0) | ((e.key_light_mask & 7) << kKeyLightShift) |
                        (e.key_light_known ? kKeyLightKnown : 0));
    reflected_object_[i] = int16_t(e.reflected_object);
    reflected_position_[i] = e.reflected_position;
    reflected_normal_[i] = octahedral_encode_half(e.reflected_normal);
    ++live_count_;
    return s;
}

bool ObjectCache::key_light_known(int slot) const {
    return flags_[size_t(slot)] & kKeyLightKnown;
}

uint8_t ObjectCache::key_light_mask(int slot) const {
    return uint8_t((flags_[size_t(slot)] >> kKeyLightShift) & 7);
}

CacheEntry ObjectCache::get(int slot) const {
    const size_t i = size_t(slot);
    CacheEntry e;
    e.position = position_[i];
    e.created_position = created_position_[i];
    e.view = octahedral_decode(view_[i]);
    e.normal = octahedral_decode_half(normal_[i]);
    e.shading = shading_[i];
    e.weight = from_half(weight_[i]);
    e.created = created_[i];
    e.B_x = B_x_[i];
    e.B_theta = from_half(B_theta_[i]);
    e.B_t = B_t_[i];
    e.occlusion_ratio = occlusion_[i];
    e.occlusion_field = from_half(occlusion_field_[i]);
    e.shading_field = from_half(shading_field_[i]);
    e.sigma_v = sigma_v_[i];
    e.t_min = t_min_[i];
    e.moving = flags_[i] & kMoving;
    e.occluded = flags_[i] & kOccluded;
    e.mirror = flags_[i] & kMirror;
    e.key_light_mask = key_light_mask(slot);
    e.key_light_known = key_light_known(slot);
    e.reflected_object = reflected_object_[i];
    e.reflected_position = reflected_position_[i];
    e.reflected_normal = octahedral_decode_half(reflected_normal_[i]);
    return e;
}

void ObjectCache::set_value(int slot, const vec3& shading, float weight) {
    shading_[size_t(slot)] = shading;
    weight_[size_t(slot)] = to_half(weight);
}

void ObjectCache::remove(const std::vector<int>& slots) {
    for (int s : slots) {
        if (!live(s)) continue;
        flags_[size_t(s)] = 0;
        next_free_ = std::min(next_free_, size_t(s));
        --live_count_;
    }
}

void ObjectCache::encode(ByteWriter& w) const {
    for (const auto* v : {&position_, &created_position_, &shading_, &reflected_position_})
        w.put_vector(*v);
    w.put_vector(view_);
    w.put_vector(normal_);
    w.put_vector(reflected_normal_);
    for (const auto* v : {&created_, &occlusion_, &sigma_v_, &t_min_, &B_x_, &B_t_})
        w.put_vector(*v);
    for (const auto* v : {&B_theta_, &occlusion_field_, &shading_field_, &weight_})
        w.put_vector(*v);
    w.put_vector(reflected_object_);
    w.put_vector(flags_);
    w.put<uint64_t>(next_free_);
    w.put<uint64_t>(live_count_);
    w.put<int32_t>(reallocations_);
}

void ObjectCache::decode(ByteReader& r, const std::string& source) {
    for (auto* v : {&position_, &created_position_, &shading_, &reflected_position_})
        *v = r.get_vector<vec3>();
    view_ = r.get_vector<vec2>();
    normal_ = r.get_vector<uint32_t>();
    reflected_normal_ = r.get_vector<uint32_t>();
    for (auto* v : {&created_, &occlusion_, &sigma_v_, &t_min_, &B_x_, &B_t_})
        *v = r.get_vector<float>();
    for (auto* v : {&B_theta_, &occlusion_field_, &shading_field_, &weight_})
        *v = r.get_vector<uint16_t>();
    reflected_object_ = r.get_vector<int16_t>();
    flags_ = r.get_vector<uint8_t>();
    next_free_ = size_t(r.get<uint64_t>());
    live_count_ = size_t(r.get<uint64_t>());
    reallocations_ = r.get<int32_t>();
    const size_t n = flags_.size();
    const size_t sizes[] = {position_.size(),
                            created_position_.size(),
                            shading_.size(),
                            reflected_position_.size(),
                            view_.size(),
                            normal_.size(),
                            reflected_normal_.size(),
                            created_.size(),
                            occlusion_.size(),
                            sigma_v_.size(),
                            t_min_.size(),
                            B_x_.size(),
                            B_t_.size(),
                            B_theta_.size(),
                            occlusion_field_.size(),
                            shading_field_.size(),
                            weight_.size(),
                            reflected_object_.size()};
    for (size_t size : sizes)
        if (size != n)
            throw Error(source, "cache",
                        "slot arrays of different lengths (" + std::to_string(size) + " and " +
                            std::to_string(n) + ")");
    size_t live = 0;
    for (uint8_t f : flags_) live += f & kLive;
    if (live != live_count_ || next_free_ > n)
        throw Error(source, "cache",
                    "inconsistent slots: " + std::to_string(live) + " live flags, " +
                        std::to_string(live_count_) + " counted, cursor " +
                        std::to_string(next_free_) + " of " + std::to_string(n));
}

void RadianceCache::encode(ByteWriter& w) const {
    w.put<uint64_t>(objects_.size());
    for (const ObjectCache& o : objects_) o.encode(w);
}

void RadianceCache::decode(ByteReader& r, const std::string& source) {
    const uint64_t n = r.get<uint64_t>();
    // Each object holds at least its 19 array lengths: a count past the bytes left is damage.
    if (n > r.remaining() / (19 * sizeof(uint64_t)))
        throw Error(source, "cache",
                    std::to_string(n) + " objects in " + std::to_string(r.remaining()) + " bytes");
    objects_.assign(size_t(n), ObjectCache{});
    for (ObjectCache& o : objects_) o.decode(r, source);
}

void RadianceCache::reset(size_t objects) {
    objects_.clear();
    objects_.resize(objects);
}

size_t RadianceCache::live_count() const {
    size_t n = 0;
    for (const ObjectCache& c : objects_) n += c.live_count();
    return n;
}

size_t RadianceCache::bytes() const {
    size_t n = 0;
    for (const ObjectCache& c : objects_) n += c.bytes();
    return n;
}

long RadianceCache::evict_oldest(size_t max_bytes) {
    const size_t per = ObjectCache::bytes_per_slot();
    const size_t have = live_count() * per;
    if (have <= max_bytes) return 0;
    const size_t excess = (have - max_bytes + per - 1) / per;
    struct Aged {
        float created;
        int object, slot;
    };
    std::vector<Aged> all;
    all.reserve(live_count());
    for (size_t o = 0; o < objects_.size(); ++o)
        for (size_t s = 0; s < objects_[o].capacity(); ++s)
            if (objects_[o].live(int(s)))
                all.push_back({objects_[o].created_times()[s], int(o), int(s)});
    const size_t k = std::min(excess, all.size());
    std::nth_element(
        all.begin(), all.begin() + long(k), all.end(), [](const Aged& a, const Aged& b) {
            return a.created != b.created
                       ? a.created < b.created
                       : (a.object != b.object ? a.object < b.object : a.slot < b.slot);
        });
    std::vector<std::vector<int>> drop(objects_.size());
    for (size_t i = 0; i < k; ++i) drop[size_t(all[i].object)].push_back(all[i].slot);
    for (size_t o = 0; o < objects_.size(); ++o) objects_[o].remove(drop[o]);
    return long(k);
}

}  // namespace freqlab
