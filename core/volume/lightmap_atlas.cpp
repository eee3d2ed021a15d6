#include "volume/lightmap_atlas.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include <tbb/parallel_for.h>

#include "math/rng.h"
#include "math/sampling.h"

namespace freqlab {

size_t ObjectLightmap::count(TexelState s) const {
    return size_t(std::count_if(texels.begin(), texels.end(),
                                [s](const LightmapTexel& t) { return t.state == s; }));
}

float ObjectLightmap::density_at(size_t texel) const {
    const int t = texels[texel].triangle;
    return t >= 0 ? chart_density[size_t(triangle_chart[size_t(t)])] : texel_density;
}

std::vector<std::string> texel_state_legend() {
    return {"empty", "valid", "inside geometry", "dilated"};
}

namespace {

struct Chart {
    std::vector<int> triangles;
    int axis = 2;                    // projection drops this world axis
    vec2 lo{1e30f}, hi{-1e30f};      // projected bounds (scene units)
    float density = 0.0f;            // texels per unit granted
    int x = 0, y = 0, w = 0, h = 0;  // placement in texels, gutter included
};

// Texels a chart's extent covers: the nearest whole number, the chart centred on them
// (chart_offset, within +-0.25 texel), so that every texel centre lies at least a quarter of a
// texel inside a rectangular chart's edges. A centre on an edge samples the seam where the
// surface meets its neighbour (a box's foot on the floor, a room's corner), where half the
// hemisphere is the neighbour's plane and a path may leave through the seam.
int chart_cells(float extent, float density) {
    return std::max(1, int(std::lround(extent * density)));
}

float chart_offset(float extent, float density) {
    return 0.5f * (float(chart_cells(extent, density)) - extent * density);
}

int find_root(std::vector<int>& parent, int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

vec2 project(const vec3& p, int axis) {
    return axis == 0 ? vec2(p.y, p.z) : axis == 1 ? vec2(p.x, p.z) : vec2(p.x, p.y);
}

// Charts of one mesh: (dominant axis with sign) x connected components by shared vertex.
std::vector<Chart> make_charts(const TriangleMesh& mesh, const std::vector<vec3>& world) {
    const size_t nt = mesh.triangles.size();
    std::vector<int> cls(nt);
    for (size_t t = 0; t < nt; ++t) {
        const uvec3 tri = mesh.triangles[t];
        const vec3 n = glm::cross(world[tri.y] - world[tri.x], world[tri.z] - world[tri.x]);
        const vec3 a = glm::abs(n);
        const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
        cls[t] = axis * 2 + (n[axis] < 0.0f ? 1 : 0);
    }
    // Union triangles of one class sharing a vertex (through a per-vertex, per-class owner).
    std::vector<int> parent(nt);
    std::iota(parent.begin(), parent.end(), 0);
    std::vector<int> owner(mesh.positions.size() * 6, -1);
    for (size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            int& o = owner[size_t(mesh.triangles[t][k]) * 6 + cls[t]];
            if (o < 0)
                o = int(t);
            else
                parent[find_root(parent, int(t))] = find_root(parent, o);
        }
    std::vector<int> chart_of(nt, -1);
    std::vector<Chart> charts;
    for (size_t t = 0; t < nt; ++t) {
        const int r = find_root(parent, int(t));
        if (chart_of[r] < 0) {
            chart_of[r] = int(charts.size());
            charts.push_back({});
            charts.back().axis = cls[t] / 2;
        }
        Chart& c = charts[chart_of[r]];
        c.triangles.push_back(int(t));
        for (int k = 0; k < 3; ++k) {
            const vec2 p = project(world[mesh.triangles[t][k]], c.axis);
            c.lo = glm::min(c.lo, p);
            c.hi = glm::max(c.hi, p);
        }
    }
    return charts;
}

// Shelf packing, tallest first, each chart at its density x `scale`; returns the atlas size
// (width, height) or (0, 0) when a side would exceed max_size.
ivec2 pack(std::vector<Chart>& charts, float scale, int padding, int max_size) {
    double area = 0.0;
    for (Chart& c : charts) {
        c.w = chart_cells(c.hi.x - c.lo.x, c.density * scale) + 2 * padding;
        c.h = chart_cells(c.hi.y - c.lo.y, c.density * scale) + 2 * padding;
        area += double(c.w) * c.h;
    }
    // Near-square atlases: the side holds ~15 % shelf waste (a multiple of 4 up to the limit)
    // and the widest chart.
    int width = std::max(4, int(std::ceil(std::sqrt(1.15 * area))));
    width = std::min((width + 3) / 4 * 4, max_size);
    for (const Chart& c : charts) width = std::max(width, c.w);
    if (width > max_size) return {0, 0};
    std::vector<int> order(charts.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return charts[a].h > charts[b].h; });
    int x = 0, y = 0, shelf = 0;
    for (int i : order) {
        Chart& c = charts[i];
        if (x + c.w > width) {
            x = 0;
            y += shelf;
            shelf = 0;
        }
        c.x = x;
        c.y = y;
        x += c.w;
        shelf = std::max(shelf, c.h);
    }
    const int height = y + shelf;
    if (height > max_size) return {0, 0};
    return {width, height};
}

bool wants_lightmap(const Scene& scene, const SceneObject& o) {
    if (!o.lightmap.enabled) return false;
    if (o.shape != ShapeKind::Mesh || !o.mesh || !o.animation.is_static()) return false;
    return scene.materials[o.material].type != BrdfType::Mirror;
}

// Fraction of rays over p's hemisphere that hit a back face: a texel inside a closed mesh sees
// only back faces there (the other hemisphere holds its own surface, front-facing).
float backface_fraction(const RayScene& rs, const vec3& p, const vec3& n, int rays, uint64_t key) {
    int back = 0, hits = 0;
    for (int i = 0; i < rays; ++i) {
        CounterRng rng(key, 0x7e57, 0, uint64_t(i));
        const float u1 = rng.next_float(), u2 = rng.next_float();
        vec3 d = sample_uniform_sphere(u1, u2);
        if (glm::dot(d, n) < 0.0f) d = -d;
        Ray ray{spawn_point(p, n), d, 0.0f, INFINITY};
        const SurfaceHit h = rs.intersect(ray);
        if (!h.valid) continue;
        ++hits;
        // Back face: the triangle's own (wound) normal points away from the ray origin.
        const SceneObject& o = rs.scene().objects[h.object];
        if (o.shape != ShapeKind::Mesh) continue;
        const uvec3 tri = o.mesh->triangles[h.primitive];
        const mat4& m = rs.object_to_world(h.object);
        const vec3 a = vec3(m * vec4(o.mesh->positions[tri.x], 1.0f));
        const vec3 b = vec3(m * vec4(o.mesh->positions[tri.y], 1.0f));
        const vec3 c = vec3(m * vec4(o.mesh->positions[tri.z], 1.0f));
        if (glm::dot(glm::cross(b - a, c - a), d) > 0.0f) ++back;
    }
    (void)hits;
    return float(back) / float(rays);
}

std::string density_text(float d) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", double(d));
    return buf;
}

// Each chart's density: the requested one where it fits; charts wider than the side at their
// own; then, when the total overflows, every chart scaled by the largest common factor that
// packs. Returns the atlas size ((0, 0): no density packs) and says each reduction.
ivec2 choose_densities(std::vector<Chart>& charts, float requested, int side, int padding,
                       std::vector<AtlasReduction>& reductions) {
    const int room = side - 2 * padding;
    if (room < 1) return {0, 0};
    AtlasReduction wide{0, requested, requested, ""};
    float widest = 0.0f;
    for (Chart& c : charts) {
        const float extent = std::max(c.hi.x - c.lo.x, c.hi.y - c.lo.y);
        c.density = requested;
        if (chart_cells(extent, requested) <= room) continue;
        // extent x density <= room rounds to at most room cells.
        c.density = float(room) / extent;
        ++wide.charts;
        wide.granted = std::min(wide.granted, c.density);
        widest = std::max(widest, extent);
    }
    if (wide.charts > 0) {
        wide.reason =
            (wide.charts == 1 ? "a chart " : std::to_string(wide.charts) + " charts up to ") +
            density_text(widest) + " units across would be wider than the " + std::to_string(side) +
            "-texel atlas side";
        reductions.push_back(wide);
    }
    ivec2 size = pack(charts, 1.0f, padding, side);
    if (size.x > 0) return size;
    // Bisection on the common factor: `fits` packs, `fails` does not.
    float fits = 0.5f, fails = 1.0f;
    while (pack(charts, fits, padding, side).x == 0) {
        fails = fits;
        fits *= 0.5f;
        if (fits < 1e-7f) return {0, 0};  // not even a texel a chart fits
    }
    for (int i = 0; i < 24 && fails - fits > 1e-4f * fits; ++i) {
        const float mid = 0.5f * (fits + fails);
        (pack(charts, mid, padding, side).x > 0 ? fits : fails) = mid;
    }
    size = pack(charts, fits, padding, side);
    for (Chart& c : charts) c.density *= fits;
    for (AtlasReduction& r : reductions) r.granted *= fits;  // the wide charts shrink as well
    reductions.push_back({int(charts.size()), requested, requested * fits,
                          "the " + std::to_string(charts.size()) + " charts at " +
                              density_text(requested) + " texels/unit would not pack into " +
                              std::to_string(side) + " x " + std::to_string(side) + " texels"});
    return size;
}

std::string object_label(const Scene& scene, int object) {
    return "objects[" + std::to_string(object) + "] '" + scene.objects[size_t(object)].name + "'";
}

// Texels of one page: each chart's triangles rasterised at the chart's density, then the
// validity flags.
void place_texels(const RayScene& rs, size_t oi, const std::vector<vec3>& world,
                  const std::vector<Chart>& charts, const AtlasSettings& settings,
                  ObjectLightmap& map) {
    const Scene& scene = rs.scene();
    const SceneObject& obj = scene.objects[oi];
    const TriangleMesh& mesh = *obj.mesh;
    const mat3 nm = glm::transpose(glm::inverse(mat3(rs.object_to_world(int(oi)))));
    const ivec2 size(map.width, map.height);
    const Material& material = scene.materials[obj.material];
    tbb::parallel_for(size_t(0), charts.size(), [&](size_t ci) {
        const Chart& c = charts[ci];
        const float density = c.density;
        const vec2 offset(chart_offset(c.hi.x - c.lo.x, density),
                          chart_offset(c.hi.y - c.lo.y, density));
        for (int t : c.triangles) {
            const uvec3 tri = mesh.triangles[size_t(t)];
            vec2 q[3];
            for (int k = 0; k < 3; ++k) {
                q[k] = (project(world[tri[k]], c.axis) - c.lo) * density +
                       vec2(float(settings.padding)) + offset;
                map.triangle_uv[size_t(t) * 3 + size_t(k)] = q[k] + vec2(c.x, c.y);
            }
            const vec2 lo = glm::min(q[0], glm::min(q[1], q[2]));
            const vec2 hi = glm::max(q[0], glm::max(q[1], q[2]));
            const float area =
                (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (q[1].y - q[0].y);
            if (std::abs(area) < 1e-12f) continue;
            for (int y = std::max(0, int(std::floor(lo.y))); y <= int(hi.y) && y < c.h; ++y)
                for (int x = std::max(0, int(std::floor(lo.x))); x <= int(hi.x) && x < c.w; ++x) {
                    const vec2 pc(x + 0.5f, y + 0.5f);
                    auto edge = [&](vec2 a, vec2 b) {
                        return ((b.x - a.x) * (pc.y - a.y) - (pc.x - a.x) * (b.y - a.y)) / area;
                    };
                    const float w0 = edge(q[1], q[2]), w1 = edge(q[2], q[0]), w2 = edge(q[0], q[1]);
                    if (w0 < -1e-6f || w1 < -1e-6f || w2 < -1e-6f) continue;
                    LightmapTexel& tx = map.texels[size_t(c.y + y) * size.x + size_t(c.x + x)];
                    if (tx.triangle >= 0) continue;  // a fold: the first triangle keeps it
                    tx.triangle = t;
                    tx.state = TexelState::Valid;
                    tx.position = w0 * world[tri.x] + w1 * world[tri.y] + w2 * world[tri.z];
                    vec3 n = glm::cross(world[tri.y] - world[tri.x], world[tri.z] - world[tri.x]);
                    if (!mesh.normals.empty()) {
                        const vec3 sn = nm * (w0 * mesh.normals[tri.x] + w1 * mesh.normals[tri.y] +
                                              w2 * mesh.normals[tri.z]);
                        if (glm::dot(sn, n) > 0.0f) n = sn;
                    }
                    tx.normal = glm::normalize(n);
                    const vec2 uv = mesh.uvs.empty() ? vec2(0.0f)
                                                     : w0 * mesh.uvs[tri.x] + w1 * mesh.uvs[tri.y] +
                                                           w2 * mesh.uvs[tri.z];
                    tx.albedo = material.albedo.eval(uv);
                }
        }
    });
    // Validity: texels inside closed geometry see mostly back faces.
    tbb::parallel_for(size_t(0), map.texels.size(), [&](size_t i) {
        LightmapTexel& tx = map.texels[i];
        if (tx.state != TexelState::Valid) return;
        const float f =
            backface_fraction(rs, tx.position, tx.normal, settings.validity_rays,
                              mix64(oi * 0x100000000ULL + (size_t(map.page) << 40) + i));
        if (f > settings.backface_tolerance)
            tx.state = TexelState::InsideGeometry;
        else
            tx.covered =
                covered_along(rs, tx.position, tx.normal, kTexelCoverReach / map.density_at(i));
    });
}

}  // namespace

bool covered_along(const RayScene& rays, const vec3& p, const vec3& n, float reach) {
    return rays.occluded(shadow_ray(spawn_point(p, n), n, reach));
}

std::string reduction_note(const Scene& scene, const ObjectLightmap& map, const AtlasReduction& r) {
    return object_label(scene, map.object) +
           (map.page > 0 ? " (page " + std::to_string(map.page) + ")" : std::string()) +
           ": lightmap at " + density_text(r.granted) + " texels/unit instead of the requested " +
           density_text(r.requested) + " (factor " + density_text(r.granted / r.requested) + ", " +
           std::to_string(r.charts) + " of " + std::to_string(map.charts) +
           " charts): " + r.reason +
           "; raise its lightmap.max_size (or bake.max_size) or lower its lightmap.density_scale";
}

std::vector<ObjectLightmap> build_lightmaps(const RayScene& rs, const AtlasSettings& settings,
                                            std::vector<std::string>* notes) {
    const Scene& scene = rs.scene();
    std::vector<ObjectLightmap> maps;
    for (size_t oi = 0; oi < scene.objects.size(); ++oi) {
        const SceneObject& obj = scene.objects[oi];
        if (!wants_lightmap(scene, obj)) continue;
        const TriangleMesh& mesh = *obj.mesh;
        const mat4& m = rs.object_to_world(int(oi));
        std::vector<vec3> world(mesh.positions.size());
        for (size_t v = 0; v < world.size(); ++v)
            world[v] = vec3(m * vec4(mesh.positions[v], 1.0f));
        const float requested = settings.texel_density * obj.lightmap.density_scale;
        const int side = obj.lightmap.max_size > 0 ? obj.lightmap.max_size : settings.max_size;
        // A chart wider than the side gets a page of its own, so that its reduction does not
        // shrink the object's other charts.
        std::vector<std::vector<Chart>> pages(1);
        for (Chart& c : make_charts(mesh, world)) {
            const float extent = std::max(c.hi.x - c.lo.x, c.hi.y - c.lo.y);
            if (chart_cells(extent, requested) > side - 2 * settings.padding)
                pages.push_back({std::move(c)});
            else
                pages[0].push_back(std::move(c));
        }
        const size_t first_map = maps.size();
        for (std::vector<Chart>& charts : pages) {
            if (charts.empty()) continue;
            ObjectLightmap map;
            map.object = int(oi);
            map.page = int(maps.size() - first_map);  // numbered among the pages made
            map.requested_density = requested;
            const ivec2 size =
                choose_densities(charts, requested, side, settings.padding, map.reductions);
            if (size.x == 0) {
                if (notes)
                    notes->push_back(object_label(scene, int(oi)) + ": no lightmap: its " +
                                     std::to_string(charts.size()) + " charts do not fit " +
                                     std::to_string(side) + " x " + std::to_string(side) +
                                     " texels even at one texel each; raise its "
                                     "lightmap.max_size");
                continue;
            }
            map.width = size.x;
            map.height = size.y;
            map.charts = int(charts.size());
            map.texel_density = requested;
            map.chart_density.resize(charts.size());
            map.triangle_chart.assign(mesh.triangles.size(), -1);
            for (size_t ci = 0; ci < charts.size(); ++ci) {
                map.chart_density[ci] = charts[ci].density;
                map.texel_density = std::min(map.texel_density, charts[ci].density);
                for (int t : charts[ci].triangles) map.triangle_chart[size_t(t)] = int(ci);
            }
            if (notes)
                for (const AtlasReduction& r : map.reductions)
                    notes->push_back(reduction_note(scene, map, r));
            map.texels.resize(size_t(size.x) * size.y);
            map.triangle_uv.resize(mesh.triangles.size() * 3);
            place_texels(rs, oi, world, charts, settings, map);
            maps.push_back(std::move(map));
        }
    }
    return maps;
}

std::vector<TexelState> dilate(const ObjectLightmap& map, std::vector<float>& values, int channels,
                               int rings) {
    std::vector<TexelState> state(map.texels.size());
    for (size_t i = 0; i < state.size(); ++i) state[i] = map.texels[i].state;
    const int w = map.width, h = map.height;
    for (int ring = 0; ring < rings; ++ring) {
        std::vector<TexelState> next = state;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const size_t i = size_t(y) * w + x;
                if (state[i] == TexelState::Valid || state[i] == TexelState::Dilated) continue;
                int n = 0;
                std::vector<float> sum(size_t(channels), 0.0f);
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int xx = x + dx, yy = y + dy;
                        if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
                        const size_t j = size_t(yy) * w + xx;
                        if (state[j] != TexelState::Valid && state[j] != TexelState::Dilated)
                            continue;
                        for (int c = 0; c < channels; ++c) sum[c] += values[j * channels + c];
                        ++n;
                    }
                if (n == 0) continue;
                for (int c = 0; c < channels; ++c) values[i * channels + c] = sum[c] / float(n);
                next[i] = TexelState::Dilated;
            }
        state.swap(next);
    }
    return state;
}

