// Method B's bakers (volume/bake_estimators.h, volume/lightmap_baker.h): the impulse bake
// against volumetric path tracing on a receiver under a point light in fog (issue acceptance
// 1), closed forms for extinction, identity of all methods without media, the atlas's
// geometry and validity flags, and determinism across progressive passes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>

#include <tbb/parallel_for.h>

#include "bake_fixture.h"
#include "math/sh.h"
#include "scene/scene_loader.h"
#include "shared_tables.h"
#include "volume/impulse_irradiance.h"
#include "volume/lightmap_baker.h"
#include "volume/lightmap_preview.h"
#include "volume/texel_filter.h"

using namespace freqlab;

namespace {

using Fixture = test_support::BakeFixture;

std::string receiver_scene(const std::string& albedo, const std::string& media) {
    return R"({"frames": 1, "camera": {"position": [0, -5, 3], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert", "albedo": )" +
           albedo + R"(}},
      "objects": [{"name": "receiver", "shape": {"type": "plane", "size": [4, 4]}, "material": "m"}],
      "lights": [{"type": "point", "position": [0.3, 0.2, 1.0], "intensity": 10}],
      "media": )" +
           media + "}";
}

// Mean of `paths` estimates, summed in double (40k float additions would round by 1e-4).
IrradianceParts mean_estimate(const BakeEstimator& e, vec3 p, vec3 n, vec3 albedo, int paths,
                              uint64_t key) {
    glm::dvec3 surface(0.0), single(0.0), multiple(0.0);
    BakeCounters counters;
    for (int s = 0; s < paths; ++s) {
        CounterRng rng(0, key, 0, uint64_t(s));
        const IrradianceParts one = e.estimate(p, n, albedo, rng, counters);
        surface += glm::dvec3(one.surface);
        single += glm::dvec3(one.single);
        multiple += glm::dvec3(one.multiple);
    }
    return {vec3(surface / double(paths)), vec3(single / double(paths)),
            vec3(multiple / double(paths))};
}

}  // namespace

// Acceptance 1: black receiver (only incident light counts), point light in a homogeneous
// anisotropic medium, single scattering only. The impulse estimate is deterministic here (one
// point light, no bounce); VPT at 16k paths per point has ~0.7 % standard error.
TEST(Bake, ImpulseMatchesVolumetricPathTracingOnAReceiverInFog) {
    Fixture f(receiver_scene("0", R"([{"sigma_s": 0.6, "sigma_a": 0.1, "g": 0.3}])"));
    BakeSettings s;
    s.bounces = 0;
    s.media_bounces = 1;
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    const BakeEstimator impulse(*f.rays, f.media, &tables, BakeMethod::Impulse, s);
    const BakeEstimator vpt(*f.rays, f.media, nullptr, BakeMethod::Vpt, s);
    std::vector<vec3> points;
    for (float x : {-1.6f, -0.7f, 0.3f, 1.1f, 1.8f})
        for (float y : {-1.5f, 0.2f, 1.7f}) points.emplace_back(x, y, 0.0f);
    std::vector<IrradianceParts> vpt_mean(points.size());
    tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
        vpt_mean[i] = mean_estimate(vpt, points[i], vec3(0, 0, 1), vec3(0.0f), 16000, 2);
    });
    double rel_e = 0.0, rel_single = 0.0;
    int n = 0;
    for (size_t i = 0; i < points.size(); ++i) {
        const vec3 p = points[i], nrm(0, 0, 1);
        const IrradianceParts a = mean_estimate(impulse, p, nrm, vec3(0.0f), 1, 1);
        const IrradianceParts& b = vpt_mean[i];
        EXPECT_EQ(a.multiple, vec3(0.0f));
        EXPECT_EQ(b.multiple, vec3(0.0f));
        const double ea = luminance(a.total()), eb = luminance(b.total());
        const double sa = luminance(a.single), sb = luminance(b.single);
        ASSERT_GT(sb, 0.0);
        rel_e += (ea - eb) * (ea - eb) / (eb * eb);
        rel_single += (sa - sb) * (sa - sb) / (sb * sb);
        ++n;
        // The attenuated direct part is computed the same way by both: exactly equal.
        EXPECT_NEAR(luminance(a.surface), luminance(b.surface), 1e-6 * luminance(b.surface));
    }
    rel_e /= n;
    rel_single /= n;
    std::printf("relMSE impulse vs vpt: irradiance %.5f, single scattering alone %.5f\n", rel_e,
                rel_single);
    EXPECT_LE(rel_e, 0.02);
    EXPECT_LE(rel_single, 0.02);  // stronger: the part the tables provide
}

// Extinction of a point light through a slab of fog between it and the receiver: the closed
// form I cos / d^2 exp(-sigma_t x chord) at every point.
TEST(Bake, ExtinctionMatchesTheClosedForm) {
    Fixture f(receiver_scene("0.5", R"([{"sigma_s": 0.8, "sigma_a": 0.4,
                    "bounds": {"box": {"min": [-5, -5, 0.4], "max": [5, 5, 0.6]}}}])"));
    BakeSettings s;
    s.bounces = 0;
    const BakeEstimator e(*f.rays, f.media, nullptr, BakeMethod::Extinction, s);
    const vec3 light(0.3f, 0.2f, 1.0f);
    for (float x : {-1.5f, 0.0f, 1.2f}) {
        const vec3 p(x, 0.5f, 0.0f);
        const vec3 to = light - p;
        const double d = glm::length(to), cos = to.z / d;
        const double chord = 0.2 / cos;
        const double expected = 10.0 * cos / (d * d) * std::exp(-1.2 * chord);
        const IrradianceParts a = mean_estimate(e, p, vec3(0, 0, 1), vec3(0.5f), 1, 3);
        EXPECT_NEAR(luminance(a.surface), expected, 1e-4 * expected) << x;
    }
}

// Without media every method bakes the same light: surface, extinction and impulse exactly
// (same random numbers), VPT within its confidence interval (t-test on the mean).
// A plane and a box (two lightmaps) under a point light and a constant sky, no media.
const char* const kPlaneAndBox =
    R"({"frames": 1, "camera": {"position": [0, -5, 3], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert", "albedo": 0.7}},
      "objects": [{"shape": {"type": "plane", "size": [4, 4]}, "material": "m"},
                  {"shape": {"type": "box", "size": [1, 1, 1]}, "material": "m",
                   "transform": {"translate": [0.8, 0, 0.5]}}],
      "lights": [{"type": "point", "position": [-0.5, -0.5, 2.0], "intensity": 8},
                 {"type": "envmap", "radiance": 0.3}]})";

TEST(Bake, WithoutMediaAllMethodsAgree) {
    Fixture f(kPlaneAndBox);
    ASSERT_TRUE(f.media.empty());
    BakeSettings s;
    s.bounces = 2;
    const vec3 p(0.1f, 0.0f, 0.0f), n(0, 0, 1), albedo(0.7f);
    const int paths = 20000;
    const IrradianceParts surf = mean_estimate(
        BakeEstimator(*f.rays, f.media, nullptr, BakeMethod::Surface, s), p, n, albedo, paths, 5);
    for (BakeMethod m : {BakeMethod::Extinction, BakeMethod::Impulse}) {
        const IrradianceParts o =
            mean_estimate(BakeEstimator(*f.rays, f.media, nullptr, m, s), p, n, albedo, paths, 5);
        EXPECT_EQ(o.total(), surf.total()) << to_string(m);
    }
    // VPT: a t-test of its per-path mean against the surface bake's.
    const BakeEstimator vpt(*f.rays, f.media, nullptr, BakeMethod::Vpt, s);
    const BakeEstimator surface(*f.rays, f.media, nullptr, BakeMethod::Surface, s);
    double sa = 0, sa2 = 0, sb = 0, sb2 = 0;
    BakeCounters c;
    for (int i = 0; i < paths; ++i) {
        CounterRng ra(1, 7, 0, uint64_t(i)), rb(2, 7, 0, uint64_t(i));
        const double a = luminance(vpt.estimate(p, n, albedo, ra, c).total());
        const double b = luminance(surface.estimate(p, n, albedo, rb, c).total());
        sa += a, sa2 += a * a, sb += b, sb2 += b * b;
    }
    const double ma = sa / paths, mb = sb / paths;
    const double va = (sa2 / paths - ma * ma) / paths, vb = (sb2 / paths - mb * mb) / paths;
    const double t = (ma - mb) / std::sqrt(va + vb);
    EXPECT_LT(std::abs(t), 4.0) << "vpt " << ma << " surface " << mb;
    EXPECT_GT(mb, 0.0);
}

