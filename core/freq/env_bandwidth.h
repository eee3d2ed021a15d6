// The environment's local bandwidth hierarchy (seed, Premier article §4 "Incident Lighting
// Bandwidth", Fig. 8, and §7): for cone directions mu and footprint sizes, the bandwidth B_L of
// the environment's luminance inside a cosine-power window, from a 2D FFT (FFTW) of the windowed
// patch; a mip-like set of lat-long tables, built once per map and cached on disk.
//
// Unit: cycles per radian everywhere (the tangent-plane frequency of the windowed patch).
//
// | parameter          | value                                                                |
// |--------------------|----------------------------------------------------------------------|
// | levels             | window radius r_l = 90 deg / 2^l while the window spans >= 16 texels |
// |                    | (2 r_l >= 16 texel widths); smaller footprints get kNyquist          |
// | window             | cos^e(theta), theta from mu: e = 1 at level 0 (the clamped cosine),  |
// |                    | else the Phong exponent whose footprint radius atan(3 sigma) = r_l   |
// | patch              | azimuthal-equidistant P x P samples over [-r_l, r_l]^2 about mu,     |
// |                    | P = clamp(next power of 2 of 2 r_l / texel, 16, 256), bilinear lookups |
// | mean               | the window-weighted mean is subtracted first: a bright constant patch's |
// |                    | DC would otherwise hold 95 % of the energy and hide its variation     |
// | bandwidth          | radius of the 95th percentile of the spectrum's energy (rings of     |
// |                    | 1 / (P h), linear within the ring)                                    |
// | grid               | nodes every r_l / 2 in latitude and longitude (lat-long, cell centres) |
// | footprint max      | each node stores the maximum over nodes within r_l of it (the seed's |
// |                    | "maximum over the texels a footprint spans")                          |
// | query (mu, radius) | level by log2(90 deg / radius), bilinear in the grid, linear between |
// |                    | levels; radius under the finest level's: kNyquist                    |
// | kNyquist           | one cycle per two texels: width / (4 pi)                             |
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "math/types.h"

namespace freqlab {

class EnvironmentMap;

// The bandwidth of one windowed patch (row-major P x P, sample spacing h radians): the radius in
// cycles per radian holding `percentile` of the spectrum's energy. The FFT path (FFTW) and a
// direct DFT path (for tests) share the ring accumulation.
double patch_bandwidth(const std::vector<double>& patch, int P, double spacing,
                       double percentile = 0.95, bool direct_dft = false);
// The energy spectrum |F|^2 over the half plane FFTW returns (P x (P/2 + 1)), for tests.
std::vector<double> patch_spectrum(const std::vector<double>& patch, int P, bool direct_dft);

class EnvBandwidthHierarchy {
  public:
    static constexpr int kFormatVersion = 1;
    struct Level {
        double radius = 0.0;    // window radius r_l (radians)
        double exponent = 1.0;  // window cos^e
        int patch_size = 16;    // P
        int width = 0, height = 0;
        std::vector<float> bandwidth;  // per node, before the footprint max
        std::vector<float> maximum;    // per node, max over nodes within `radius`
    };

    static EnvBandwidthHierarchy build(const EnvironmentMap& env);
    // Built, or loaded from the cache folder when a file for this map's content exists.
    static EnvBandwidthHierarchy cached(const EnvironmentMap& env,
                                        std::string* path_used = nullptr);

    // B_L (cycles per radian) in the cone about `direction` of angular radius `radius`.
    double query(const vec3& direction, double radius) const;
    // One level's stored maximum at a direction (bilinear), for views and tests.
    double level_value(int level, const vec3& direction) const;
    double nyquist() const { return nyquist_; }
    const std::vector<Level>& levels() const { return levels_; }
    int env_width() const { return env_width_; }

    void save(const std::filesystem::path& path) const;
    static EnvBandwidthHierarchy load(const std::filesystem::path& path);

  private:
    std::vector<Level> levels_;
    double nyquist_ = 0.0;
    int env_width_ = 0;
    float rotation_deg_ = 0.0f;
    uint64_t content_hash_ = 0;
};

// The hierarchy as viewable layers on a width x width/2 lat-long grid: "color" (the map)
// and one continuous layer "B_L r=<deg>" per level (the footprint maxima, cycles per radian).
class LayerSet;
LayerSet bandwidth_layers(const EnvironmentMap& env, const EnvBandwidthHierarchy& hierarchy,
                          int width);

}  // namespace freqlab
