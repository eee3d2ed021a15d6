// Lightmap atlases that keep their promise (issue "Method B, part 4", acceptance 4;
// volume/lightmap_atlas.h): a chart wider than the atlas side gets a page of its own and the
// object's other charts keep the requested density; every reduction is said, naming the object
// and the factor; per-object "lightmap" options (false, density_scale, max_size) are obeyed and
// bad ones refused naming the field.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "bake_fixture.h"
#include "base/error.h"
#include "scene/scene_loader.h"
#include "volume/lightmap_atlas.h"
#include "volume/texel_filter.h"

using namespace freqlab;
namespace fs = std::filesystem;

namespace {

using Fixture = test_support::BakeFixture;

// The world distance between horizontally adjacent placed texels of one chart: 1 / density.
double texel_spacing(const ObjectLightmap& map) {
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x + 1 < map.width; ++x) {
            const LightmapTexel& a = map.texels[size_t(y) * size_t(map.width) + size_t(x)];
            const LightmapTexel& b = map.texels[size_t(y) * size_t(map.width) + size_t(x) + 1];
            if (a.triangle < 0 || b.triangle < 0) continue;
            if (map.triangle_chart[size_t(a.triangle)] != map.triangle_chart[size_t(b.triangle)])
                continue;
            return double(glm::length(b.position - a.position));
        }
    return 0.0;
}

// The atlases at `density` texels per unit (bake.max_size's default 1024), 4 validity rays.
std::vector<ObjectLightmap> atlases(const Fixture& f, float density,
                                    std::vector<std::string>& notes) {
    AtlasSettings a;
    a.texel_density = density;
    a.max_size = 1024;
    a.validity_rays = 4;
    return build_lightmaps(*f.rays, a, &notes);
}

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

// One object: a 2000 x 2000 ground quad and a unit cube floating above it (one OBJ file).
std::string level_scene() {
    const fs::path dir = fs::temp_directory_path() / "freqlab_atlas_level";
    fs::create_directories(dir);
    std::ofstream obj(dir / "level.obj");
    obj << "v -1000 -1000 0\nv 1000 -1000 0\nv 1000 1000 0\nv -1000 1000 0\nf 1 2 3\nf 1 3 4\n";
    for (int i = 0; i < 8; ++i)
        obj << "v " << (i & 1 ? 0.5 : -0.5) << " " << (i & 2 ? 0.5 : -0.5) << " "
            << (i & 4 ? 3.0 : 2.0) << "\n";
    // Outward-wound cube faces (vertices 5..12).
    obj << "f 5 7 8\nf 5 8 6\nf 9 10 12\nf 9 12 11\nf 5 6 10\nf 5 10 9\n"
        << "f 7 11 12\nf 7 12 8\nf 5 9 11\nf 5 11 7\nf 6 8 12\nf 6 12 10\n";
    obj.close();
    return R"({"frames": 1, "camera": {"position": [0, -8, 5], "look_at": [0, 0, 2]},
      "materials": {"m": {"type": "lambert", "albedo": 0.5}},
      "objects": [{"name": "level", "mesh": ")" +
           (dir / "level.obj").string() + R"(", "material": "m"}],
      "lights": [{"type": "directional", "direction": [0.2, 0.3, -1], "irradiance": 1}]})";
}

}  // namespace