TEST(Bake, AtlasTexelsLieOnTheirTrianglesAndInsideTexelsAreFlagged) {
    // A closed box standing on a plane: plane texels under the box see back faces.
    Fixture f(R"({"frames": 1, "camera": {"position": [0, -5, 3], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert", "albedo": 0.5}},
      "objects": [{"name": "floor", "shape": {"type": "plane", "size": [4, 4]}, "material": "m"},
                  {"name": "box", "shape": {"type": "box", "size": [1, 1, 1]}, "material": "m",
                   "transform": {"translate": [0, 0, 0.49]}}],
      "lights": [{"type": "point", "position": [0, 0, 3], "intensity": 1}]})");
    AtlasSettings a;
    a.texel_density = 10.0f;
    const std::vector<ObjectLightmap> maps = build_lightmaps(*f.rays, a);
    ASSERT_EQ(maps.size(), 2u);
    const ObjectLightmap& floor = maps[0];
    const ObjectLightmap& box = maps[1];
    EXPECT_EQ(box.charts, 6);
    // Texel counts follow area x density^2 (floor 16 m^2, box 6 m^2, edges add a row).
    const double floor_texels =
        double(floor.count(TexelState::Valid) + floor.count(TexelState::InsideGeometry));
    EXPECT_NEAR(floor_texels, 16 * 100, 0.06 * 1600);
    EXPECT_NEAR(double(box.count(TexelState::Valid)), 6 * 100, 0.2 * 600);
    long inside_ok = 0, inside = 0;
    for (const LightmapTexel& t : floor.texels) {
        if (t.state == TexelState::Empty) continue;
        EXPECT_NEAR(t.position.z, 0.0f, 1e-5f);
        EXPECT_LE(std::abs(t.position.x), 2.0f + 1e-4f);
        const bool under_box = std::abs(t.position.x) < 0.45f && std::abs(t.position.y) < 0.45f;
        const bool clear = std::abs(t.position.x) > 0.55f || std::abs(t.position.y) > 0.55f;
        if (under_box) {
            ++inside;
            inside_ok += t.state == TexelState::InsideGeometry;
        }
        if (clear) {
            EXPECT_EQ(t.state, TexelState::Valid) << t.position.x << "," << t.position.y;
        }
    }
    EXPECT_GT(inside, 50);
    EXPECT_EQ(inside_ok, inside);
}

TEST(Bake, ProgressivePassesGiveTheSameLightmap) {
    Fixture f(receiver_scene("0.6", R"([{"sigma_s": 0.3, "sigma_a": 0.05}])"));
    BakeSettings s;
    s.spp = 7;
    s.texel_density = 4.0f;
    s.bounces = 1;
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    s.media_bounces = tables.bounces();
    // Impulse with the texels' own Monte Carlo terms and reading the field (texel_terms).
    for (const auto& [m, terms] : {std::pair{BakeMethod::Impulse, TexelTerms::Own},
                                   std::pair{BakeMethod::Impulse, TexelTerms::Field},
                                   std::pair{BakeMethod::Vpt, TexelTerms::Own}}) {
        s.texel_terms = terms;
        const std::string name =
            std::string(to_string(m)) + (terms == TexelTerms::Field ? " field" : "");
        LightmapBaker once(*f.rays, f.media, &tables, m, s);
        once.run_pass(7);
        LightmapBaker passes(*f.rays, f.media, &tables, m, s);
        passes.run();  // 1 + 2 + 4
        EXPECT_EQ(passes.samples(), 7);
        const LayerSet a = once.layers(0), b = passes.layers(0);
        EXPECT_EQ(a.get("lm_total").data, b.get("lm_total").data) << name;
        double multiple = 0.0;
        for (float v : a.get("lm_inscatter_multiple").data) multiple += v;
        EXPECT_GT(multiple, 0.0) << name;  // media_bounces >= 2 reaches it
    }
}

// The direct light of point and directional lights at a texel is the same on every path: reused
// from the first (BakeEstimator::FixedDirect), the estimates are those of paths that recompute
// it (to float rounding), with one shadow ray fewer per path after the first.
TEST(Bake, FixedDirectLightIsReusedExactly) {
    Fixture f(receiver_scene("0.6", R"([{"sigma_s": 0.3, "sigma_a": 0.05, "g": 0.2}])"));
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    BakeSettings s;
    s.bounces = 2;
    for (BakeMethod m : {BakeMethod::Surface, BakeMethod::Extinction, BakeMethod::Impulse}) {
        const BakeEstimator e(*f.rays, f.media, &tables, m, s);
        BakeEstimator::FixedDirect fixed;
        BakeCounters with, without;
        const int paths = 64;
        glm::dvec3 a(0.0), b(0.0);
        for (int i = 0; i < paths; ++i) {
            CounterRng ra(0, 1, 2, uint64_t(i)), rb(0, 1, 2, uint64_t(i));
            a += glm::dvec3(
                e.estimate(vec3(0.1f, -0.2f, 0.0f), vec3(0, 0, 1), vec3(0.6f), ra, with, &fixed)
                    .total());
            b += glm::dvec3(
                e.estimate(vec3(0.1f, -0.2f, 0.0f), vec3(0, 0, 1), vec3(0.6f), rb, without)
                    .total());
        }
        EXPECT_TRUE(fixed.known) << to_string(m);
        EXPECT_NEAR(a.x, b.x, 1e-5 * b.x) << to_string(m);
        EXPECT_GT(a.x, 0.0) << to_string(m);
        EXPECT_EQ(without.rays - with.rays, paths - 1) << to_string(m);  // one point light
    }
}

// A re-bake after a slider change (Media::set_coefficients, then reset) equals a fresh bake of
// the changed media: nothing the estimator resolved per medium (its table) outlives the change,
// and the change does show (the albedo and g of the fog both move). The vertex correction
// field's geometry (its rays) is what the re-bake keeps, and it does keep it.
TEST(Bake, ReBakeAfterACoefficientChangeEqualsAFreshBake) {
    Fixture f(receiver_scene("0.6", R"([{"sigma_s": 0.3, "sigma_a": 0.05, "g": 0.1}])"));
    BakeSettings s;
    s.spp = 4;
    s.texel_density = 3.0f;
    s.bounces = 1;
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    LightmapBaker rebake(*f.rays, f.media, &tables, BakeMethod::Impulse, s);
    rebake.run();
    const std::vector<float> before = rebake.layers(0).get("lm_inscatter_single").data;
    ASSERT_NE(rebake.vertex_corrections(), nullptr);
    // Held here, so that a geometry traced anew could not take its address.
    const std::shared_ptr<const VertexCorrectionField::Geometry> geometry =
        rebake.vertex_corrections()->geometry();
    f.media.set_coefficients(0, 0.6, 0.02, 0.4, 1.0);
    rebake.reset();
    rebake.run();
    EXPECT_EQ(rebake.vertex_corrections()->geometry(), geometry);
    LightmapBaker fresh(*f.rays, f.media, &tables, BakeMethod::Impulse, s);
    fresh.run();
    const std::vector<float> after = rebake.layers(0).get("lm_inscatter_single").data;
    EXPECT_EQ(after, fresh.layers(0).get("lm_inscatter_single").data);
    EXPECT_NE(after, before);
}

