// OpenVDB density grids for participating media (issue "Method B, part 2"): one named float
// grid of a .vdb file, densified over its active voxels' bounding box into the piecewise
// constant voxels of volume/media.h. Built without OpenVDB, reading throws an Error saying so.
#pragma once

#include <string>
#include <vector>

#include "math/types.h"

namespace freqlab {

struct VdbDensity {
    vec3 box_min{0.0f}, box_max{0.0f};  // world space
    ivec3 resolution{0};
    std::vector<float> voxels;  // x fastest
};

// Throws Error(scene_file, field, ...) when the file cannot be read, the grid is missing or
// not a float grid, its transform is not a uniform scale, or a voxel is negative or not finite.
VdbDensity read_vdb_density(const std::string& file, const std::string& grid_name,
                            const std::string& scene_file, const std::string& field);
// Writes one float grid (tests and the demo scene's generator; voxel size `voxel`, origin at
// box_min).
void write_vdb_density(const std::string& file, const std::string& grid_name,
                       const VdbDensity& density);

}  // namespace freqlab