TEST(LightmapAtlas, AHugeGroundPlaneGetsAPageOfItsOwnAndTheRestKeepsTheRequestedDensity) {
    Fixture f(level_scene());
    std::vector<std::string> notes;
    const std::vector<ObjectLightmap> maps = atlases(f, 32.0f, notes);
    ASSERT_EQ(maps.size(), 2u);
    const ObjectLightmap& props = maps[0];
    const ObjectLightmap& ground = maps[1];
    EXPECT_EQ(props.object, 0);
    EXPECT_EQ(ground.object, 0);
    EXPECT_EQ(props.page, 0);
    EXPECT_EQ(ground.page, 1);
    // The cube's six charts at the requested density, untouched by the ground.
    EXPECT_EQ(props.charts, 6);
    EXPECT_TRUE(props.reductions.empty());
    EXPECT_FLOAT_EQ(props.texel_density, 32.0f);
    EXPECT_NEAR(texel_spacing(props), 1.0 / 32.0, 1e-4);
    EXPECT_NEAR(double(props.count(TexelState::Valid)), 6.0 * 32 * 32, 0.1 * 6 * 32 * 32);
    // The ground at the density that fits the side (1024 - 2 x 2 gutter texels over 2000 units).
    ASSERT_EQ(ground.reductions.size(), 1u);
    const float granted = 1020.0f / 2000.0f;
    EXPECT_FLOAT_EQ(ground.texel_density, granted);
    EXPECT_FLOAT_EQ(ground.reductions[0].requested, 32.0f);
    EXPECT_FLOAT_EQ(ground.reductions[0].granted, granted);
    EXPECT_NEAR(texel_spacing(ground), 1.0 / double(granted), 1e-3 / double(granted));
    EXPECT_LE(ground.width, 1024);
    EXPECT_LE(ground.height, 1024);
    // Said once, naming the object, its page and the factor.
    ASSERT_EQ(notes.size(), 1u);
    EXPECT_TRUE(contains(notes[0], "objects[0] 'level' (page 1)")) << notes[0];
    EXPECT_TRUE(contains(notes[0], "factor 0.01594")) << notes[0];
    EXPECT_TRUE(contains(notes[0], "2000 units across")) << notes[0];
    // Each triangle is on exactly one page, and lookups find it there.
    const LightmapLookup lookup(maps, f.scene.objects.size());
    EXPECT_EQ(lookup.find(0, 0), 1);
    EXPECT_EQ(lookup.find(0, 1), 1);
    for (int t = 2; t < 14; ++t) EXPECT_EQ(lookup.find(0, t), 0) << t;
    EXPECT_EQ(lookup.find(0, 14), -1);
    // A surface point on the ground maps into the ground's page only.
    SurfaceHit hit = f.rays->intersect(Ray{vec3(300.0f, -200.0f, 10.0f), vec3(0, 0, -1), 0, 1e9f});
    ASSERT_TRUE(hit.valid);
    vec2 uv;
    EXPECT_FALSE(lightmap_uv(*f.rays, props, hit, &uv));
    ASSERT_TRUE(lightmap_uv(*f.rays, ground, hit, &uv));
    const LightmapTexel& t = ground.texels[size_t(uv.y) * size_t(ground.width) + size_t(uv.x)];
    EXPECT_EQ(t.state, TexelState::Valid);
    EXPECT_LT(glm::length(t.position - hit.position), 1.5f / granted);
}

TEST(LightmapAtlas, ChartsThatOverflowTheAtlasShareOneReducedDensityAndItIsSaid) {
    // A unit box at 16 texels/unit: six 20-texel charts (gutters included) need more than
    // 40 x 40 texels.
    Fixture f(R"({"frames": 1, "camera": {"position": [0, -5, 3], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert", "albedo": 0.5}},
      "objects": [{"name": "crate", "shape": {"type": "box", "size": [1, 1, 1]}, "material": "m",
                   "lightmap": {"max_size": 40}}],
      "lights": [{"type": "point", "position": [0, 0, 3], "intensity": 1}]})");
    std::vector<std::string> notes;
    const std::vector<ObjectLightmap> maps = atlases(f, 16.0f, notes);
    ASSERT_EQ(maps.size(), 1u);
    const ObjectLightmap& m = maps[0];
    EXPECT_LE(m.width, 40);
    EXPECT_LE(m.height, 40);
    ASSERT_EQ(m.reductions.size(), 1u);
    EXPECT_EQ(m.reductions[0].charts, 6);
    const float granted = m.reductions[0].granted;
    EXPECT_GT(granted, 4.0f);
    EXPECT_LT(granted, 16.0f);
    for (float d : m.chart_density) EXPECT_FLOAT_EQ(d, granted);
    EXPECT_NEAR(texel_spacing(m), 1.0 / double(granted), 1e-4 / double(granted));
    ASSERT_EQ(notes.size(), 1u);
    EXPECT_TRUE(contains(notes[0], "objects[0] 'crate'")) << notes[0];
    EXPECT_TRUE(contains(notes[0], "would not pack into 40 x 40 texels")) << notes[0];
}