// The tabulated double products (impulse_irradiance.h) against a table query and the O(N)
// double product at random distances, cosines and shifts, in the canonical medium.
TEST(Bake, TabulatedIrradianceMatchesQueryAndDoubleProduct) {
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    const double g = 0.35, albedo = 0.8;
    const ImpulseIrradiance table(tables, g, albedo, tables.bounces());
    double cosine_zh[kImpulseOrder];
    zh_clamped_cosine(kImpulseOrder, cosine_zh);
    CounterRng rng(3, 1, 4, 1);
    double worst = 0.0;
    for (int i = 0; i < 300; ++i) {
        const double D = 0.01 * std::pow(1500.0, rng.next_double());  // 0.01 .. 15
        const double cos = 2.0 * rng.next_double() - 1.0, shift = rng.next_double();
        const int kind = i % 3;
        ImpulseQuery q;
        q.emitter = kind == 0   ? EmitterKind::Point
                    : kind == 1 ? EmitterKind::Directional
                                : EmitterKind::Area;
        q.distance = D;
        q.shift = shift;
        q.medium = {albedo, 1.0 - albedo, g};
        q.last_bounce = tables.bounces();
        const ImpulseResponse r = query_impulse(tables, q);  // probes: receiver in the medium
        ImpulseQuery on_surface = q;                         // lightmap texels
        on_surface.receiver = Receiver::OnSurface;
        const ImpulseResponse texel = query_impulse(tables, on_surface);
        // Receiver normal at `cos` from the single lobe's axis (z); the light axis is z too,
        // except for area emitters whose single lobe is tilted by axis_tilt about y.
        const glm::dvec3 n(std::sqrt(1.0 - cos * cos), 0.0, cos);
        const glm::dvec3 z(0, 0, 1), light(-std::sin(r.axis_tilt), 0.0, std::cos(r.axis_tilt));
        const double single = zh_double_product(kImpulseOrder, r.single.data(), z, cosine_zh, n);
        const glm::dvec3 multiple_axis = q.emitter == EmitterKind::Area ? light : z;
        const double multiple =
            zh_double_product(kImpulseOrder, texel.multiple.data(), multiple_axis, cosine_zh, n);
        const ImpulseIrradiance::At at = ImpulseIrradiance::at(D);
        ScatteredIrradiance e;
        if (kind == 0) e = table.point(at, cos);
        if (kind == 1) e = table.directional(at, cos);
        if (kind == 2) {
            EXPECT_NEAR(table.tilt(at, shift), r.axis_tilt, 2e-3) << D << " " << shift;
            e = table.area(at, shift, cos, glm::dot(multiple_axis, n));
        }
        // Scale: the response's largest magnitude at this distance (its value facing the axis).
        const double scale = std::max(std::abs(single), std::abs(multiple)) +
                             zh_double_product(kImpulseOrder, r.single.data(), z, cosine_zh, z);
        double err = std::max(std::abs(e.single - single), std::abs(e.multiple - multiple)) / scale;
        // The probes' lobes: the response's own first 3 ZH coefficients, against the query's,
        // relative to the largest of them.
        const ImpulseIrradiance::Lobes lobes = table.lobes(q.emitter, at, shift);
        double lobe_scale = 1e-30, lobe_err = 0.0;
        for (int b = 0; b < ImpulseIrradiance::kProbeBands; ++b)
            lobe_scale = std::max(
                {lobe_scale, std::abs(r.single[size_t(b)]), std::abs(r.multiple[size_t(b)])});
        for (int b = 0; b < ImpulseIrradiance::kProbeBands; ++b)
            lobe_err = std::max({lobe_err, std::abs(lobes.single[b] - r.single[size_t(b)]),
                                 std::abs(lobes.multiple[b] - r.multiple[size_t(b)])});
        err = std::max(err, lobe_err / lobe_scale);
        worst = std::max(worst, err);
        EXPECT_LT(err, 5e-3) << "kind " << kind << " D " << D << " cos " << cos << " shift "
                             << shift << ": " << e.single << " vs " << single << ", " << e.multiple
                             << " vs " << multiple;
    }
    std::printf("tabulated irradiance: worst error %.2e of the facing value\n", worst);
}

// Segments through several media (ImpulseIrradianceCache::blend): the bilinear blend of the
// grid's node tables against the table built at the mixture's own (g, albedo), at random
// mixtures (albedo up to 0.999 and exactly 1), distances, cosines and shifts; error relative to
// the facing value as above. A blend is the same whatever order the cells were first met in.
TEST(Bake, MixtureBlendMatchesTheTableOfItsOwnCoefficients) {
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    const ImpulseIrradianceCache cache(tables);
    CounterRng rng(5, 2, 9, 1);
    double worst = 0.0;
    for (int m = 0; m < 8; ++m) {
        const double g = -0.3 + 1.2 * rng.next_double();  // -0.3 .. 0.9
        const double albedo = m == 7 ? 1.0 : 1.0 - std::pow(10.0, -3.0 * rng.next_double());
        const ImpulseIrradiance own(tables, g, albedo, tables.bounces());
        const ImpulseIrradianceBlend blend = cache.blend(g, albedo, tables.bounces());
        ASSERT_GT(blend.count, 0);
        double weights = 0.0;
        for (int k = 0; k < blend.count; ++k) weights += blend.weight[k];
        EXPECT_NEAR(weights, 1.0, 1e-12);
        double worst_here = 0.0;
        for (int i = 0; i < 40; ++i) {
            const double D = 0.01 * std::pow(1500.0, rng.next_double());  // 0.01 .. 15
            const double cos = 2.0 * rng.next_double() - 1.0, shift = rng.next_double();
            const ImpulseIrradiance::At at = ImpulseIrradiance::at(D);
            auto eval = [&](const ImpulseIrradiance& t, int kind) {
                return kind == 0   ? t.point(at, cos)
                       : kind == 1 ? t.directional(at, cos)
                                   : t.area(at, shift, cos, cos);
            };
            for (int kind = 0; kind < 3; ++kind) {
                const ScatteredIrradiance e = eval(own, kind);
                ScatteredIrradiance b;
                for (int k = 0; k < blend.count; ++k) {
                    const ScatteredIrradiance one = eval(*blend.table[k], kind);
                    b.single += blend.weight[k] * one.single;
                    b.multiple += blend.weight[k] * one.multiple;
                }
                const ScatteredIrradiance facing = eval(own, kind == 2 ? 0 : kind);
                const double scale = std::abs(facing.single) + std::abs(facing.multiple) + 1e-30;
                const double err =
                    std::max(std::abs(b.single - e.single), std::abs(b.multiple - e.multiple)) /
                    std::max(scale, std::abs(e.single) + std::abs(e.multiple));
                worst = std::max(worst, err);
                worst_here = std::max(worst_here, err);
                EXPECT_LT(err, 2e-3)
                    << "g " << g << " albedo " << albedo << " kind " << kind << " D " << D << ": "
                    << b.single << " vs " << e.single << ", " << b.multiple << " vs " << e.multiple;
            }
        }
        std::printf("  g %.3f albedo %.5f: worst %.2e\n", g, albedo, worst_here);
    }
    std::printf("mixture blend: worst error %.2e of the facing value (%zu node tables)\n", worst,
                cache.blend_nodes());
}

// Probes: a constant environment gives incident radiance L everywhere, whose order-3 SH is
// L sqrt(4 pi) in the DC term and 0 elsewhere (statistical bounds); in fog, impulse and VPT
// probes agree on single scattering from a point light.
TEST(Bake, ProbesSeeAConstantEnvironmentAndAgreeInFog) {
    Fixture env(R"({"frames": 1, "camera": {"position": [0, -5, 3], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert", "albedo": 0.5}},
      "objects": [{"shape": {"type": "plane", "size": [1, 1]}, "material": "m",
                   "transform": {"translate": [0, 0, -100]}}],
      "lights": [{"type": "envmap", "radiance": 0.5}]})");
    BakeSettings s;
    s.bounces = 0;
    const BakeEstimator surface(*env.rays, env.media, nullptr, BakeMethod::Surface, s);
    double sh[9] = {}, sh2[9] = {};
    const int n = 20000;
    BakeCounters c;
    for (int i = 0; i < n; ++i) {
        CounterRng rng(0, 1, 0, uint64_t(i));
        const BakeEstimator::ProbeParts p = surface.estimate_probe(vec3(0, 0, 1), rng, c);
        for (int k = 0; k < 9; ++k) {
            sh[k] += p.surface[size_t(k)].x / double(n);
            sh2[k] += double(p.surface[size_t(k)].x) * p.surface[size_t(k)].x / double(n);
        }
    }
    EXPECT_NEAR(sh[0], 0.5 * std::sqrt(4.0 * 3.14159265358979), 2e-3);
    for (int k = 1; k < 9; ++k) {
        const double standard_error = std::sqrt((sh2[k] - sh[k] * sh[k]) / n);
        EXPECT_LT(std::abs(sh[k]), 4.5 * standard_error) << "coefficient " << k;
    }

    Fixture fog(R"({"frames": 1, "camera": {"position": [0, -5, 3], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert", "albedo": 0}},
      "objects": [{"shape": {"type": "plane", "size": [1, 1]}, "material": "m",
                   "transform": {"translate": [0, 0, -100]}}],
      "lights": [{"type": "point", "position": [0.4, 0, 1], "intensity": 5}],
      "media": [{"sigma_s": 0.5, "sigma_a": 0.1, "g": 0.2}]})");
    s.media_bounces = 1;
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    const BakeEstimator impulse(*fog.rays, fog.media, &tables, BakeMethod::Impulse, s);
    const BakeEstimator vpt(*fog.rays, fog.media, nullptr, BakeMethod::Vpt, s);
    CounterRng r0(0, 2, 0, 0);
    const BakeEstimator::ProbeParts a = impulse.estimate_probe(vec3(0, 0, 0), r0, c);
    glm::dvec3 b[9] = {};
    std::vector<std::array<glm::dvec3, 9>> partial(8);
    tbb::parallel_for(0, 8, [&](int chunk) {
        BakeCounters cc;
        for (int i = chunk; i < 64000; i += 8) {
            CounterRng rng(0, 3, 0, uint64_t(i));
            const BakeEstimator::ProbeParts p = vpt.estimate_probe(vec3(0, 0, 0), rng, cc);
            for (int k = 0; k < 9; ++k)
                partial[size_t(chunk)][size_t(k)] += glm::dvec3(p.single[size_t(k)]) / 64000.0;
        }
    });
    for (const auto& p : partial)
        for (int k = 0; k < 9; ++k) b[k] += p[size_t(k)];
    // DC and the linear band along the light's axis carry the lobe.
    EXPECT_NEAR(a.single[0].x, b[0].x, 0.03 * b[0].x);
    std::printf("probe single scattering DC: impulse %.5f vpt %.5f\n", a.single[0].x, b[0].x);
    EXPECT_GT(a.single[0].x, 0.0f);
}

