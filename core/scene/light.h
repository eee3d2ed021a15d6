// Lights of the scene model: a lat-long HDR environment map, a procedural sky (sun disk +
// zenith/horizon gradient, HDR), point, directional and quad area lights.
// Lat-long convention (z up): theta from +z (zenith), phi = atan2(y, x) turned by the map's
// rotation; u = phi / 2pi, v = theta / pi, row 0 at the zenith.
#pragma once

#include <memory>
#include <string>

#include "base/enum_names.h"
#include "base/huge_pages.h"
#include "image/image_io.h"
#include "math/distribution.h"
#include "math/types.h"

namespace freqlab {

// A lat-long map with importance sampling.
//
// The lighting function every integrator sees is the map as a piecewise-constant function
// over texels (eval): the sampling density is then exactly luminance x sin(theta) per texel
// (per tile of f x f texels on a smooth map, Distribution2D::tile(): a sky without a sun disc
// samples from a table that stays in cache), an environment sample's radiance is one texel
// read (no trigonometry), and estimator and pdf agree exactly. What a camera or a mirror sees
// directly is interpolated bilinearly (eval_smooth) so backgrounds do not look blocky; that
// radiance is not integrated. Negative texels (some HDR files have them) are read as 0 on load and
// counted (negative_texels(); the scene loader reports them in Scene::load_notes). A texel brighter
// than kMaxEnvironmentRadiance (after scale) is refused (Error naming the map and the pixel): a
// finite 1e38 in an HDR file turns every estimate into Inf (found by fuzz_env_hdr).
constexpr float kMaxEnvironmentRadiance = 1e20f;
class EnvironmentMap {
  public:
    EnvironmentMap(std::string source, std::shared_ptr<const RgbImage> image, float rotation_deg,
                   float scale, float spin_deg_per_s = 0.0f);

    vec3 eval(const vec3& direction) const;         // the texel's radiance (lighting)
    vec3 eval_smooth(const vec3& direction) const;  // bilinear (direct view)
    // Direction with density pdf (solid angle) from 4 uniforms; returns the radiance there.
    vec3 sample(const vec4& u, vec3* direction, float* pdf) const;
    float pdf(const vec3& direction) const;
    // eval() and pdf() together (one direction-to-texel conversion).
    vec3 eval_with_pdf(const vec3& direction, float* pdf) const;

    // The same two in steps, for loops over many samples: each step names the memory the next
    // one reads, so prefetching it overlaps the cache misses of all the samples (the alias
    // table and texels of a 1024x512 map are 12 MB; profiled: these reads were a third of a
    // sparse frame). sample_at(sample_texel(u), u) == sample(u).
    void prefetch_alias(const vec4& u) const { distribution_.prefetch(u); }
    int sample_texel(const vec4& u) const { return distribution_.sample_texel(u); }
    // The texel by CDF inversion (stratified u stay stratified); sample_at(texel,
    // vec4(u, *within)) then gives the direction, with the same density as sample().
    int sample_texel_inverted(vec2 u, vec2* within) const {
        return distribution_.sample_texel_inverted(u, within);
    }
    // Its stages (Distribution2D::Inversion), for loops that overlap the samples' misses.
    Distribution2D::Inversion invert_begin(vec2 u) const { return distribution_.invert_begin(u); }
    void invert_guide(Distribution2D::Inversion& s) const { distribution_.invert_guide(s); }
    int invert_finish(Distribution2D::Inversion& s) const { return distribution_.invert_finish(s); }
    void prefetch_texel(int texel) const { __builtin_prefetch(&texels_[size_t(texel)]); }
    vec3 sample_at(int texel, const vec4& u, vec3* direction, float* pdf) const;
    // The texel holding `direction` and its (u, v); eval_with_pdf_at(texel_of(d, &uv), uv)
    // == eval_with_pdf(d). (sample_at and these take one sample: the reference the batch
    // calls below are tested against.)
    int texel_of(const vec3& direction, vec2* uv) const;
    vec3 eval_with_pdf_at(int texel, vec2 uv, float* pdf) const;
    // Both for n samples at once, in loops the compiler vectorizes (math/fast_math.h instead of
    // libm), split where the memory is read so that a caller can compute between starting the
    // reads and using them (the texels' cache misses were most of the integrator's time):
    // - sample_directions(): sample_at()'s directions for the chosen texels and in-tile
    //   positions (u.z, u.w) of `u`, and their sin(theta); reads no texel;
    // - lookup_texels(): the texels holding n directions and their sin(theta); prefetches them;
    // - texel_values(): radiance and solid-angle pdf of n samples from texels and sin(theta).
    // Directions are structure of arrays.
    void sample_directions(int n, const int* texel, const vec4* u, float* x, float* y, float* z,
                           float* sin_theta) const;
    void lookup_texels(int n, const float* x, const float* y, const float* z, int* texel,
                       float* sin_theta) const;
    void texel_values(int n, const int* texel, const float* sin_theta, float* pdf,
                      vec3* radiance) const;

