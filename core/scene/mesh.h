// Triangle meshes: procedural primitives and files read through assimp (OBJ, PLY, glTF,
// Collada, ...). Spheres are not meshed: they are exact Embree sphere primitives (see
// accel/), so analytic tests see a true sphere.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "math/types.h"

namespace freqlab {

struct TriangleMesh {
    std::vector<vec3> positions;
    std::vector<vec3> normals;  // per vertex, may be empty (then the face normal is used)
    std::vector<vec2> uvs;      // per vertex, may be empty
    std::vector<uvec3> triangles;
    // Sub-meshes of a file (assimp materials): triangle -> group, group -> its name there.
    std::vector<uint16_t> triangle_group;  // empty: one group
    std::vector<std::string> group_names;
    size_t degenerate_removed = 0;  // zero-area or out-of-range triangles dropped on load

    vec3 bounds_min() const;
    vec3 bounds_max() const;
};

// Removes zero-area triangles and ones indexing past the vertices; throws Error(origin, field)
// when vertices are non-finite or nothing valid remains.
void clean_mesh(TriangleMesh& mesh, const std::string& origin, const std::string& field);

TriangleMesh make_plane(vec2 size, float uv_scale);  // z = 0, normal +z, centred
TriangleMesh make_box(vec3 size);                    // centred
TriangleMesh make_disk(float radius, int segments);  // z = 0, normal +z
TriangleMesh make_torus(float major, float minor, int segments, int sides);  // about z

// A heightfield over [-size/2, size/2]^2 of cells.x x cells.y quads (2 triangles each): z =
// height x (2 fbm(x, y) - 1) (math/noise.h: seed, frequency in cycles per unit, octaves), with
// the analytic normals of that surface and uv = (x, y) / size x uv_scale.
struct TerrainShape {
    vec2 size{100.0f};
    ivec2 cells{256};
    float height = 2.0f;
    double frequency = 0.05;
    int octaves = 4;
    uint32_t seed = 1;
    float uv_scale = 1.0f;
};
TriangleMesh make_terrain(const TerrainShape& t);

// All meshes of a file flattened into one (node transforms applied).
TriangleMesh load_mesh_file(const std::filesystem::path& path, const std::string& origin,
                            const std::string& field);

}  // namespace freqlab