TEST(LightmapAtlas, ObjectOptionsOptOutScaleAndCap) {
    Fixture f(R"({"frames": 1, "camera": {"position": [0, -5, 3], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert", "albedo": 0.5}},
      "objects": [{"name": "skip", "shape": {"type": "plane", "size": [2, 2]}, "material": "m",
                   "lightmap": false},
                  {"name": "coarse", "shape": {"type": "plane", "size": [2, 2]}, "material": "m",
                   "transform": {"translate": [5, 0, 0]}, "lightmap": {"density_scale": 0.25}},
                  {"name": "fine", "shape": {"type": "plane", "size": [2, 2]}, "material": "m",
                   "transform": {"translate": [-5, 0, 0]}, "lightmap": true}],
      "lights": [{"type": "point", "position": [0, 0, 3], "intensity": 1}]})");
    std::vector<std::string> notes;
    const std::vector<ObjectLightmap> maps = atlases(f, 16.0f, notes);
    ASSERT_EQ(maps.size(), 2u);  // "skip" has none
    EXPECT_EQ(maps[0].object, 1);
    EXPECT_EQ(maps[1].object, 2);
    EXPECT_FLOAT_EQ(maps[0].requested_density, 4.0f);
    EXPECT_FLOAT_EQ(maps[0].texel_density, 4.0f);
    EXPECT_EQ(maps[0].count(TexelState::Valid), 64u);    // 2 x 2 units at 4 texels/unit
    EXPECT_EQ(maps[1].count(TexelState::Valid), 1024u);  // at 16
    EXPECT_TRUE(notes.empty());
}

TEST(LightmapAtlas, BadOptionsAreRefusedNamingTheField) {
    auto error_of = [](const std::string& option) -> std::string {
        try {
            parse_scene(R"({"frames": 1, "camera": {"position": [0, -5, 3], "look_at": [0, 0, 0]},
              "materials": {"m": {"type": "lambert"}},
              "objects": [{"shape": {"type": "plane", "size": [2, 2]}, "material": "m",
                           "lightmap": )" +
                            option + "}]}",
                        "s.json", "");
        } catch (const Error& e) {
            return e.what();
        }
        return "";
    };
    EXPECT_TRUE(contains(error_of("\"yes\""), "objects[0].lightmap: expected true, false or"))
        << error_of("\"yes\"");
    EXPECT_TRUE(contains(error_of(R"({"density_scale": 0})"), "objects[0].lightmap.density_scale"))
        << error_of(R"({"density_scale": 0})");
    EXPECT_TRUE(contains(error_of(R"({"max_size": 9000})"), "objects[0].lightmap.max_size"))
        << error_of(R"({"max_size": 9000})");
    EXPECT_TRUE(contains(error_of(R"({"size": 3})"), "objects[0].lightmap"))
        << error_of(R"({"size": 3})");
}

// Cover (lightmap_atlas.h): ground texels under a floor 0.05 above them are covered, the open
// ground beside it and the floor's top are not, and the texel filter never averages covered
// texels with open ones on the same surface (at 1 texel/unit valley's ground under a house's
// floor took the vertex field's value of the open ground beside it: house03:224,47 read 0.055
// where VPT reads 0.0003).
TEST(LightmapAtlas, TexelsUnderAFloorAreCoveredAndFilteredApartFromTheOpenGround) {
    Fixture f(R"({"frames": 1, "camera": {"position": [0, -9, 4], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert", "albedo": 0.5}},
      "objects": [{"name": "ground", "shape": {"type": "plane", "size": [8, 8]}, "material": "m"},
                  {"name": "floor", "shape": {"type": "box", "size": [4, 8, 0.2]}, "material": "m",
                   "transform": {"translate": [-2, 0, 0.15]}}],
      "lights": [{"type": "point", "position": [3, 0, 3], "intensity": 1}]})");
    std::vector<std::string> notes;
    const std::vector<ObjectLightmap> maps = atlases(f, 2.0f, notes);  // reach 0.125
    ASSERT_EQ(maps.size(), 2u);
    long under = 0, open = 0, floor_bottom = 0, floor_top = 0;
    for (const ObjectLightmap& map : maps)
        for (const LightmapTexel& t : map.texels) {
            if (t.state != TexelState::Valid) continue;
            if (map.object == 0 && t.position.x < -0.5f) {
                EXPECT_TRUE(t.covered) << t.position.x << " " << t.position.y;
                ++under;
            } else if (map.object == 0 && t.position.x > 0.5f) {
                EXPECT_FALSE(t.covered) << t.position.x << " " << t.position.y;
                ++open;
            } else if (map.object == 1 && t.normal.z < -0.9f) {
                EXPECT_TRUE(t.covered);
                ++floor_bottom;
            } else if (map.object == 1 && t.normal.z > 0.9f) {
                EXPECT_FALSE(t.covered);
                ++floor_top;
            }
        }
    EXPECT_GT(under, 40);
    EXPECT_GT(open, 40);
    EXPECT_GT(floor_bottom, 40);
    EXPECT_GT(floor_top, 40);
    // The ground's filter windows: texels across the floor's edge are otherwise alike (one
    // surface, one light level, no shadow told apart) and within reach, and are left out.
    const ObjectLightmap& ground = maps[0].object == 0 ? maps[0] : maps[1];
    const size_t n = ground.texels.size();
    TexelFilterGuide guide = TexelFilterGuide::sized(n);
    for (float& l : guide.light) l = 1.0f;
    long across = 0;
    for (size_t i = 0; i < n; ++i) {
        if (ground.texels[i].state != TexelState::Valid) continue;
        const std::vector<size_t> near = texel_filter_neighbours(ground, guide, i, 3);
        for (size_t j : near) EXPECT_EQ(ground.texels[j].covered, ground.texels[i].covered) << i;
        const int x = int(i % size_t(ground.width)), y = int(i / size_t(ground.width));
        for (int yj = std::max(0, y - 3); yj <= std::min(ground.height - 1, y + 3); ++yj)
            for (int xj = std::max(0, x - 3); xj <= std::min(ground.width - 1, x + 3); ++xj) {
                const LightmapTexel& u =
                    ground.texels[size_t(yj) * size_t(ground.width) + size_t(xj)];
                across += u.state == TexelState::Valid && u.covered != ground.texels[i].covered;
            }
    }
    EXPECT_GT(across, 20) << "the window reaches across the floor's edge";
}