    const std::string& source() const { return source_; }
    const RgbImage& image() const { return *image_; }
    float rotation_deg() const { return rotation_deg_; }
    // Rotation about the vertical axis over time (seed §5.2: lighting rotation feeds B_t).
    float spin_deg_per_s() const { return spin_deg_per_s_; }
    // The map as it stands at `time` (a copy turned by spin x time; same texels).
    std::shared_ptr<const EnvironmentMap> at_time(float time) const;
    float scale() const { return scale_; }
    long negative_texels() const { return negative_texels_; }  // read as 0
    float most_negative() const { return most_negative_; }     // their lowest channel (or 0)
    const Distribution2D& distribution() const { return distribution_; }
    vec2 direction_to_uv(const vec3& d) const;
    vec3 uv_to_direction(vec2 uv) const;

  private:
    int texel_index(vec2 uv) const;
    static float solid_angle_pdf(float pdf_uv, vec2 uv);
    std::string source_;
    std::shared_ptr<const RgbImage> image_;
    struct Texel {
        vec3 radiance;  // clamped and scaled
        float pdf_uv;   // sampling density over [0,1)^2: read with the radiance, one miss
    };
    HugePageVector<Texel> texels_;  // read at random by every sample
    long negative_texels_ = 0;
    float most_negative_ = 0.0f;
    float rotation_deg_, scale_, spin_deg_per_s_ = 0.0f;
    Distribution2D distribution_;
};

// A lat-long image of constant radiance (what "radiance" envmaps and tests use).
std::shared_ptr<const RgbImage> constant_latlong(const vec3& radiance, int width = 32,
                                                 int height = 16);

struct ProceduralSky {
    vec3 sun_direction = glm::normalize(vec3(0.4f, -0.3f, 0.6f));
    float sun_angular_radius_deg = 0.53f;
    vec3 sun_radiance{2.0e4f, 1.8e4f, 1.5e4f};
    vec3 zenith{0.25f, 0.45f, 1.0f};
    vec3 horizon{0.9f, 0.95f, 1.1f};
    vec3 ground{0.25f, 0.22f, 0.2f};

    vec3 eval(const vec3& direction) const;
    // The sky as a lat-long image; texels the sun touches are supersampled 8x8.
    std::shared_ptr<const RgbImage> bake(int width, int height) const;
};

enum class LightType { Environment, Sky, Point, Directional, Quad };
inline constexpr EnumName<LightType> kLightTypeNames[] = {{LightType::Environment, "envmap"},
                                                          {LightType::Sky, "sky"},
                                                          {LightType::Point, "point"},
                                                          {LightType::Directional, "directional"},
                                                          {LightType::Quad, "quad"}};
inline const char* to_string(LightType type) {
    return enum_name(kLightTypeNames, type);
}

struct Light {
    LightType type = LightType::Point;
    vec3 position{0.0f};       // Point
    vec3 intensity{1.0f};      // Point: W/sr; Directional: irradiance; Quad: radiance
    vec3 direction{0, 0, -1};  // Directional: direction the light travels
    vec3 corner{0.0f}, edge_u{1, 0, 0}, edge_v{0, 1, 0};  // Quad, emits on edge_u x edge_v side
    // Environment, and Sky (baked into a map so that both are sampled the same way).
    std::shared_ptr<const EnvironmentMap> environment;
    ProceduralSky sky;  // Sky: its parameters
};

// One sample of a point, directional or quad light seen from p: the one copy that method A's
// direct lighting, method B's bakers, the VPT ground truth and the key-light masks call
// (environment and sky light is EnvironmentMap::sample's). A quad is sampled uniformly on its
// area and converted to solid angle; it emits on its edge_u x edge_v side only.
struct LightSample {
    bool valid = false;         // false: p behind the quad (direction, distance, intensity and
                                // emitter_normal still set), or on the point light
    vec3 direction{0.0f};       // from p towards the sampled point, unit
    float distance = INFINITY;  // to it; infinite for a directional light
    vec3 irradiance{0.0f};      // at p on a plane facing the light: radiance / solid-angle pdf
    vec3 intensity{0.0f};       // point: W/sr; quad: radiance x area; directional: irradiance
    vec3 emitter_normal{0.0f};  // quad: its unit normal
    float emitter_cos = 1.0f;   // quad: cosine between -direction and the normal
};
// How many uniforms sample_light reads for `light` (quad: 2; point, directional: 0).
inline int light_sample_dimensions(const Light& light) {
    return light.type == LightType::Quad ? 2 : 0;
}
// `light` must be a point, directional or quad light; u is read by quads only.
LightSample sample_light(const Light& light, const vec3& p, vec2 u);

}  // namespace freqlab
