#include "scene/medium_desc.h"

#include <filesystem>

#include "scene/json_reader.h"

namespace freqlab {

namespace {

ivec3 read_resolution(const JsonReader& r) {
    if (r.array_size() != 3) r.fail("expected [nx, ny, nz] voxel counts");
    ivec3 res;
    for (int i = 0; i < 3; ++i) res[i] = r.at(size_t(i)).integer_in(1, 1024);
    if (long(res.x) * res.y * res.z > (1l << 27))
        r.fail("expected at most 2^27 voxels in all (the grid is held in memory)");
    return res;
}

void read_bounds(const JsonReader& r, MediumDesc& m) {
    r.only_keys({"box", "sphere"});
    if (r.has("box") == r.has("sphere")) r.fail("expected exactly one of \"box\" or \"sphere\"");
    if (r.has("box")) {
        const JsonReader b = r.get("box");
        b.only_keys({"min", "max"});
        m.bounds = MediumBounds::Box;
        m.box_min = b.get("min").vector3();
        m.box_max = b.get("max").vector3();
        if (!glm::all(glm::lessThan(m.box_min, m.box_max)))
            b.get("max").fail("expected max > min on every axis");
    } else {
        const JsonReader s = r.get("sphere");
        s.only_keys({"center", "radius"});
        m.bounds = MediumBounds::Sphere;
        m.center = s.get("center").vector3();
        m.radius = float(s.get("radius").number_in(0.0, 1e9, true));
    }
}

DensityBrush read_brush(const JsonReader& r) {
    r.only_keys({"shape", "center", "size", "density"});
    DensityBrush b;
    b.shape = r.get("shape").one_of({"box", "ellipsoid"}) == "box" ? DensityBrush::Shape::Box
                                                                   : DensityBrush::Shape::Ellipsoid;
    b.center = r.get("center").vector3();
    b.half_size = 0.5f * r.get("size").vector3();
    if (!glm::all(glm::greaterThan(b.half_size, vec3(0.0f))))
        r.get("size").fail("expected a positive size on every axis");
    b.density = float(r.number_or("density", 1.0, 0.0, 1e6));
    return b;
}

void read_density(const JsonReader& r, MediumDesc& m, const std::string& scene_dir) {
    const std::string source = r.get("source").one_of({"noise", "height_fog", "brushes", "vdb"});
    if (source == "noise") {
        r.only_keys({"source", "resolution", "frequency", "octaves", "threshold", "seed"});
        m.density = DensitySource::Noise;
        m.frequency = float(r.number_or("frequency", 1.0, 0.0, 1e4));
        m.octaves = r.has("octaves") ? r.get("octaves").integer_in(1, 12) : 4;
        m.threshold = float(r.number_or("threshold", 0.0, 0.0, 0.99));
        m.seed = r.has("seed") ? uint32_t(r.get("seed").integer_in(0, 1 << 30)) : 1u;
    } else if (source == "height_fog") {
        r.only_keys({"source", "resolution", "base", "falloff"});
        m.density = DensitySource::HeightFog;
        m.base = float(r.number_or("base", 0.0, -1e9, 1e9));
        m.falloff = float(r.has("falloff") ? r.get("falloff").number_in(0.0, 1e9, true) : 1.0);
    } else if (source == "brushes") {
        r.only_keys({"source", "resolution", "brushes"});
        m.density = DensitySource::Brushes;
        const JsonReader list = r.get("brushes");
        const size_t n = list.array_size();
        if (n == 0) list.fail("expected at least one brush");
        for (size_t i = 0; i < n; ++i) m.brushes.push_back(read_brush(list.at(i)));
    } else {
        r.only_keys({"source", "file", "grid"});
        m.density = DensitySource::Vdb;
        const std::string file = r.get("file").string();
        m.vdb_file = std::filesystem::path(file).is_absolute() || scene_dir.empty()
                         ? file
                         : (std::filesystem::path(scene_dir) / file).string();
        if (!std::filesystem::exists(m.vdb_file))
            r.get("file").fail("expected an OpenVDB file; '" + m.vdb_file + "' does not exist");
        if (r.has("grid")) m.vdb_grid = r.get("grid").string();
    }
    if (r.has("resolution")) m.resolution = read_resolution(r.get("resolution"));
}

}  // namespace

std::vector<MediumDesc> parse_media(const JsonReader& media, const std::string& scene_dir) {
    std::vector<MediumDesc> out;
    const size_t n = media.array_size();
    for (size_t i = 0; i < n; ++i) {
        const JsonReader r = media.at(i);
        r.only_keys({"name", "sigma_s", "sigma_a", "g", "density_scale", "bounds", "density"});
        MediumDesc m;
        m.name = r.has("name") ? r.get("name").string() : "medium" + std::to_string(i);
        // The seed's coefficients are non-negative and HG is defined for |g| < 1 only.
        m.sigma_s = r.get("sigma_s").number_in(0.0, 1e6);
        m.sigma_a = r.has("sigma_a") ? r.get("sigma_a").number_in(0.0, 1e6) : 0.0;
        m.g = r.has("g") ? r.get("g").number_in(-1.0, 1.0, true, true) : 0.0;
        m.density_scale = r.number_or("density_scale", 1.0, 0.0, 1e6);
        if (r.has("bounds")) read_bounds(r.get("bounds"), m);
        if (r.has("density")) {
            read_density(r.get("density"), m, scene_dir);
            if (m.bounds != MediumBounds::Box && m.density != DensitySource::Vdb)
                r.get("density").fail(
                    "a density grid needs \"bounds\": {\"box\": ...} (the grid's extent)");
        }
        out.push_back(std::move(m));
    }
    return out;
}

}  // namespace freqlab