// The texel filter's single-scattering ratio (ratio_correction): where the window's paired
// tables explain its real parts it scales the texel's tables by their ratio; where they explain
// nothing (tables 1e-6 against real parts of 40: a wall facing a smoke volume its connections
// only graze) it reads the window's mean real part instead of 1e6 times the texel's tables; a
// dark window (no real part) reads 0; a window that drew nothing keeps the tables; and the
// corrected value is never negative.
TEST(TexelFilter, RatioCorrectionScalesExplainedTablesAndLeansToTheMeanWhereTheyExplainNothing) {
    const std::vector<size_t> near = {0, 1, 2, 3};
    auto window = [](vec3 tables_i, vec3 paired, vec3 real) {
        std::vector<SingleCorrectionSums> sums(4);
        for (SingleCorrectionSums& s : sums) {
            s.paired_tables = paired / 4.0f;
            s.real = real / 4.0f;
        }
        sums[0].tables = tables_i;
        return sums;
    };
    auto corrected = [&](vec3 tables_i, vec3 paired, vec3 real) {
        return tables_i + ratio_correction(window(tables_i, paired, real), 0, near);
    };
    // Explained: T R / P = 1.5 within kTablesExplainShare's pull towards the mean (1.0).
    const vec3 explained = corrected(vec3(3.0f), vec3(8.0f), vec3(4.0f));
    EXPECT_NEAR(explained.x, 1.5f, 0.02f);
    EXPECT_LT(explained.x, 1.5f);
    EXPECT_GT(explained.x, 1.4f);
    // Unexplained: the mean real part per texel, 40 / 4.
    EXPECT_NEAR(corrected(vec3(1e-7f), vec3(1e-6f), vec3(40.0f)).x, 10.0f, 1e-3f);
    // Dark and nothing drawn.
    EXPECT_EQ(corrected(vec3(2.0f), vec3(5.0f), vec3(0.0f)).x, 0.0f);
    EXPECT_EQ(ratio_correction(window(vec3(2.0f), vec3(0.0f), vec3(0.0f)), 0, near).x, 0.0f);
    // Never negative, whatever the sums.
    CounterRng rng(3, 1, 4, 1);
    for (int k = 0; k < 10000; ++k) {
        const float t = std::exp(20.0f * rng.next_float() - 10.0f);
        const float p = std::exp(20.0f * rng.next_float() - 10.0f);
        const float r = rng.next_float() < 0.1f ? 0.0f : std::exp(20.0f * rng.next_float() - 10.0f);
        EXPECT_GE(corrected(vec3(t), vec3(p), vec3(r)).x, -1e-6f * t) << t << " " << p << " " << r;
    }
}