// --debug-texel and the workbench's texel trace re-run a texel's paths with the bake's own keys
// (texel_random): on a lightmap other than the first, texel_estimate is what the bake stored
// there. Keyed as lightmap 0 (the bug this guards against) it is not.
TEST(Bake, TexelEstimateIsWhatTheBakeStoredOnEveryLightmap) {
    Fixture f(kPlaneAndBox);
    BakeSettings s;
    s.spp = 4;
    s.bounces = 1;
    s.texel_density = 4.0f;
    LightmapBaker baker(*f.rays, f.media, nullptr, BakeMethod::Surface, s);
    baker.run();
    ASSERT_EQ(baker.lightmaps().size(), 2u);
    const size_t box = 1;
    const ObjectLightmap& map = baker.lightmaps()[box];
    const LayerSet baked = baker.layers(box);
    const Layer& stored = baked.get("lm_irradiance");
    const BakeEstimator estimator(*f.rays, f.media, nullptr, BakeMethod::Surface, s);
    int checked = 0, differs_as_lightmap0 = 0;
    for (size_t i = 0; i < map.texels.size() && checked < 40; i += 3) {
        if (map.texels[i].state != TexelState::Valid) continue;
        ++checked;
        const vec3 mine =
            texel_estimate(estimator, baker.lightmaps(), box, i, s.seed, s.spp).total();
        const float baked = stored.data[i * 3];
        EXPECT_NEAR(mine.x, baked, 1e-5f * std::max(1.0f, baked)) << "texel " << i;
        IrradianceParts as0;
        BakeCounters c;
        for (int k = 0; k < s.spp; ++k) {
            CounterRng rng = texel_random(s.seed, 0, i, k);
            as0 += estimator.estimate(map.texels[i].position, map.texels[i].normal,
                                      map.texels[i].albedo, rng, c);
        }
        if (std::abs(as0.total().x / float(s.spp) - baked) > 1e-3f * std::max(1.0f, baked))
            ++differs_as_lightmap0;
    }
    EXPECT_GE(checked, 20);
    EXPECT_GT(differs_as_lightmap0, checked / 2);
}

namespace {

// A floor, a box on it and a point light, in fog: the texel-estimate tests' scene.
constexpr const char* kFloorAndBoxByALampInFog =
    R"({"frames": 1, "camera": {"position": [0, -5, 3], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert", "albedo": 0.7}},
      "objects": [{"shape": {"type": "plane", "size": [4, 4]}, "material": "m"},
                  {"shape": {"type": "box", "size": [1, 1, 1]}, "material": "m",
                   "transform": {"translate": [0.8, 0, 0.5]}}],
      "lights": [{"type": "point", "position": [-0.5, -0.5, 2.0], "intensity": 8}],
      "media": [{"sigma_s": 0.4, "sigma_a": 0.05, "g": 0.3,
                 "bounds": {"box": {"min": [-2, -2, 0], "max": [2, 2, 2.5]}}}]})";

// Their bake: 8 paths a texel, one bounce, 4 texels/unit, no probes.
BakeSettings small_texel_bake() {
    BakeSettings s;
    s.spp = 8;
    s.bounces = 1;
    s.texel_density = 4.0f;
    s.probes_x = 0;
    return s;
}

}  // namespace

// bake.texel_terms = field: a texel reads the vertex correction field at itself instead of
// running its own Monte Carlo terms. texel_estimate (--debug-texel) re-runs it through the same
// BakeEstimator::estimate_texel: what the bake stored, each path recording what it read.
TEST(Bake, TexelsReadingTheFieldAreWhatTheBakeStoredAndTheirPathsSaySo) {
    Fixture f(kFloorAndBoxByALampInFog);
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    BakeSettings s = small_texel_bake();
    s.texel_terms = TexelTerms::Field;
    LightmapBaker baker(*f.rays, f.media, &tables, BakeMethod::Impulse, s);
    baker.run();
    EXPECT_EQ(baker.stats().texel_terms, "field");
    const ObjectLightmap& floor = baker.lightmaps()[0];
    const LayerSet baked = baker.layers(0);
    const Layer& stored = baked.get("lm_irradiance");
    BakeEstimator estimator(*f.rays, f.media, &tables, BakeMethod::Impulse, s);
    EXPECT_FALSE(estimator.texel_reads_field());  // no field yet: the texels run their own
    estimator.set_vertex_corrections(baker.vertex_corrections());
    ASSERT_TRUE(estimator.texel_reads_field());
    int checked = 0, added = 0;
    for (size_t i = 0; i < floor.texels.size() && checked < 30; i += 5) {
        if (floor.texels[i].state != TexelState::Valid) continue;
        ++checked;
        TexelFilterUse use;
        const float mine =
            texel_estimate(estimator, baker.lightmaps(), 0, i, s.seed, s.spp, &use).total().x;
        const float baked_value = stored.data[i * 3];
        EXPECT_NEAR(mine, baked_value, 1e-5f * std::max(1.0f, baked_value)) << "texel " << i;
        ASSERT_EQ(use.paths.size(), size_t(s.spp));
        for (const TexelPathRecord& r : use.paths) {
            EXPECT_TRUE(r.texel_field.read);
            EXPECT_FALSE(r.mc_ran);  // no Monte Carlo terms of its own
            EXPECT_EQ(luminance(r.deferred.total()), 0.0f);
        }
        added += use.paths.front().texel_field.holds &&
                 luminance(use.paths.front().texel_field.added) > 0.0f;
    }
    EXPECT_GE(checked, 20);
    EXPECT_GE(added, checked / 2);  // the field brought the lit medium and the walk's light
}

// The field's prepass decides a texel's side of the shadows among its neighbours by
// fixed_light_shadows (its shadow rays alone): the shadows its first path learns, on every
// floor texel, the box's shadow and the box's own texels below the lamp's horizon included.
TEST(Bake, FixedLightShadowsAreWhatTheFirstPathLearns) {
    Fixture f(kFloorAndBoxByALampInFog);
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    const BakeSettings s = small_texel_bake();
    const LightmapBaker baker(*f.rays, f.media, &tables, BakeMethod::Impulse, s);
    const BakeEstimator estimator(*f.rays, f.media, &tables, BakeMethod::Impulse, s);
    int checked = 0, shadowed = 0;
    for (const ObjectLightmap& map : baker.lightmaps())
        for (size_t i = 0; i < map.texels.size(); ++i) {
            const LightmapTexel& t = map.texels[i];
            if (t.state != TexelState::Valid) continue;
            BakeCounters counters;
            BakeEstimator::FixedDirect fixed;
            CounterRng rng(1, 2, i, 0);
            estimator.estimate(t.position, t.normal, t.albedo, rng, counters, &fixed);
            ASSERT_TRUE(fixed.known);
            const uint64_t rays = estimator.fixed_light_shadows(t.position, t.normal, counters);
            EXPECT_EQ(rays, fixed.shadows) << "texel " << i;
            ++checked;
            shadowed += fixed.shadows != 0;
        }
    EXPECT_GT(checked, 200);
    EXPECT_GT(shadowed, 20);
    EXPECT_LT(shadowed, checked - 20);
}

// With texels reading the field, a computed texel whose surface holds few of the prepass's
// lattice texels within its mean's reach (the box's 4 x 4-texel faces; chart edges) runs up to
// kFieldMaxBoost (3) times the paths: its mean rests on about as many paths as a texel's amid
// a wide chart. Without texels reading it (own terms), every computed texel runs the same.
TEST(Bake, FieldPrepassRaisesThePathsWhereFewTexelsShareAMean) {
    Fixture f(kFloorAndBoxByALampInFog);
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    BakeSettings s = small_texel_bake();
    s.spp = 64;  // 64 x 0.02 x 2.5: 4 paths a computed texel in field mode, 1 otherwise
    const std::vector<ObjectLightmap> maps =
        LightmapBaker(*f.rays, f.media, &tables, BakeMethod::Impulse, s).lightmaps();
    // Amid the floor's chart a window holds the whole 3 x 3 lattice; a face of the box (4 x 4
    // texels) at most 2 x 2 of it, and the texel itself.
    int floor_most = 0, box_most = 0;
    for (size_t m = 0; m < maps.size(); ++m)
        for (size_t i = 0; i < maps[m].texels.size(); ++i)
            (m == 0 ? floor_most : box_most) =
                std::max(m == 0 ? floor_most : box_most, texel_filter_capacity(maps[m], i, 2, 2));
    EXPECT_EQ(floor_most, 9);
    EXPECT_LE(box_most, 5);
    for (TexelTerms terms : {TexelTerms::Field, TexelTerms::Own}) {
        s.texel_terms = terms;
        const VertexCorrectionField field(*f.rays, f.media, &tables, s, maps);
        const long nominal = field.computed_texels() * field.paths_per_texel();
        if (terms == TexelTerms::Field) {
            EXPECT_EQ(field.paths_per_texel(), 4);
            EXPECT_GT(field.paths_run(), nominal);
            EXPECT_LE(field.paths_run(), 3 * nominal);
        } else {
            EXPECT_EQ(field.paths_per_texel(), 1);
            EXPECT_EQ(field.paths_run(), nominal);
        }
    }
}

