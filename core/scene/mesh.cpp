#include "scene/mesh.h"

#include <tbb/parallel_for.h>

#include "math/noise.h"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>

#include "base/error.h"

namespace freqlab {

vec3 TriangleMesh::bounds_min() const {
    vec3 lo(INFINITY);
    for (const vec3& p : positions) lo = glm::min(lo, p);
    return lo;
}

vec3 TriangleMesh::bounds_max() const {
    vec3 hi(-INFINITY);
    for (const vec3& p : positions) hi = glm::max(hi, p);
    return hi;
}

void clean_mesh(TriangleMesh& mesh, const std::string& origin, const std::string& field) {
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        if (!std::isfinite(mesh.positions[i].x) || !std::isfinite(mesh.positions[i].y) ||
            !std::isfinite(mesh.positions[i].z))
            throw Error(origin, field, "vertex " + std::to_string(i) + " is not finite");
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size()) mesh.normals.clear();
    if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size()) mesh.uvs.clear();
    for (vec3& n : mesh.normals) {
        const float len = glm::length(n);
        n = std::isfinite(len) && len > 0 ? n / len : vec3(0.0f);
    }
    // Zero area relative to the mesh's size: |e1 x e2| below (1e-7 * extent)^2.
    const vec3 extent = mesh.positions.empty() ? vec3(0.0f) : mesh.bounds_max() - mesh.bounds_min();
    const float scale = std::max(extent.x, std::max(extent.y, extent.z));
    const float min_area2 = std::pow(1e-7f * scale, 2.0f);
    if (!mesh.triangle_group.empty() && mesh.triangle_group.size() != mesh.triangles.size())
        mesh.triangle_group.clear();
    std::vector<uvec3> kept;
    std::vector<uint16_t> kept_group;
    kept.reserve(mesh.triangles.size());
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
        const uvec3& t = mesh.triangles[i];
        const size_t n = mesh.positions.size();
        if (t.x >= n || t.y >= n || t.z >= n) continue;
        const vec3 c = glm::cross(mesh.positions[t.y] - mesh.positions[t.x],
                                  mesh.positions[t.z] - mesh.positions[t.x]);
        if (!(glm::length(c) > min_area2)) continue;
        kept.push_back(t);
        if (!mesh.triangle_group.empty()) kept_group.push_back(mesh.triangle_group[i]);
    }
    mesh.degenerate_removed += mesh.triangles.size() - kept.size();
    mesh.triangles.swap(kept);
    if (!mesh.triangle_group.empty()) mesh.triangle_group.swap(kept_group);
    if (mesh.triangles.empty())
        throw Error(origin, field,
                    "mesh has no usable triangles (" + std::to_string(mesh.degenerate_removed) +
                        " degenerate or invalid ones were dropped); expected at least one "
                        "triangle of non-zero area");
}