TriangleToTexels triangle_to_texels(const RayScene& rays, const ObjectLightmap& map, size_t t) {
    const SceneObject& obj = rays.scene().objects[size_t(map.object)];
    const mat4& to_world = rays.object_to_world(map.object);
    const uvec3 tri = obj.mesh->triangles[t];
    const vec3 a = vec3(to_world * vec4(obj.mesh->positions[tri.x], 1.0f));
    const vec3 b = vec3(to_world * vec4(obj.mesh->positions[tri.y], 1.0f));
    const vec3 c = vec3(to_world * vec4(obj.mesh->positions[tri.z], 1.0f));
    const vec2* uv = &map.triangle_uv[t * 3];
    TriangleToTexels m;
    m.a = a;
    m.t0 = uv[0];
    const vec3 n = glm::cross(b - a, c - a);
    const float area2 = glm::dot(n, n);
    if (!(area2 > 0.0f)) return m;
    m.gb = glm::cross(c - a, n) / area2;
    m.gc = glm::cross(n, b - a) / area2;
    m.du = uv[1] - uv[0];
    m.dv = uv[2] - uv[0];
    return m;
}

LightmapLookup::LightmapLookup(const std::vector<ObjectLightmap>& maps, size_t object_count)
    : maps_(&maps), maps_of_object_(object_count) {
    for (size_t i = 0; i < maps.size(); ++i)
        if (size_t(maps[i].object) < object_count)
            maps_of_object_[size_t(maps[i].object)].push_back(int(i));
}

