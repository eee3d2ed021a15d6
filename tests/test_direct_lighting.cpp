// The direct-lighting estimator against closed forms. Each check: |estimate - exact| <= 3
// standard errors, and 3 standard errors <= 0.5 % of the exact value (so the tolerance is
// never looser than that).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "image/image_io.h"
#include "render/direct_lighting.h"
#include "scene/scene_loader.h"

using namespace freqlab;
namespace fs = std::filesystem;

namespace {

void expect_closed_form(const RadianceEstimate& e, double exact, const std::string& what) {
    const double est = e.radiance.g;  // grey scenes: every channel is the same estimate
    const double se = std::sqrt(double(e.variance));
    EXPECT_LE(std::fabs(est - exact), 3 * se)
        << what << ": estimate " << est << " exact " << exact << " se " << se;
    EXPECT_LE(3 * se, 0.005 * exact) << what << ": too few samples for a 0.5 % test";
}

// Averages independent batches until 3 standard errors fall below 0.45 % of `exact` (or a
// cap): the tolerance asserted is always 3 SE, the sample count is what adapts.
RadianceEstimate estimate_precisely(const DirectLighting& lighting, const ShadingPoint& p,
                                    double exact, uint64_t key) {
    RadianceEstimate sum;
    double var_sum = 0;
    for (int k = 1; k <= 24; ++k) {
        CounterRng rng(key, uint64_t(k), 0, 0);
        const RadianceEstimate e = lighting.estimate(p, 200000, rng);
        sum.radiance += e.radiance;
        var_sum += e.variance;
        const double se = std::sqrt(var_sum) / k;
        if (k >= 2 && 3 * se <= 0.0045 * exact) {
            RadianceEstimate out;
            out.radiance = sum.radiance / float(k);
            out.variance = float(var_sum / (double(k) * k));
            return out;
        }
    }
    RadianceEstimate out;
    out.radiance = sum.radiance / 24.0f;
    out.variance = float(var_sum / (24.0 * 24.0));
    return out;
}

ShadingPoint lambert_point(const Scene& s, int object, vec3 p, vec3 n) {
    const Material& m = s.materials[size_t(s.objects[size_t(object)].material)];
    return ShadingPoint{p, n, n, n, &m, m.albedo.color};
}

// scenes/analytic/sphere_on_plane.json: a sphere (radius 1, albedo 0.5) resting on a plane of
// 4e4 x 4e4 (2e4 radii each way), constant environment radiance 1.
Scene sphere_on_plane() {
    return load_scene(FREQLAB_SOURCE_DIR "/scenes/analytic/sphere_on_plane.json");
}

TEST(DirectLighting, PlanePointNextToSphere) {
    const Scene scene = sphere_on_plane();
    EmbreeDevice device(2);
    RayScene rs(scene, device);
    const DirectLighting lighting(rs, ShadingSettings{});
    for (double d : {0.5, 1.0, 2.0, 4.0}) {
        const double exact = 0.5 * (1.0 - std::pow(1.0 / (d * d + 1.0), 1.5));
        const RadianceEstimate e = estimate_precisely(
            lighting, lambert_point(scene, 0, vec3(float(d), 0, 0), vec3(0, 0, 1)), exact,
            uint64_t(d * 100));
        expect_closed_form(e, exact, "plane at d = " + std::to_string(d));
    }
}

TEST(DirectLighting, SpherePointSeesTheUpperHalfSpace) {
    const Scene scene = sphere_on_plane();
    EmbreeDevice device(2);
    RayScene rs(scene, device);
    const DirectLighting lighting(rs, ShadingSettings{});
    for (double deg : {0.0, 45.0, 90.0, 120.0}) {
        const vec3 n(float(std::sin(glm::radians(deg))), 0.0f, float(std::cos(glm::radians(deg))));
        const double exact = 0.5 * (1.0 + n.z) / 2.0;
        const RadianceEstimate e = estimate_precisely(
            lighting, lambert_point(scene, 1, vec3(0, 0, 1) + n, n), exact, 1000 + uint64_t(deg));
        expect_closed_form(e, exact, "sphere normal at " + std::to_string(deg) + " deg");
    }
}

// A Lambertian plane (albedo 0.5) under the lat-long map L(theta) = 1 + cos(theta), written as
// an EXR and loaded as a scene would: an upward point reflects rho 5/3.
Scene one_plus_cos_scene() {
    const fs::path dir = fs::temp_directory_path() / "freqlab_one_plus_cos";
    fs::create_directories(dir);
    LayerSet map(512, 256);
    Layer& c = map.add("color", LayerKind::Color, 3);
    for (int y = 0; y < 256; ++y)
        for (int x = 0; x < 512; ++x)
            for (int k = 0; k < 3; ++k)
                c.at(512, x, y, k) = 1.0f + std::cos(kPi * (y + 0.5f) / 256);
    write_exr(dir / "one_plus_cos.exr", map);
    std::ofstream(dir / "scene.json") << R"({
      "camera": {"position": [0, -5, 2], "look_at": [0, 0, 0]},
      "objects": [{"shape": {"type": "plane", "size": [10, 10]}, "material": {"type": "lambert", "albedo": 0.5}}],
      "lights": [{"type": "envmap", "file": "one_plus_cos.exr", "rotation_deg": 17}]
    })";
    return load_scene((dir / "scene.json").string());
}

}  // namespace

