// Method A's object-space radiance cache (seed, Premier article §5.2 "Caching and Reusing
// Radiance Points", §7 growth): one cache per scene object, structure-of-arrays, free slots
// reused, growth by 1.5x at most once per object per frame.
//
// | field              | storage                                                           |
// |--------------------|-------------------------------------------------------------------|
// | position           | object space (moves with the object)                              |
// | created_position   | world, at creation (the spatial test's reference)                 |
// | view               | object space, unit; octahedral float pair (angular test precision)|
// | normal             | object space, unit; octahedral half pair (not tested, shown)      |
// | shading            | demodulated radiance (texture divided out); mirrors: the radiance  |
// | weight             | samples behind the value (merge weights; half float)              |
// | created            | time (s) of the frame that computed it                            |
// | B_x, B_t           | the point's spatial and temporal bandwidths (radius, lifespan)    |
// | B_theta            | the angular bandwidth (angular radius); half float                |
// | occlusion_ratio, sigma_v, t_min, occluded | the visibility statistics it stands for    |
// | occlusion_field    | the upsampled occlusion ratio at its pixel when it was computed   |
// | shading_field      | the upsampled log shading luminance there then (observed change)  |
// | reflected_*        | mirrors: the object, object-space position and normal it reflects  |
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/byte_stream.h"
#include "math/types.h"

namespace freqlab {

// One entry unpacked (insertion, tests, the inspector).
struct CacheEntry {
    vec3 position{0.0f};
    vec3 created_position{0.0f};
    vec3 view{0.0f, 0.0f, 1.0f};
    vec3 normal{0.0f, 0.0f, 1.0f};
    vec3 shading{0.0f};
    float weight = 1.0f;
    float created = 0.0f;
    float B_x = 0.0f, B_theta = 0.0f, B_t = 0.0f;
    float occlusion_ratio = 0.0f, sigma_v = 0.0f, t_min = 0.0f;
    // The occlusion ratio this frame's upsampled statistics gave at its pixel when it was
    // computed: the occlusion test compares like with like (see cache_decision.h).
    float occlusion_field = 0.0f;
    // Likewise the upsampled log luminance of the initial points' shading (NaN: none reached).
    float shading_field = NAN;
    bool moving = false, occluded = false, mirror = false;
    // Visibility towards the frame's key lights when computed (bit k: key k unoccluded), and
    // whether it was recorded (scenes where something moves): the key-light half of the
    // temporal test (cache_decision.h).
    uint8_t key_light_mask = 0;
    bool key_light_known = false;
    int reflected_object = -1;
    vec3 reflected_position{0.0f};
    vec3 reflected_normal{0.0f, 0.0f, 1.0f};
};

class ObjectCache {
  public:
    // Makes room for `count` insertions: grows (to max(1.5 x capacity, what is needed)) only
    // when the free slots do not suffice, so at most one reallocation per call.
    void reserve_for(size_t count);
    int insert(const CacheEntry& e);  // into a free slot (grows if none; call reserve_for first)
    CacheEntry get(int slot) const;
    // get(slot).key_light_known and .key_light_mask alone (the per-frame key-light test of every
    // reused entry reads nothing else; a whole get() decodes ~20 arrays).
    bool key_light_known(int slot) const;
    uint8_t key_light_mask(int slot) const;
    bool live(int slot) const { return flags_[size_t(slot)] & 1; }
    void set_value(int slot, const vec3& shading, float weight);
    // Batch removal (seed: once per frame): the slots become free for later insertions.
    void remove(const std::vector<int>& slots);

    size_t capacity() const { return flags_.size(); }
    size_t live_count() const { return live_count_; }
    size_t bytes() const;  // slot storage
    static size_t bytes_per_slot();
    int reallocations() const { return reallocations_; }

    // Every slot's fields, the free-slot cursor and the growth count, exactly (a checkpoint:
    // the cache resumed from it grows and reuses slots as the one that wrote it).
    void encode(ByteWriter& w) const;
    // Throws Error naming `source` when the bytes are not a whole, consistent ObjectCache.
    void decode(ByteReader& r, const std::string& source);

    // Hot fields read by the per-frame reprojection.
    const std::vector<vec3>& positions() const { return position_; }
    const std::vector<float>& created_times() const { return created_; }

  private:
    void grow_to(size_t capacity);
    std::vector<vec3> position_, created_position_, shading_, reflected_position_;
    std::vector<vec2> view_;                           // octahedral
    std::vector<uint32_t> normal_, reflected_normal_;  // octahedral, two halves
    std::vector<float> created_, occlusion_, sigma_v_, t_min_;
    // B_x and B_t as floats: as halves, B_x past 65504 (185000 on rotor's mast edge) was
    // clamped there, its validity radius 2.8x too wide (and B_t, B_x times a speed, alike).
    std::vector<float> B_x_, B_t_;
    // Half floats: the angular bandwidth (BRDF-limited, far below 65504) and the
    // observed-change references.
    std::vector<uint16_t> B_theta_, occlusion_field_, shading_field_;
    std::vector<uint16_t> weight_;  // half
    std::vector<int16_t> reflected_object_;
    std::vector<uint8_t> flags_;  // live, moving, occluded, mirror
    size_t next_free_ = 0;        // no free slot below it
    size_t live_count_ = 0;
    int reallocations_ = 0;
};

class RadianceCache {
  public:
    void reset(size_t objects);
    size_t object_count() const { return objects_.size(); }
    ObjectCache& object(int o) { return objects_[size_t(o)]; }
    const ObjectCache& object(int o) const { return objects_[size_t(o)]; }
    size_t live_count() const;
    size_t bytes() const;
    // Removes the oldest live entries until bytes() would fit `max_bytes` at the current
    // capacity (slots are freed, not released). Returns how many were evicted.
    long evict_oldest(size_t max_bytes);
    void encode(ByteWriter& w) const;
    void decode(ByteReader& r, const std::string& source);

  private:
    std::vector<ObjectCache> objects_;
};

// Octahedral mapping of unit vectors (float pairs: exact enough for sub-1e-6 rad tests; the
// half-float packing keeps ~1e-3 rad).
vec2 octahedral_encode(const vec3& n);
vec3 octahedral_decode(const vec2& e);
uint32_t octahedral_encode_half(const vec3& n);
vec3 octahedral_decode_half(uint32_t packed);

}  // namespace freqlab