int LightmapLookup::find(int object, int triangle) const {
    if (object < 0 || size_t(object) >= maps_of_object_.size()) return -1;
    for (int m : maps_of_object_[size_t(object)])
        if ((*maps_)[size_t(m)].holds(triangle)) return m;
    return -1;
}

bool lightmap_uv(const RayScene& rays, const ObjectLightmap& map, const SurfaceHit& hit, vec2* uv) {
    if (hit.object != map.object || !map.holds(hit.primitive)) return false;
    *uv = triangle_to_texels(rays, map, size_t(hit.primitive)).uv(hit.position);
    return true;
}

vec3 sample_bilinear(const float* values, int channels, int width, int height, vec2 uv) {
    const float fx = uv.x - 0.5f, fy = uv.y - 0.5f;
    const int x0 = std::clamp(int(std::floor(fx)), 0, width - 1);
    const int y0 = std::clamp(int(std::floor(fy)), 0, height - 1);
    const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
    const float wx = std::clamp(fx - float(x0), 0.0f, 1.0f),
                wy = std::clamp(fy - float(y0), 0.0f, 1.0f);
    auto at = [&](int x, int y) {
        vec3 v(0.0f);
        const float* p = values + (size_t(y) * size_t(width) + size_t(x)) * size_t(channels);
        for (int c = 0; c < std::min(3, channels); ++c) v[c] = p[c];
        return v;
    };
    return (1 - wy) * ((1 - wx) * at(x0, y0) + wx * at(x1, y0)) +
           wy * ((1 - wx) * at(x0, y1) + wx * at(x1, y1));
}

}  // namespace freqlab