TriangleMesh make_plane(vec2 size, float uv_scale) {
    TriangleMesh m;
    const vec2 h = 0.5f * size;
    m.positions = {{-h.x, -h.y, 0}, {h.x, -h.y, 0}, {h.x, h.y, 0}, {-h.x, h.y, 0}};
    m.normals.assign(4, vec3(0, 0, 1));
    // uv in world-ish units so a checker keeps its scale on any plane size.
    m.uvs = {{0, 0},
             {size.x * uv_scale, 0},
             {size.x * uv_scale, size.y * uv_scale},
             {0, size.y * uv_scale}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

TriangleMesh make_box(vec3 size) {
    TriangleMesh m;
    const vec3 h = 0.5f * size;
    for (int axis = 0; axis < 3; ++axis)
        for (int sign = -1; sign <= 1; sign += 2) {
            vec3 n(0.0f);
            n[axis] = float(sign);
            const int a = (axis + 1) % 3, b = (axis + 2) % 3;
            const uint32_t base = uint32_t(m.positions.size());
            const vec2 corners[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
            for (const vec2& c : corners) {
                vec3 p(0.0f);
                p[axis] = sign * h[axis];
                p[a] = c.x * h[a];
                p[b] = c.y * h[b];
                m.positions.push_back(p);
                m.normals.push_back(n);
                m.uvs.push_back(0.5f * (c + 1.0f));
            }
            if (sign > 0)
                m.triangles.insert(m.triangles.end(),
                                   {{base, base + 1, base + 2}, {base, base + 2, base + 3}});
            else
                m.triangles.insert(m.triangles.end(),
                                   {{base, base + 2, base + 1}, {base, base + 3, base + 2}});
        }
    return m;
}

TriangleMesh make_disk(float radius, int segments) {
    TriangleMesh m;
    m.positions.push_back(vec3(0.0f));
    m.uvs.push_back(vec2(0.5f));
    for (int i = 0; i <= segments; ++i) {
        const float phi = kTwoPi * i / segments;
        m.positions.push_back(radius * vec3(std::cos(phi), std::sin(phi), 0.0f));
        m.uvs.push_back(0.5f + 0.5f * vec2(std::cos(phi), std::sin(phi)));
    }
    m.normals.assign(m.positions.size(), vec3(0, 0, 1));
    for (int i = 0; i < segments; ++i)
        m.triangles.push_back({0u, uint32_t(i + 1), uint32_t(i + 2)});
    return m;
}

TriangleMesh make_torus(float major, float minor, int segments, int sides) {
    TriangleMesh m;
    for (int i = 0; i <= segments; ++i) {
        const float u = kTwoPi * i / segments;
        for (int j = 0; j <= sides; ++j) {
            const float v = kTwoPi * j / sides;
            const vec3 centre(major * std::cos(u), major * std::sin(u), 0.0f);
            const vec3 n(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v));
            m.positions.push_back(centre + minor * n);
            m.normals.push_back(n);
            m.uvs.push_back(vec2(float(i) / segments, float(j) / sides));
        }
    }
    for (int i = 0; i < segments; ++i)
        for (int j = 0; j < sides; ++j) {
            const uint32_t a = i * (sides + 1) + j, b = (i + 1) * (sides + 1) + j;
            m.triangles.push_back({a, b, b + 1});
            m.triangles.push_back({a, b + 1, a + 1});
        }
    return m;
}

namespace {

// The terrain's grid vertex (i, j) of nx x ny cells, row by row.
uint32_t terrain_vertex(int nx, int i, int j) {
    return uint32_t(j * (nx + 1) + i);
}

// Side walls from the height field's boundary down to z = bottom, facing out: the boundary
// walked counter-clockwise seen from above, each side with its own vertices (its horizontal
// normal) so that the corners stay sharp.
void add_terrain_skirt(TriangleMesh& m, int nx, int ny, float bottom) {
    struct Side {
        int i0, j0, di, dj, n;
        vec3 normal;
    };
    const Side sides[4] = {{0, 0, 1, 0, nx, vec3(0, -1, 0)},
                           {nx, 0, 0, 1, ny, vec3(1, 0, 0)},
                           {nx, ny, -1, 0, nx, vec3(0, 1, 0)},
                           {0, ny, 0, -1, ny, vec3(-1, 0, 0)}};
    for (const Side& side : sides) {
        const uint32_t first = uint32_t(m.positions.size());
        for (int k = 0; k <= side.n; ++k) {
            const uint32_t v = terrain_vertex(nx, side.i0 + k * side.di, side.j0 + k * side.dj);
            const vec3 p = m.positions[v];
            const vec2 uv = m.uvs[v];
            m.positions.push_back(p);
            m.positions.push_back(vec3(p.x, p.y, bottom));
            m.normals.push_back(side.normal);
            m.normals.push_back(side.normal);
            m.uvs.push_back(uv);
            m.uvs.push_back(uv);
        }
        for (int k = 0; k < side.n; ++k) {
            const uint32_t t0 = first + 2 * uint32_t(k), b0 = t0 + 1, t1 = t0 + 2, b1 = t0 + 3;
            m.triangles.push_back({t0, b0, b1});
            m.triangles.push_back({t0, b1, t1});
        }
    }
}

}  // namespace

TriangleMesh make_terrain(const TerrainShape& t) {
    TriangleMesh m;
    const int nx = t.cells.x, ny = t.cells.y;
    const size_t verts = size_t(nx + 1) * size_t(ny + 1);
    m.positions.resize(verts);
    m.normals.resize(verts);
    m.uvs.resize(verts);
    auto height = [&](double x, double y) {
        return double(t.height) * (2.0 * fbm(t.seed, t.frequency, t.octaves, {x, y, 0.0}) - 1.0);
    };
    // The normal from central differences a tenth of a cell apart (the fBm's smoothstep is C1).
    const double hx = 0.1 * double(t.size.x) / nx, hy = 0.1 * double(t.size.y) / ny;
    tbb::parallel_for(0, ny + 1, [&](int j) {
        for (int i = 0; i <= nx; ++i) {
            const double x = (double(i) / nx - 0.5) * t.size.x,
                         y = (double(j) / ny - 0.5) * t.size.y;
            const size_t v = terrain_vertex(nx, i, j);
            m.positions[v] = vec3(float(x), float(y), float(height(x, y)));
            const double dzdx = (height(x + hx, y) - height(x - hx, y)) / (2.0 * hx);
            const double dzdy = (height(x, y + hy) - height(x, y - hy)) / (2.0 * hy);
            m.normals[v] = vec3(glm::normalize(glm::dvec3(-dzdx, -dzdy, 1.0)));
            m.uvs[v] = vec2(float(x / t.size.x + 0.5), float(y / t.size.y + 0.5)) * t.uv_scale;
        }
    });
    m.triangles.reserve(size_t(nx) * size_t(ny) * 2);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const uint32_t a = terrain_vertex(nx, i, j), b = a + 1, c = a + uint32_t(nx + 1),
                           d = c + 1;
            m.triangles.push_back({a, b, d});
            m.triangles.push_back({a, d, c});
        }
    if (t.skirt > 0.0f) add_terrain_skirt(m, nx, ny, -t.height - t.skirt);
    return m;
}

TriangleMesh load_mesh_file(const std::filesystem::path& path, const std::string& origin,
                            const std::string& field) {
    Assimp::Importer importer;
    importer.SetPropertyFloat(AI_CONFIG_PP_GSN_MAX_SMOOTHING_ANGLE, kGeneratedNormalMaxAngle);
    const aiScene* scene = importer.ReadFile(
        path.string(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                           aiProcess_GenSmoothNormals | aiProcess_PreTransformVertices |
                           aiProcess_SortByPType);
    if (!scene || !scene->mRootNode)
        throw Error(origin, field,
                    "cannot read mesh file " + path.string() + " (" + importer.GetErrorString() +
                        "); expected a mesh file with at least one triangle");
    TriangleMesh mesh;
    for (unsigned mi = 0; mi < scene->mNumMeshes; ++mi) {
        const aiMesh* am = scene->mMeshes[mi];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        const uint32_t base = uint32_t(mesh.positions.size());
        const bool has_uv = am->HasTextureCoords(0);
        aiString material_name;
        scene->mMaterials[am->mMaterialIndex]->Get(AI_MATKEY_NAME, material_name);
        const std::string group =
            material_name.length ? material_name.C_Str() : "mesh" + std::to_string(mi);
        auto found = std::find(mesh.group_names.begin(), mesh.group_names.end(), group);
        const uint16_t group_index = uint16_t(found - mesh.group_names.begin());
        if (found == mesh.group_names.end()) mesh.group_names.push_back(group);
        for (unsigned v = 0; v < am->mNumVertices; ++v) {
            const aiVector3D& p = am->mVertices[v];
            mesh.positions.push_back(vec3(p.x, p.y, p.z));
            mesh.normals.push_back(
                am->HasNormals() ? vec3(am->mNormals[v].x, am->mNormals[v].y, am->mNormals[v].z)
                                 : vec3(0.0f));
            mesh.uvs.push_back(has_uv ? vec2(am->mTextureCoords[0][v].x, am->mTextureCoords[0][v].y)
                                      : vec2(0.0f));
        }
        for (unsigned f = 0; f < am->mNumFaces; ++f) {
            const aiFace& face = am->mFaces[f];
            if (face.mNumIndices != 3) continue;
            mesh.triangles.push_back(
                {base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
            mesh.triangle_group.push_back(group_index);
        }
    }
    if (mesh.triangles.empty())
        throw Error(origin, field,
                    "mesh file " + path.string() +
                        " contains no triangles; expected a mesh file with at least one triangle");
    clean_mesh(mesh, origin, field);
    return mesh;
}

}  // namespace freqlab