TEST(DirectLighting, LatLongOnePlusCosTheta) {
    const Scene scene = one_plus_cos_scene();
    EmbreeDevice device(2);
    RayScene rs(scene, device);
    const DirectLighting lighting(rs, ShadingSettings{});
    CounterRng rng(3, 0, 0, 0);
    const RadianceEstimate e = lighting.estimate(
        lambert_point(scene, 0, vec3(0.3f, -0.2f, 0), vec3(0, 0, 1)), 200000, rng);
    expect_closed_form(e, 0.5 * 5.0 / 3.0, "rho 5/3");
}

TEST(DirectLighting, WhiteFurnace) {
    const Scene scene = parse_scene(R"({
      "camera": {"position": [0, -6, 0], "look_at": [0, 0, 0]},
      "objects": [{"shape": {"type": "sphere", "radius": 1}, "material": {"type": "lambert", "albedo": 1}}],
      "lights": [{"type": "envmap", "radiance": 1}]
    })",
                                    "furnace", "");
    EmbreeDevice device(2);
    RayScene rs(scene, device);
    const DirectLighting lighting(rs, ShadingSettings{});
    // Lambert with albedo 1 reflects exactly 1, at any point and for any view.
    for (int k = 0; k < 3; ++k) {
        const vec3 n = glm::normalize(vec3(0.3f * k - 0.2f, 0.5f, 0.4f - 0.3f * k));
        CounterRng rng(4, 0, uint64_t(k), 0);
        const RadianceEstimate e = lighting.estimate(lambert_point(scene, 0, n, n), 200000, rng);
        expect_closed_form(e, 1.0, "lambert furnace");
    }
    // Every other BRDF with albedo 1 reflects at most 1, from any view direction.
    std::vector<Material> materials;
    for (float e : {2.0f, 10.0f, 100.0f}) {
        Material m;
        m.type = BrdfType::Phong;
        m.phong_exponent = e;
        materials.push_back(m);
    }
    for (BrdfType t : {BrdfType::Beckmann, BrdfType::Ggx})
        for (float a : {0.05f, 0.3f, 1.0f}) {
            Material m;
            m.type = t;
            m.roughness = a;
            materials.push_back(m);
        }
    for (Material& m : materials) {
        m.albedo.color = vec3(1.0f);
        for (float view_deg : {0.0f, 45.0f, 80.0f}) {
            const vec3 n(0, 0, 1);
            const vec3 wo(std::sin(glm::radians(view_deg)), 0.0f, std::cos(glm::radians(view_deg)));
            CounterRng rng(5, 0, uint64_t(view_deg), 0);
            const RadianceEstimate e =
                lighting.estimate(ShadingPoint{n, n, n, wo, &m, vec3(1.0f)}, 40000, rng);
            EXPECT_LE(e.radiance.g - 3 * std::sqrt(e.variance), 1.0)
                << to_string(m.type) << " view " << view_deg;
            EXPECT_GT(e.radiance.g, 0.0) << to_string(m.type);
        }
    }
}

TEST(DirectLighting, MirrorSeesTheEnvironmentTimesAlbedo) {
    const Scene scene = parse_scene(R"({
      "camera": {"position": [0, -6, 0], "look_at": [0, 0, 0]},
      "objects": [{"shape": {"type": "plane", "size": [4, 4]}, "material": {"type": "mirror", "albedo": 0.8}}],
      "lights": [{"type": "envmap", "radiance": [1, 2, 3]}]
    })",
                                    "mirror", "");
    EmbreeDevice device(1);
    RayScene rs(scene, device);
    const DirectLighting lighting(rs, ShadingSettings{});
    CounterRng rng(6, 0, 0, 0);
    const RadianceEstimate e =
        lighting.trace(Ray{vec3(0.5f, -2, 2), glm::normalize(vec3(0, 1, -1))}, 8, rng);
    EXPECT_NEAR(e.radiance.r, 0.8f, 1e-5f);
    EXPECT_NEAR(e.radiance.b, 2.4f, 1e-5f);
    ShadingSettings no_bounce;
    no_bounce.mirror_depth = 0;
    const DirectLighting capped(rs, no_bounce);
    EXPECT_EQ(
        capped.trace(Ray{vec3(0.5f, -2, 2), glm::normalize(vec3(0, 1, -1))}, 8, rng).radiance.r,
        0.0f);
}

