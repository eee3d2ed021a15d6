// Participating media as a scene describes them (seed, Deuxième article §3.1, §4.4): what the
// JSON `media` array holds, validated on load. Sampling the density into grids, tracking and
// transmittance live in volume/media.h; this is only the description.
//
// | field               | meaning                                                           |
// |---------------------|-------------------------------------------------------------------|
// | sigma_s, sigma_a    | scattering / absorption coefficients at density 1 (1/scene unit) |
// | g                   | Henyey-Greenstein anisotropy, |g| < 1                              |
// | bounds              | none (fills all space), a box or a sphere; grids need a box         |
// | density             | constant 1, or a grid from noise, a height-fog ramp, box/ellipsoid |
// |                     | brushes or an OpenVDB file's float grid, times `density_scale`     |
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/enum_names.h"
#include "math/types.h"

namespace freqlab {

enum class MediumBounds { Everywhere, Box, Sphere };
enum class DensitySource { Constant, Noise, HeightFog, Brushes, Vdb };
inline constexpr EnumName<DensitySource> kDensitySourceNames[] = {
    {DensitySource::Constant, "constant"},
    {DensitySource::Noise, "noise"},
    {DensitySource::HeightFog, "height_fog"},
    {DensitySource::Brushes, "brushes"},
    {DensitySource::Vdb, "vdb"}};
inline const char* to_string(DensitySource source) {
    return enum_name(kDensitySourceNames, source);
}

struct DensityBrush {
    enum class Shape { Box, Ellipsoid } shape = Shape::Box;
    vec3 center{0.0f};
    vec3 half_size{1.0f};  // box half extents, or the ellipsoid's semi-axes
    float density = 1.0f;  // added inside (brushes add up)
};

struct MediumDesc {
    std::string name;
    double sigma_s = 0.1, sigma_a = 0.0, g = 0.0;
    double density_scale = 1.0;
    MediumBounds bounds = MediumBounds::Everywhere;
    vec3 box_min{0.0f}, box_max{0.0f};  // Box (grids: the grid's extent)
    vec3 center{0.0f};                  // Sphere
    float radius = 0.0f;
    DensitySource density = DensitySource::Constant;
    ivec3 resolution{32};  // grid voxels (not Constant, not Vdb: the file's own voxels)
    // Noise: fBm of value noise, `frequency` cycles per unit, `octaves`, remapped so that
    // values below `threshold` are empty: max(0, n - threshold) / (1 - threshold).
    float frequency = 1.0f, threshold = 0.0f;
    int octaves = 4;
    uint32_t seed = 1;
    // Height fog: density exp(-(z - base) / falloff) above base, 1 below.
    float base = 0.0f, falloff = 1.0f;
    std::vector<DensityBrush> brushes;
    std::string vdb_file, vdb_grid = "density";  // vdb_file resolved against the scene folder

    bool is_grid() const { return density != DensitySource::Constant; }
};

class JsonReader;
// Throws Error naming file and field (negative sigma, |g| >= 1, a grid without a box, ...).
std::vector<MediumDesc> parse_media(const JsonReader& media, const std::string& scene_dir);

}  // namespace freqlab