// Impulse defers its Monte Carlo terms and the baker filters them over neighbouring texels
// (volume/texel_filter.h): texel_estimate, what --debug-texel prints, re-runs the window and
// filters it the same way, so it is still what the bake stored; unfiltered it is not.
TEST(Bake, ImpulseTexelEstimateIsTheFilteredBakedTexel) {
    Fixture f(kFloorAndBoxByALampInFog);
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    BakeSettings s = small_texel_bake();
    s.texel_mc_rate = 0.25f;
    s.texel_mc_radius = 2;
    LightmapBaker baker(*f.rays, f.media, &tables, BakeMethod::Impulse, s);
    baker.run();
    const ObjectLightmap& floor = baker.lightmaps()[0];
    const LayerSet baked = baker.layers(0);
    const Layer& stored = baked.get("lm_irradiance");
    // The estimator as the baker ran it: with the baker's vertex correction field.
    BakeEstimator estimator(*f.rays, f.media, &tables, BakeMethod::Impulse, s);
    ASSERT_NE(baker.vertex_corrections(), nullptr);
    estimator.set_vertex_corrections(baker.vertex_corrections());
    BakeSettings own = s;
    own.texel_mc_radius = 0;
    BakeEstimator unfiltered(*f.rays, f.media, &tables, BakeMethod::Impulse, own);
    unfiltered.set_vertex_corrections(baker.vertex_corrections());
    // What --debug-texel reports beside it: the texel's own rate and its filter's window.
    const std::vector<float> rates = texel_mc_rates(floor, estimator);
    int checked = 0, differs_unfiltered = 0, averaged = 0, ran_mc = 0, bounces = 0;
    for (size_t i = 0; i < floor.texels.size() && checked < 30; i += 5) {
        if (floor.texels[i].state != TexelState::Valid) continue;
        ++checked;
        const float baked = stored.data[i * 3];
        TexelFilterUse use, use_alone;
        const float mine =
            texel_estimate(estimator, baker.lightmaps(), 0, i, s.seed, s.spp, &use).total().x;
        EXPECT_NEAR(mine, baked, 1e-5f * std::max(1.0f, baked)) << "texel " << i;
        EXPECT_EQ(use.mc_rate, rates[i]) << "texel " << i;
        EXPECT_GE(use.texels, 1);
        EXPECT_LE(use.texels, 25);
        averaged += use.texels > 1;
        // Its paths as the bake ran them: they sum to its sums, and a path's deferred terms
        // are its recorded terms (the lit medium, the walk) times 1 / rate where they ran.
        ASSERT_EQ(use.paths.size(), size_t(s.spp));
        vec3 path_sum(0.0f), deferred_sum(0.0f);
        for (const TexelPathRecord& r : use.paths) {
            path_sum += r.path.total();
            deferred_sum += r.deferred.total();
            if (r.bounce.hit) {
                // The indirect segment's vertex, as far from the texel as the ray went.
                ++bounces;
                EXPECT_NEAR(r.bounce.distance,
                            glm::length(r.bounce.position - floor.texels[i].position), 1e-3f);
                EXPECT_GE(r.bounce.object, 0);
            }
            if (!r.mc_ran) {
                EXPECT_EQ(r.deferred.total(), vec3(0.0f));
                continue;
            }
            ++ran_mc;
            EXPECT_FLOAT_EQ(r.mc_weight, 1.0f / use.mc_rate);
            vec3 terms = r.walk.total() + r.hidden.total();
            for (const TexelPathRecord::Term& t : r.terms)
                if (t.occluded) terms += t.value.total();
            EXPECT_NEAR(r.deferred.total().x, terms.x * r.mc_weight,
                        1e-4f * std::max(1.0f, terms.x * r.mc_weight));
        }
        EXPECT_NEAR(path_sum.x, use.sum.total().x, 1e-4f * std::max(1.0f, path_sum.x));
        EXPECT_NEAR(deferred_sum.x, use.deferred.total().x, 1e-4f * std::max(1.0f, deferred_sum.x));
        const float alone =
            texel_estimate(unfiltered, baker.lightmaps(), 0, i, s.seed, s.spp, &use_alone)
                .total()
                .x;
        EXPECT_EQ(use_alone.texels, 1);
        if (std::abs(alone - baked) > 1e-3f * std::max(1.0f, baked)) ++differs_unfiltered;
    }
    EXPECT_GE(checked, 20);
    EXPECT_GT(differs_unfiltered, checked / 2);
    EXPECT_GT(averaged, checked / 2);
    EXPECT_GT(ran_mc, checked) << "at rate 0.25 about 2 of 8 paths a texel run the terms";
    EXPECT_GT(bounces, 10) << "some of the floor's bounces reach the box (the rest escape)";
    // The lightmapped preview shows each pixel's nearest texel's window (texel_mc_window).
    std::vector<LayerSet> all;
    for (size_t m = 0; m < baker.lightmaps().size(); ++m) all.push_back(baker.layers(m));
    const LayerSet preview =
        render_lightmap_preview(*f.rays, f.scene.camera.at(0.0f), 64, 48, baker.lightmaps(), all);
    const Layer* window = preview.find("texel_mc_window");
    ASSERT_NE(window, nullptr);
    const Layer& texel = preview.get("lightmap_texel");
    int seen = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 64; ++x) {
            const int m = int(texel.at(64, x, y, 2));
            if (m < 0) continue;
            const ObjectLightmap& map = baker.lightmaps()[size_t(m)];
            const size_t i =
                size_t(texel.at(64, x, y, 1)) * size_t(map.width) + size_t(texel.at(64, x, y, 0));
            EXPECT_EQ(window->at(64, x, y, 0), all[size_t(m)].get("texel_mc_window").data[i]);
            seen += window->at(64, x, y, 0) > 1.0f;
        }
    EXPECT_GT(seen, 100) << "most of the floor's texels average several";
}

// The filter of the deferred terms: a constant field stays constant (a box filter of the
// texel's own surface); texels across a shadow's edge (a different occluded-light mask), on
// another chart (the box's faces next to the floor's texels in the atlas) or with twice the
// light are never averaged in.
TEST(Bake, TexelFilterAveragesOnlyTheTexelsOwnSurfaceAndShadowSide) {
    Fixture f(kPlaneAndBox);
    AtlasSettings a;
    a.texel_density = 4.0f;
    const std::vector<ObjectLightmap> maps = build_lightmaps(*f.rays, a);
    ASSERT_EQ(maps.size(), 2u);
    long full = 0;  // texels whose window is whole
    for (const ObjectLightmap& map : maps) {
        const size_t n = map.texels.size();
        TexelFilterGuide guide;  // without the sums' variance and scattered light
        guide.shadows.assign(n, 0);
        guide.light.assign(n, 1.0f);
        std::vector<IrradianceParts> sums(n);
        for (size_t i = 0; i < n; ++i) {
            const LightmapTexel& t = map.texels[i];
            // Left of x = 0 "in a shadow", with a field of 10 there and 1 elsewhere.
            guide.shadows[i] = t.position.x < 0.0f ? 1 : 0;
            sums[i].single =
                vec3(t.state == TexelState::Valid ? (guide.shadows[i] ? 10.0f : 1.0f) : 1000.0f);
        }
        std::vector<int> window;  // what the texel_mc_window layer shows
        const std::vector<IrradianceParts> out =
            filter_texel_sums(map, sums, guide, 2, nullptr, &window);
        ASSERT_EQ(window.size(), n);
        long averaged = 0;
        for (size_t i = 0; i < n; ++i) {
            if (map.texels[i].state != TexelState::Valid) {
                EXPECT_EQ(out[i].single.x, 0.0f);
                EXPECT_EQ(window[i], 0);
                continue;
            }
            EXPECT_FLOAT_EQ(out[i].single.x, sums[i].single.x) << "texel " << i;
            const std::vector<size_t> near = texel_filter_neighbours(map, guide, i, 2);
            EXPECT_EQ(window[i], int(near.size())) << "texel " << i;
            full += window[i] == 25;
            averaged += long(near.size());
            for (size_t j : near) {
                EXPECT_GT(glm::dot(map.texels[j].normal, map.texels[i].normal), 0.9f);
                EXPECT_EQ(guide.shadows[j], guide.shadows[i]);
            }
        }
        EXPECT_GT(averaged, long(map.count(TexelState::Valid)) * 4) << "the filter averages";
        // A neighbour with twice the light is left out.
        for (size_t i = 0; i < n; ++i) {
            if (map.texels[i].state != TexelState::Valid) continue;
            const std::vector<size_t> near = texel_filter_neighbours(map, guide, i, 1);
            if (near.size() < 3) continue;
            const size_t j = near[0] == i ? near[1] : near[0];
            guide.light[j] = 2.0f;
            const std::vector<size_t> after = texel_filter_neighbours(map, guide, i, 1);
            EXPECT_EQ(after.size(), near.size() - 1);
            EXPECT_EQ(std::count(after.begin(), after.end(), j), 0);
            break;
        }
    }
    EXPECT_GT(full, 0) << "texels amid the floor average the whole 5 x 5 window";
}