TEST(DirectLighting, PointLightIsExact) {
    // A point light of intensity I at height h over a Lambertian plane: L = rho/pi * I/h^2.
    const Scene scene = parse_scene(R"({
      "camera": {"position": [0, -6, 2], "look_at": [0, 0, 0]},
      "objects": [{"shape": {"type": "plane", "size": [10, 10]}, "material": {"type": "lambert", "albedo": 0.5}}],
      "lights": [{"type": "point", "position": [0, 0, 2], "intensity": 8}]
    })",
                                    "point", "");
    EmbreeDevice device(1);
    RayScene rs(scene, device);
    const DirectLighting lighting(rs, ShadingSettings{});
    CounterRng rng(7, 0, 0, 0);
    const RadianceEstimate e =
        lighting.estimate(lambert_point(scene, 0, vec3(0), vec3(0, 0, 1)), 4, rng);
    EXPECT_NEAR(e.radiance.g, 0.5 / M_PI * 8.0 / 4.0, 1e-6);
    EXPECT_EQ(e.variance, 0.0f);
}

// Stratified samples (SampleSequence::ScrambledSobol): every estimate is unbiased, and at a
// modest count its spread is well below that of independent samples, both where a visibility
// edge crosses the hemisphere (sphere_on_plane) and where the environment's CDF inversion does
// the work (1 + cos theta). Means and spreads are over many independently seeded estimates.
TEST(DirectLighting, StratifiedSamplesAreUnbiasedAndSpreadLess) {
    struct Case {
        const char* what;
        Scene scene;
        int object;
        vec3 p;
        double exact;
        double max_variance_ratio;  // stratified / independent, asserted
    };
    std::vector<Case> cases;
    cases.push_back({"plane next to the sphere", sphere_on_plane(), 0, vec3(0.5f, 0, 0),
                     0.5 * (1.0 - std::pow(1.0 / 1.25, 1.5)), 0.4});
    cases.push_back(
        {"1 + cos theta", one_plus_cos_scene(), 0, vec3(0.3f, -0.2f, 0), 0.5 * 5.0 / 3.0, 0.05});
    const int spp = 64, runs = 24000;
    for (const Case& c : cases) {
        EmbreeDevice device(2);
        RayScene rs(c.scene, device);
        const ShadingPoint sp = lambert_point(c.scene, c.object, c.p, vec3(0, 0, 1));
        double variance[2];
        for (SampleSequence sequence :
             {SampleSequence::Independent, SampleSequence::ScrambledSobol}) {
            const DirectLighting lighting(rs, ShadingSettings{}, sequence);
            double sum = 0, sum2 = 0;
            for (int k = 0; k < runs; ++k) {
                CounterRng rng(41, 0, uint64_t(k), 0);
                const double v = lighting.estimate(sp, spp, rng).radiance.g;
                sum += v;
                sum2 += v * v;
            }
            const double mean = sum / runs, var = (sum2 - runs * mean * mean) / (runs - 1);
            const double se = std::sqrt(var / runs);
            const bool sobol = sequence == SampleSequence::ScrambledSobol;
            variance[sobol] = var;
            std::printf("%-24s %-11s mean %.5f exact %.5f se %.5f variance %.3g\n", c.what,
                        sobol ? "stratified" : "independent", mean, c.exact, se, var);
            EXPECT_LE(std::fabs(mean - c.exact), 3 * se) << c.what << (sobol ? " stratified" : "");
            EXPECT_LE(3 * se, 0.005 * c.exact) << c.what;
        }
        EXPECT_LT(variance[1], c.max_variance_ratio * variance[0]) << c.what;
    }
}

TEST(DirectLighting, MethodARayOffsetDefaultsToTheOneSpawnRule) {
    // Method A's shading.ray_epsilon is the spawn rule's epsilon unless the user sets it.
    EXPECT_EQ(ShadingSettings{}.ray_epsilon, kRayEpsilon);
    const vec3 p(10.0f, -3.0f, 2.0f), n(0.0f, 0.0f, 1.0f);
    EXPECT_FLOAT_EQ(spawn_point(p, n).z, 2.0f + 10.0f * kRayEpsilon);
}