// The light-level test reads the sums as estimates: a sum of 16 paths of which one caught 1.0
// (variance 1 - 1/16) agrees with a dark neighbour's 0, a sum of 16 paths of 0.0625 each (no
// variance) does not, nor does one path alone (no variance known), nor a noisy sum whose
// scattered light differs (it sees lit medium the dark texel does not); within the ratio they
// agree whatever the variance.
TEST(Bake, TexelFilterLightTestAllowsForTheSumsNoise) {
    BakeEstimator::FixedDirect none;
    const auto light_of = [](float v) {
        IrradianceParts p;
        p.surface = vec3(v);
        return p;
    };
    TexelFilterGuide guide = TexelFilterGuide::sized(6);
    set_texel_filter_guide(guide, 0, none, light_of(0.0f), 0.0f, 16);
    set_texel_filter_guide(guide, 1, none, light_of(1.0f), 1.0f, 16);  // one path of 1
    set_texel_filter_guide(guide, 2, none, light_of(1.0f), 16 * 0.0625f * 0.0625f, 16);
    set_texel_filter_guide(guide, 3, none, light_of(1.0f), 1.0f, 1);
    set_texel_filter_guide(guide, 4, none, light_of(1.4f), 0.0f, 16);
    IrradianceParts seeing_medium = light_of(0.5f);
    seeing_medium.single = vec3(0.5f);
    set_texel_filter_guide(guide, 5, none, seeing_medium, 1.0f, 16);
    EXPECT_NEAR(guide.variance[1], 1.0f - 1.0f / 16.0f, 1e-6f);
    EXPECT_NEAR(guide.variance[2], 0.0f, 1e-6f);
    EXPECT_EQ(guide.variance[3], 0.0f);
    EXPECT_TRUE(texel_lights_agree(guide, 0, 1));
    EXPECT_TRUE(texel_lights_agree(guide, 1, 0));
    EXPECT_FALSE(texel_lights_agree(guide, 0, 2));
    EXPECT_FALSE(texel_lights_agree(guide, 0, 3));
    EXPECT_TRUE(texel_lights_agree(guide, 2, 4));  // within the ratio
    EXPECT_TRUE(texel_lights_agree(guide, 0, 0));  // dark texels agree
    EXPECT_NEAR(guide.variance[5], guide.variance[1], 1e-6f);
    EXPECT_FALSE(texel_lights_agree(guide, 0, 5));
    // A guide without variances keeps the ratio alone.
    TexelFilterGuide plain{guide.shadows, guide.light, {}, {}};
    EXPECT_FALSE(texel_lights_agree(plain, 0, 1));
}

// The method names joined by any separator, NULs included: the workbench's bake-method combo is
// a NUL-separated list (it showed nothing when the list was cut at the first NUL).
TEST(Bake, MethodListKeepsEverySeparator) {
    EXPECT_EQ(bake_method_list(), "surface|extinction|impulse|vpt");
    const std::string combo = bake_method_list(std::string(1, '\0'));
    EXPECT_EQ(combo, std::string("surface\0extinction\0impulse\0vpt", 30));
    EXPECT_EQ(parse_bake_method("vpt"), BakeMethod::Vpt);
    EXPECT_THROW(parse_bake_method("walk"), Error);
}

namespace {

// The field tests' scene: an 8 x 8 floor (albedo 0.6) in fog, `objects` after it (each
// preceded by a comma), lit by `light`.
std::string fog_floor_scene(
    const std::string& objects,
    const std::string& light =
        R"({"type": "directional", "direction": [0.3, 0.2, -1], "irradiance": 3})") {
    return R"({"frames": 1, "camera": {"position": [0, -9, 5], "look_at": [0, 0, 0]},
      "materials": {"m": {"type": "lambert", "albedo": 0.6}},
      "objects": [{"name": "floor", "shape": {"type": "plane", "size": [8, 8]}, "material": "m"})" +
           objects + R"(],
      "lights": [)" +
           light + R"(],
      "media": [{"sigma_s": 0.08, "sigma_a": 0.01, "g": 0.3,
                 "bounds": {"box": {"min": [-4, -4, 0], "max": [4, 4, 4]}}}]})";
}

// An impulse bake at 1 texel per unit without probes: the vertex correction field's tests.
std::unique_ptr<LightmapBaker> bake_field(const Fixture& f, int spp) {
    BakeSettings s;
    s.spp = spp;
    s.bounces = 2;
    s.texel_density = 1.0f;
    s.probes_x = 0;
    auto baker = std::make_unique<LightmapBaker>(
        *f.rays, f.media, &test_support::shared_impulse_tables(), BakeMethod::Impulse, s);
    baker->run();
    return baker;
}

// The floor (object 0) under (x, y), by a ray down from height `from_z`.
SurfaceHit floor_hit(const Fixture& f, float x, float y, float from_z) {
    const SurfaceHit hit =
        f.rays->intersect(Ray{vec3(x, y, from_z), vec3(0, 0, -1), 0.0f, from_z + 1.0f});
    EXPECT_TRUE(hit.valid && hit.object == 0) << x << ", " << y;
    return hit;
}

// The floor under a lid (no lightmap) `height` above it, covering x < 1.3, lit by a sky.
std::string sky_lid_scene(float height) {
    return fog_floor_scene(
        R"(,
                  {"name": "lid", "shape": {"type": "plane", "size": [5.3, 8]}, "material": "m",
                   "lightmap": false,
                   "transform": {"translate": [-1.35, 0, )" +
            std::to_string(height) + R"(], "rotate": {"axis": [1, 0, 0], "deg": 180}}})",
        R"({"type": "sky", "sun_direction": [0.45, -0.35, 0.55], "sun_radiance": 0})");
}

// The texel of `map` that `hit` lands in (the field's nearest-texel rule).
const LightmapTexel& texel_at(const Fixture& f, const ObjectLightmap& map, const SurfaceHit& hit) {
    vec2 uv;
    EXPECT_TRUE(lightmap_uv(*f.rays, map, hit, &uv));
    const int x = std::clamp(int(uv.x), 0, map.width - 1);
    const int y = std::clamp(int(uv.y), 0, map.height - 1);
    return map.texels[size_t(y) * size_t(map.width) + size_t(x)];
}

}  // namespace

// A closed room (walls 0.15 thick at half-width 1.1-1.25, a canopy reaching past them as its
// ceiling) on a sunlit floor in fog, baked at 1 texel per unit: the floor's texels centred at
// x = 1.5 lie outside, their footprints reach into the room. Impulse's deeper vertices read the
// vertex correction field at the texel they land in; one landing inside read the sunlit side's
// value (valley's houses: a roof's underside across its walls, lm_irradiance relMSE 146 against
// VPT, 1.6 with the fix). The field now answers a hit in a straddling texel only when the hit
// sees the texel's centre.
TEST(Bake, VertexCorrectionFieldDoesNotLeakThroughWallsCrossingItsTexels) {
    namespace fs = std::filesystem;
    const fs::path obj = fs::temp_directory_path() / "freqlab_room_walls.obj";
    {
        std::ofstream out(obj);
        // Four wall slabs, 0.15 thick, from the floor to the canopy: each side's quad facing out
        // (outer, half-width 1.25) and facing in (inner, 1.1).
        int v = 1;
        auto quad = [&](vec3 a, vec3 b, vec3 c, vec3 d, bool inward) {
            for (const vec3& p : {a, b, c, d})
                out << "v " << p.x << " " << p.y << " " << p.z << "\n";
            if (inward)
                out << "f " << v << " " << v + 2 << " " << v + 1 << "\nf " << v << " " << v + 3
                    << " " << v + 2 << "\n";
            else
                out << "f " << v << " " << v + 1 << " " << v + 2 << "\nf " << v << " " << v + 2
                    << " " << v + 3 << "\n";
            v += 4;
        };
        for (const float s : {1.25f, 1.1f}) {
            const float h = 1.5f;
            const bool inward = s < 1.2f;
            quad({s, -s, 0}, {s, s, 0}, {s, s, h}, {s, -s, h}, inward);      // +x
            quad({-s, s, 0}, {-s, -s, 0}, {-s, -s, h}, {-s, s, h}, inward);  // -x
            quad({s, s, 0}, {-s, s, 0}, {-s, s, h}, {s, s, h}, inward);      // +y
            quad({-s, -s, 0}, {s, -s, 0}, {s, -s, h}, {-s, -s, h}, inward);  // -y
        }
    }
    Fixture f(fog_floor_scene(R"(,
                  {"name": "canopy", "shape": {"type": "plane", "size": [5, 5]}, "material": "m",
                   "transform": {"translate": [0, 0, 1.5], "rotate": {"axis": [1, 0, 0], "deg": 180}}},
                  {"name": "walls", "mesh": ")" +
                              obj.string() + R"(", "material": "m", "lightmap": false})"));
    const std::unique_ptr<LightmapBaker> baker = bake_field(f, 16);
    const VertexCorrectionField* field = baker->vertex_corrections();
    ASSERT_NE(field, nullptr);
    EXPECT_GT(field->straddling_texels(), 0);
    // Hits on the floor, from 1 unit above (under the canopy).
    auto hit = [&](float x, float y) { return floor_hit(f, x, y, 1.0f); };
    // The texel covering x in [1, 2] (centre 1.5, outside): inside the room it is not read...
    EXPECT_FALSE(field->locate(hit(1.05f, 0.3f)).found());
    EXPECT_FALSE(field->locate(hit(0.3f, -1.05f)).found());
    // ... outside it is; and inside, texels the walls do not cross are read.
    EXPECT_TRUE(field->locate(hit(1.8f, 0.3f)).found());
    EXPECT_TRUE(field->locate(hit(0.5f, 0.4f)).found());
    // The lookups' visibility rays are counted (the bake's stats.rays): one or two on a texel
    // the walls cross, none on one they do not.
    long rays = 0;
    field->locate(hit(1.05f, 0.3f), &rays);
    EXPECT_GE(rays, 1);
    EXPECT_LE(rays, 2);
    rays = 0;
    EXPECT_TRUE(field->locate(hit(0.5f, 0.4f), &rays).found());
    EXPECT_EQ(rays, 0);
}

// A lid 0.02 above a floor lit by a lamp beside it, ending inside a floor texel whose centre
// (x = 1.5) is in the open: the lid's underside sends its paths into the gap, where they land
// in that texel. Valley's layered IFC walls (0.025 apart) did this: the gap's hits read the
// lamp-lit centre's surface light, +0.14 where VPT reads 0 (90 % of the bake's relMSE). The
// rays that find walls crossing a footprint run 0.1 texel high, above such a gap; a footprint
// partly covered close above straddles too, and a hit reads it only when covered as the centre
// is. And a field texel keeps the shadows of its point and directional lights: a hit shadowed
// otherwise does not read it.
TEST(Bake, VertexCorrectionFieldIsNotReadInAGapUnderALid) {
    Fixture f(fog_floor_scene(R"(,
                  {"name": "lid", "shape": {"type": "plane", "size": [5.3, 8]}, "material": "m",
                   "transform": {"translate": [-1.35, 0, 0.02],
                                 "rotate": {"axis": [1, 0, 0], "deg": 180}}})",
                              R"({"type": "point", "position": [3, 0, 2], "intensity": 20})"));
    const std::unique_ptr<LightmapBaker> baker = bake_field(f, 4);
    const VertexCorrectionField* field = baker->vertex_corrections();
    ASSERT_NE(field, nullptr);
    // In the gap, within the texel whose centre is in the open: not read.
    EXPECT_FALSE(field->locate(floor_hit(f, 1.1f, 0.3f, 0.01f)).found());
    EXPECT_FALSE(field->locate(floor_hit(f, 1.2f, -0.4f, 0.01f)).found());
    // In the open part of that texel: read, for points that see the lamp as its centre does.
    const VertexCorrectionField::Texel open = field->locate(floor_hit(f, 1.8f, 0.3f, 1.0f));
    ASSERT_TRUE(open.found());
    EXPECT_TRUE(open.holds_for(0));
    EXPECT_FALSE(open.holds_for(1));  // light 0 occluded: not like the centre
}

// A pocket 0.1 high over a floor at 1 texel per unit, closed by a wall standing exactly on a
// texel's centre (x = 1.5) and open on the far side; a partition at y = 0.8 crosses the texels
// (they straddle). Valley's layered IFC walls are so (pockets 0.025 wide, walls at round
// coordinates, where texel centres fall): a hit in a pocket, lifted by the straddle test's 0.1
// texel, came out through the pocket's far wall, and its ray to the lifted centre ended on the
// centre's wall plane, unblocked: the pocket read the other side's value (house10:98,270: 0.20
// where VPT reads 0). Here the old ray read the texel from the wall's open side through that
// plane. The ray now runs from the hit itself to the lifted centre and on past it: a centre on
// a wall is read from neither side, a clear one from its own side only.
TEST(Bake, VertexCorrectionFieldIsNotReadAcrossAWallOnTheTexelCentre) {
    Fixture f(fog_floor_scene(R"(,
                  {"name": "wall", "shape": {"type": "plane", "size": [1, 8]}, "material": "m",
                   "lightmap": false, "transform": {"translate": [1.5, 0, 0.5],
                                                    "rotate": {"axis": [0, 1, 0], "deg": -90}}},
                  {"name": "lid", "shape": {"type": "plane", "size": [0.4, 8]}, "material": "m",
                   "lightmap": false, "transform": {"translate": [1.7, 0, 0.1],
                                                    "rotate": {"axis": [1, 0, 0], "deg": 180}}},
                  {"name": "partition", "shape": {"type": "plane", "size": [2, 1]},
                   "material": "m", "lightmap": false,
                   "transform": {"translate": [2, 0.8, 0.5],
                                 "rotate": {"axis": [1, 0, 0], "deg": 90}}})"));
    const std::unique_ptr<LightmapBaker> baker = bake_field(f, 4);
    const VertexCorrectionField* field = baker->vertex_corrections();
    ASSERT_NE(field, nullptr);
    const ObjectLightmap& floor = baker->lightmaps().at(0);
    auto centre_x = [&](const SurfaceHit& hit) {
        const LightmapTexel& t = texel_at(f, floor, hit);
        EXPECT_EQ(t.state, TexelState::Valid);
        return t.position.x;
    };
    const SurfaceHit in_pocket = floor_hit(f, 1.6f, 0.4f, 0.05f);
    EXPECT_NEAR(centre_x(in_pocket), 1.5f, 1e-5f);
    EXPECT_FALSE(field->locate(in_pocket).found());
    EXPECT_FALSE(field->locate(floor_hit(f, 1.9f, 0.3f, 0.05f)).found());
    EXPECT_FALSE(field->locate(floor_hit(f, 1.3f, 0.4f, 1.0f)).found());
    // The next texel (centre 2.5, clear), crossed by the partition: read on its centre's side.
    const SurfaceHit near_side = floor_hit(f, 2.4f, 0.3f, 1.0f);
    EXPECT_NEAR(centre_x(near_side), 2.5f, 1e-5f);
    long rays = 0;
    EXPECT_TRUE(field->locate(near_side, &rays).found());
    EXPECT_GE(rays, 1);
    EXPECT_FALSE(field->locate(floor_hit(f, 2.4f, 0.9f, 1.0f)).found());
}

// A closed crate on a sunlit floor in fog, at 1 texel per unit: the floor's texels under it lie
// inside geometry; the two rings of them nearest its walls were dilated from the sunlit texels
// outside, and the field held there for any hit. Valley's hits in the closed cavities of its
// layered IFC walls read lit walls' values so (houses' lm_irradiance where VPT reads 0: 0.09;
// the bake's relMSE 2.11 -> 1.89). A hit whose nearest texel is not valid reads no field: it
// keeps its tables, as on an object without a lightmap.
TEST(Bake, VertexCorrectionFieldIsReadOnValidTexelsOnly) {
    Fixture f(fog_floor_scene(R"(,
                  {"name": "crate", "shape": {"type": "box", "size": [4, 4, 2]}, "material": "m",
                   "lightmap": false, "transform": {"translate": [0, 0, 0.95]}})"));
    const std::unique_ptr<LightmapBaker> baker = bake_field(f, 4);
    const VertexCorrectionField* field = baker->vertex_corrections();
    ASSERT_NE(field, nullptr);
    const ObjectLightmap& floor = baker->lightmaps().at(0);
    auto state_at = [&](const SurfaceHit& hit) { return texel_at(f, floor, hit).state; };
    // Inside the crate: one texel in from its wall (the dilated ring) and at its centre.
    for (const vec2 p : {vec2(1.6f, 0.3f), vec2(0.3f, 0.2f), vec2(-1.4f, -0.6f)}) {
        const SurfaceHit inside = floor_hit(f, p.x, p.y, 1.0f);
        EXPECT_NE(state_at(inside), TexelState::Valid) << p.x << ", " << p.y;
        EXPECT_FALSE(field->locate(inside).found()) << p.x << ", " << p.y;
    }
    // Outside, on valid texels: read from above (the floor's front), not from below (a texel
    // holds its front's terms; valley's one-sided house walls passed the lit outside's
    // through).
    for (const vec2 p : {vec2(3.0f, 0.3f), vec2(-2.6f, 2.7f)}) {
        const SurfaceHit outside = floor_hit(f, p.x, p.y, 1.0f);
        EXPECT_EQ(state_at(outside), TexelState::Valid) << p.x << ", " << p.y;
        EXPECT_TRUE(field->locate(outside).found()) << p.x << ", " << p.y;
        const SurfaceHit below =
            f.rays->intersect(Ray{vec3(p.x, p.y, -1.0f), vec3(0, 0, 1), 0.0f, 2.0f});
        ASSERT_TRUE(below.valid && below.object == 0 && below.back_face);
        EXPECT_FALSE(field->locate(below).found()) << p.x << ", " << p.y;
    }
}

// A floor under a lid 0.03 above it in haze, lit by a sky: the texels under the lid see the sky
// only at grazing angles through the gap, where the tables' single scattering of such a sample
// (an infinite medium around the receiver) is large and the real one about 0: its correction
// through the real media is about minus it. Drawn on a fraction of the paths and added to the
// tables of every path, a correction that met such a sample put its texel far below 0 (here
// -0.85 against the open floor's 0.27 at 16 spp; valley at 4 texels/unit: -1.5 where VPT reads
// 0). Filed with the tables' value of their own connections, the corrections scale the
// texel's own tables by their ratio (-0.006 here; VPT at 512 spp: under the lid 0.0001, open
// 0.271; impulse's open floor 0.261 with the ratio, 0.286 without).
TEST(Bake, SingleCorrectionsTravelWithTheTablesOfTheirConnections) {
    Fixture f(sky_lid_scene(0.03f));
    BakeSettings s;
    s.spp = 16;
    s.texel_density = 4.0f;
    s.probes_x = 0;
    LightmapBaker baker(*f.rays, f.media, &test_support::shared_impulse_tables(),
                        BakeMethod::Impulse, s);
    baker.run();
    const ObjectLightmap& map = baker.lightmaps().at(0);
    const LayerSet layers = baker.layers(0);
    const std::vector<float>& single = layers.get("lm_inscatter_single").data;
    double lowest = 0.0, open_sum = 0.0;
    long open = 0, under = 0;
    for (size_t i = 0; i < map.texels.size(); ++i) {
        const LightmapTexel& t = map.texels[i];
        if (t.state != TexelState::Valid) continue;
        const double v = luminance(vec3(single[i * 3], single[i * 3 + 1], single[i * 3 + 2]));
        if (t.position.x < 1.0f) {
            lowest = std::min(lowest, v);
            ++under;
        } else if (t.position.x > 1.6f) {
            open_sum += v;
            ++open;
        }
    }
    ASSERT_GT(under, 500);
    ASSERT_GT(open, 200);
    EXPECT_GT(lowest, -0.05 * open_sum / double(open));
}

// A lid 0.1 above a floor in haze, lit by a sky, open past x = 1.3: the floor's field texels
// deep under it met no unoccluded connection in the prepass, so they have no ratio of
// corrections to tables. A deeper vertex landing there that draws a sky sample through the
// opening gets the tables' single scattering of an infinite medium lit along it, where the real
// medium is lit only past the opening; uncorrected, that light reached every texel whose
// bounce landed there (valley's darkest house texels: 1.5x VPT's irradiance). The vertex now
// draws its own corrections: the lid's underside, whose paths bounce off that floor, agrees
// with VPT.
TEST(Bake, AVertexWhoseFieldTexelHasNoRatioDrawsItsOwnCorrections) {
    Fixture f(sky_lid_scene(0.1f));
    const std::unique_ptr<LightmapBaker> baker = bake_field(f, 4);
    const VertexCorrectionField* field = baker->vertex_corrections();
    ASSERT_NE(field, nullptr);
    const VertexCorrectionField::Texel deep = field->locate(floor_hit(f, -2.5f, 0.3f, 0.05f));
    const VertexCorrectionField::Texel open = field->locate(floor_hit(f, 3.0f, 0.3f, 1.0f));
    ASSERT_TRUE(deep.found());
    ASSERT_TRUE(open.found());
    EXPECT_FALSE(deep.single_ratio_known());
    EXPECT_TRUE(open.single_ratio_known());

    BakeSettings s;
    s.bounces = 1;
    BakeEstimator impulse(*f.rays, f.media, &test_support::shared_impulse_tables(),
                          BakeMethod::Impulse, s);
    impulse.set_vertex_corrections(field);
    const BakeEstimator vpt(*f.rays, f.media, nullptr, BakeMethod::Vpt, s);
    // The light of the bounce off the floor (`surface`: the vertex's gathered light, scattered
    // at the vertex included), its mean and standard error over the paths.
    auto bounce_light = [](const BakeEstimator& e, vec3 p, uint64_t key) {
        const int paths = 20000;
        double sum = 0.0, squares = 0.0;
        BakeCounters counters;
        for (int k = 0; k < paths; ++k) {
            CounterRng rng(0, key, 0, uint64_t(k));
            const double v =
                luminance(e.estimate(p, vec3(0, 0, -1), vec3(0.6f), rng, counters).surface);
            sum += v;
            squares += v * v;
        }
        const double mean = sum / paths;
        return std::pair{mean, std::sqrt((squares / paths - mean * mean) / (paths - 1))};
    };
    // Without the vertex's own corrections: 0.0135, 0.0112, 0.0126 against VPT's 0.0032, 0.0017,
    // 0.0020.
    for (const float x : {-2.5f, -1.5f, -0.5f}) {
        const vec3 p(x, 0.3f, 0.1f);
        const auto [a, se_a] = bounce_light(impulse, p, 7);
        const auto [b, se_b] = bounce_light(vpt, p, 8);
        EXPECT_LT(std::abs(a - b), 4.0 * std::hypot(se_a, se_b))
            << "x " << x << ": impulse " << a << " +- " << se_a << ", vpt " << b << " +- " << se_b;
    }
}

// smoke_room's fireflies (session 42): a wall whose light connections graze the smoke has
// ~0 tables for them while the real single scattering its corrections draw through the smoke
// it faces is not; the ratio of the two, applied to the texel's tables, made half the seeds'
// 32-spp bakes a few texels' (lm_irradiance relMSE against VPT 3.0 / 20.0 / 0.031 / 0.18 /
// 12.8 / 0.029 over seeds 1-6). Each seed's bake against the texel-by-texel median of six
// (robust to one seed's outlier at a texel): without fireflies the seeds' errors are alike.
// Measured: 0.022-0.030 (max / min 1.36); with kTablesExplainShare = 0 (the plain ratio)
// 2.99 / 21.3 / 0.028 / 0.237 / 12.5 / 0.028.
TEST(Bake, ImpulseSeedsOfSmokeRoomAgreeOnTheirError) {
    const Scene scene = load_scene(FREQLAB_SOURCE_DIR "/scenes/smoke_room.json");
    const Media media(scene.media, scene.source);
    EmbreeDevice device{2};
    RayScene rays(scene, device);
    rays.update(0.0f);
    BakeSettings s;
    s.spp = 32;
    s.probes_x = 0;
    constexpr int kSeeds = 6;
    std::vector<std::vector<LayerSet>> bakes;  // [seed][map]
    for (int seed = 1; seed <= kSeeds; ++seed) {
        s.seed = uint64_t(seed);
        LightmapBaker baker(rays, media, &test_support::shared_impulse_tables(),
                            BakeMethod::Impulse, s);
        baker.run();
        bakes.push_back(baker.all_layers());
    }
    std::vector<LayerSet> median = bakes[0];
    for (size_t m = 0; m < median.size(); ++m) {
        std::vector<float>& out = median[m].find("lm_irradiance")->data;
        for (size_t k = 0; k < out.size(); ++k) {
            std::array<float, kSeeds> v;
            for (int b = 0; b < kSeeds; ++b)
                v[size_t(b)] = bakes[size_t(b)][m].get("lm_irradiance").data[k];
            std::sort(v.begin(), v.end());
            out[k] = 0.5f * (v[kSeeds / 2 - 1] + v[kSeeds / 2]);
        }
    }
    std::vector<double> errors;
    for (int b = 0; b < kSeeds; ++b) {
        std::vector<LightmapError> maps;
        for (size_t m = 0; m < median.size(); ++m)
            maps.push_back(compare_lightmaps(bakes[size_t(b)][m], median[m], "lm_irradiance"));
        const LightmapError e = combine_lightmap_errors(maps);
        ASSERT_GT(e.texels, 0);
        errors.push_back(e.relmse);
    }
    const auto [lo, hi] = std::minmax_element(errors.begin(), errors.end());
    std::string listed;
    for (double e : errors) listed += " " + std::to_string(e);
    EXPECT_LT(*hi, 2.0 * *lo) << "lm_irradiance relMSE against the seeds' median, seeds 1-6:"
                              << listed;
}
