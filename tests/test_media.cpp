// Participating media at bake time (volume/media.h): exact optical thickness against brute-force
// quadrature, free-flight sampling against the exponential law (binomial tests), bounds
// clipping against closed forms, and bad input that must name the field.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "base/error.h"
#include "scene/json_reader.h"
#include "scene/scene_loader.h"
#include "volume/media.h"
#include "volume/vdb_reader.h"

using namespace freqlab;

namespace {

std::vector<MediumDesc> media_from(const std::string& json_text) {
    const nlohmann::json j = nlohmann::json::parse(json_text);
    return parse_media(JsonReader(j, "test.json", "media"), "");
}

// Midpoint rule with many steps: the brute force the DDA must match.
double brute_tau(const Media& m, vec3 o, vec3 d, double t_max, int steps) {
    double tau = 0.0;
    const double h = t_max / steps;
    for (int i = 0; i < steps; ++i) tau += m.at(o + d * float((i + 0.5) * h)).sigma_t() * h;
    return tau;
}

}  // namespace

TEST(Media, HomogeneousBoundsGiveClosedFormTransmittance) {
    const Media m(media_from(R"([
        {"sigma_s": 0.5, "sigma_a": 0.25, "bounds": {"box": {"min": [-1,-1,-1], "max": [1,1,1]}}},
        {"sigma_s": 0.2, "bounds": {"sphere": {"center": [5,0,0], "radius": 2}}}])"));
    // Along x from -3: 2 units in the box, then the sphere's 4-unit chord.
    const vec3 o(-3, 0, 0), d(1, 0, 0);
    EXPECT_NEAR(m.transmittance(o, d, 10.0), std::exp(-0.75 * 2 - 0.2 * 4), 1e-12);
    EXPECT_NEAR(m.transmittance(o, d, 2.5), std::exp(-0.75 * 0.5), 1e-12);
    // Off-centre chord of the sphere, above the box: 2 sqrt(r^2 - 1.5^2).
    EXPECT_NEAR(m.integrate(vec3(0, 1.5f, 0), d, 20.0).tau_s, 0.2 * 2 * std::sqrt(1.75), 1e-6);
    EXPECT_NEAR(m.exit_distance(o, d), 10.0, 1e-5);
    const SegmentOptics s = m.integrate(o, d, 10.0);
    EXPECT_NEAR(s.effective().sigma_s, (0.5 * 2 + 0.2 * 4) / 10.0, 1e-9);
}

// Many boxes (valley: air and ten smoke volumes) are rejected by a segment's bounds, a ray to
// infinity's ending where it leaves their union, before their slab tests: the answers must be
// those of each medium alone, exactly, for rays that start inside, outside, graze and miss.
TEST(Media, BoxesRejectedBySegmentBoundsChangeNothing) {
    const std::string json = R"([
        {"sigma_s": 0.05, "sigma_a": 0.01, "bounds": {"box": {"min": [-10,-10,-2], "max": [10,10,6]}}},
        {"sigma_s": 0.8, "bounds": {"box": {"min": [-6,-6,1], "max": [-3,-3,4]}}},
        {"sigma_s": 0.6, "sigma_a": 0.1, "bounds": {"box": {"min": [3,-6,1], "max": [6,-3,4]}}},
        {"sigma_s": 0.4, "bounds": {"sphere": {"center": [0,5,2], "radius": 1.5}}}])";
    const std::vector<MediumDesc> descs = media_from(json);
    const Media all(descs);
    std::vector<Media> alone;
    for (const MediumDesc& d : descs) alone.emplace_back(std::vector<MediumDesc>{d});
    const double inf = std::numeric_limits<double>::infinity();
    uint64_t h = 12345;
    auto next = [&] {
        h = h * 6364136223846793005ULL + 1442695040888963407ULL;
        return float(h >> 40) * (1.0f / float(1 << 24));
    };
    int crossing = 0, missing = 0;
    for (int i = 0; i < 2000; ++i) {
        const vec3 o =
            vec3(-14.0f, -14.0f, -4.0f) + vec3(28.0f, 28.0f, 14.0f) * vec3(next(), next(), next());
        const vec3 d = glm::normalize(vec3(next() - 0.5f, next() - 0.5f, next() - 0.5f));
        for (const double t_max : {double(next()) * 12.0, inf}) {
            double tau_s = 0.0, exit = 0.0;
            for (const Media& m : alone) {
                tau_s += m.integrate(o, d, t_max).tau_s;
                exit = std::max(exit, m.exit_distance(o, d));
            }
            const SegmentOptics s = all.integrate(o, d, t_max);
            // Sums in another order: equal to the last bits.
            EXPECT_NEAR(s.tau_s, tau_s, 1e-12 * (1.0 + tau_s)) << i;
            EXPECT_EQ(all.exit_distance(o, d), exit) << i;
            if (!std::isfinite(t_max)) {
                EXPECT_EQ(s.length, exit) << i;
            }
            (tau_s > 0.0 ? crossing : missing)++;
            // Free flights: the same collision from the same random numbers as with no
            // rejection (each medium alone draws its own uniform first, as the mixture does).
            CounterRng a(1, 2, uint64_t(i), 0), b(1, 2, uint64_t(i), 0);
            const MediumCollision c = all.sample_collision(o, d, t_max, a);
            MediumCollision best;
            best.t = t_max;
            for (const Media& m : alone) {
                CounterRng one = b;
                const MediumCollision ci = m.sample_collision(o, d, std::min(t_max, best.t), one);
                b.next_double();
                if (ci.happened && ci.t < best.t) best = ci;
            }
            EXPECT_EQ(c.happened, best.happened) << i;
            if (c.happened) {
                EXPECT_EQ(c.t, best.t) << i;
            }
        }
    }
    EXPECT_GT(crossing, 1000);
    EXPECT_GT(missing, 300);
}

// A medium without bounds whose coefficients were dragged to 0 adds nothing to a segment to
// infinity (a directional light's): 0 x inf is 0 here, not NaN (it made every path of such a
// bake non-finite, the lightmap black).
TEST(Media, ZeroCoefficientsAlongAnUnboundedSegmentAddNothing) {
    Media m(media_from(R"([{"sigma_s": 0.3, "sigma_a": 0.1, "g": 0.2}])"));
    m.set_coefficients(0, 0.0, 0.0, 0.2, 1.0);
    const vec3 o(0.0f), d(0.0f, 0.0f, 1.0f);
    const double inf = std::numeric_limits<double>::infinity();
    const SegmentOptics s = m.integrate(o, d, inf);
    EXPECT_EQ(s.tau_s, 0.0);
    EXPECT_EQ(s.tau_a, 0.0);
    EXPECT_EQ(s.tau_gs, 0.0);
    EXPECT_EQ(m.transmittance(o, d, inf), 1.0);
    CounterRng rng(1, 2, 3, 4);
    EXPECT_EQ(m.track(o, d, inf, rng).transmittance(), 1.0);
    // A density scale of 0 as well.
    m.set_coefficients(0, 0.3, 0.1, 0.2, 0.0);
    EXPECT_EQ(m.integrate(o, d, inf).tau_s, 0.0);
    // And a medium that is there still extinguishes all of an unbounded segment.
    m.set_coefficients(0, 0.3, 0.1, 0.2, 1.0);
    EXPECT_EQ(m.transmittance(o, d, inf), 0.0);
}

TEST(Media, GridOpticalThicknessIsExactAgainstQuadrature) {
    const Media m(media_from(R"([
        {"sigma_s": 2.0, "sigma_a": 0.5, "g": 0.4,
         "bounds": {"box": {"min": [-1,-2,0], "max": [1.5,1,1]}},
         "density": {"source": "noise", "resolution": [13, 17, 9], "frequency": 2, "seed": 7}},
        {"sigma_s": 0.1, "sigma_a": 0.0}])"));
    ASSERT_NE(m.grid(0), nullptr);
    EXPECT_GT(m.grid(0)->max_value(), 0.3f);
    CounterRng rng(1, 2, 3, 4);
    for (int i = 0; i < 20; ++i) {
        const vec3 o(rng.next_float() * 4 - 2, rng.next_float() * 4 - 2,
                     rng.next_float() * 2 - 0.5f);
        vec3 d(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
        d = glm::normalize(d);
        const double tau = m.integrate(o, d, 5.0).tau_s + m.integrate(o, d, 5.0).tau_a;
        // The brute force converges like h^1 at voxel boundaries: 200k steps give ~1e-5.
        EXPECT_NEAR(tau, brute_tau(m, o, d, 5.0, 200000), 2e-4 * (1.0 + tau)) << i;
    }
}

// A height-fog ramp is collapsed to one voxel in x and y and integrated from prefix sums along
// z (media.h); it must still integrate exactly what at() reads, voxel by voxel. A brush grid
// next to it varies along every axis and is marched.
TEST(Media, CollapsedGridAxesAreExactAgainstQuadrature) {
    const Media m(media_from(R"([
        {"sigma_s": 0.8, "sigma_a": 0.1,
         "bounds": {"box": {"min": [-3,-2,0], "max": [3,2.5,2]}},
         "density": {"source": "height_fog", "resolution": [7, 5, 19], "base": 0.3,
                     "falloff": 0.5}},
        {"sigma_s": 1.5, "sigma_a": 0.5, "bounds": {"box": {"min": [-2,-1,0], "max": [2,2,1.5]}},
         "density": {"source": "brushes", "resolution": [37, 29, 21],
                     "brushes": [{"shape": "ellipsoid", "center": [0,0.5,0.7], "size": [2,1.6,1]},
                                 {"shape": "box", "center": [1,1,0.5], "size": [0.9,0.7,0.6],
                                  "density": 2}]}}])"));
    ASSERT_NE(m.grid(0), nullptr);
    ASSERT_NE(m.grid(1), nullptr);
    CounterRng rng(5, 6, 7, 8);
    for (int i = 0; i < 40; ++i) {
        const vec3 o(rng.next_float() * 6 - 3, rng.next_float() * 4 - 2, rng.next_float() * 2);
        vec3 d(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
        d = glm::normalize(d);
        const SegmentOptics s = m.integrate(o, d, 6.0);
        EXPECT_NEAR(s.tau_s + s.tau_a, brute_tau(m, o, d, 6.0, 200000),
                    2e-4 * (1.0 + s.tau_s + s.tau_a))
            << i;
    }
}

// The grid tests' rays: 4000 from around grid g's box, one in eight along an axis and one in
// eight in a coordinate plane, some starting past 0; fn(ray, o, d, t_begin, t_end, marched)
// with the DDA's sum over the voxels (the reference).
template <class Fn>
void for_each_grid_test_ray(const DensityGrid& g, CounterRng& rng, Fn&& fn) {
    const vec3 lo = g.box_min() - 0.5f, hi = g.box_max() + 0.5f;
    for (int i = 0; i < 4000; ++i) {
        const vec3 o = lo + (hi - lo) * vec3(rng.next_float(), rng.next_float(), rng.next_float());
        vec3 d(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f);
        if (i % 8 == 0) d = vec3(0.0f);
        if (i % 8 == 0) d[i / 8 % 3] = i % 16 == 0 ? 1.0f : -1.0f;  // along an axis
        if (i % 8 == 1) d[i / 8 % 3] = 0.0f;                        // in a plane
        d = glm::normalize(d);
        const double t_begin = i % 5 == 0 ? 0.3 * rng.next_float() : 0.0;
        const double t_end = t_begin + 4.0 * rng.next_float();
        double marched = 0.0;
        g.march(o, d, t_begin, t_end, [&](double a, double b, float v) { marched += (b - a) * v; });
        fn(i, o, d, t_begin, t_end, marched);
    }
}

// The box's float faces and the voxels' disagree by a few float ulps of a face coordinate
// over |d_a|, times the largest density: what any integral may differ from the marched sum by.
double face_rounding(const DensityGrid& g, const vec3& d) {
    double face = 0.0;
    for (int a = 0; a < 3; ++a)
        if (d[a] != 0.0f)
            face += 8.0 * 0x1p-24 * (std::abs(g.box_min()[a]) + std::abs(g.box_max()[a])) /
                    std::abs(d[a]);
    return face * g.max_value();
}

// The grid integral from the density's jumps at voxel faces (DensityGrid::integral_by_jumps)
// is the DDA's sum over voxels, for rays from inside and outside, along axes and coordinate
// planes, ending inside, and on a collapsed (height-fog) grid. The two differ only where the
// box's float faces and the voxels' disagree: at most a few float ulps of a face coordinate
// over |d_a|, times the largest density.
TEST(Media, GridIntegralByJumpsIsTheMarchedSum) {
    const Media m(media_from(R"([
        {"sigma_s": 1.0, "bounds": {"box": {"min": [-1.2,-0.6,0], "max": [0.6,1.4,1.8]}},
         "density": {"source": "noise", "resolution": [36, 40, 36], "frequency": 1.6,
                     "octaves": 4, "threshold": 0.45, "seed": 3}},
        {"sigma_s": 1.0, "bounds": {"box": {"min": [-3,-2,0], "max": [3,2.5,2]}},
         "density": {"source": "height_fog", "resolution": [7, 5, 19], "base": 0.3,
                     "falloff": 0.5}}])"));
    CounterRng rng(11, 12, 13, 14);
    int compared = 0;
    for (size_t gi = 0; gi < m.size(); ++gi) {
        const DensityGrid& g = *m.grid(gi);
        for_each_grid_test_ray(g, rng,
                               [&](int i, vec3 o, vec3 d, double t0, double t1, double marched) {
                                   EXPECT_NEAR(g.integral_by_jumps(o, d, t0, t1), marched,
                                               1e-12 * (1.0 + marched) + face_rounding(g, d))
                                       << "grid " << gi << " ray " << i;
                                   compared += marched > 0.0;
                               });
    }
    EXPECT_GT(compared, 3000);  // most rays cross some density
}

// integral_by_runs sums only the crossings of the two axes other than the ray's dominant one,
// from float prefix integrals at the voxel faces. Against the marched sum, its error is bounded
// by their float roundings: per crossing and end, a jump interpolates between two face
// differences, each of two rounded prefixes (<= 2^-24 P each, P the largest row integral)
// rounded once more (<= 2^-24 2P): <= 2^-24 4P, divided by |d_a| (d in voxels along a); plus
// the box faces' float rounding as for the jumps. On this grid the bound is ~1e-4 and the observed
// errors ~1e-6: the bound holds for every ray, the mean error is below 1 % of it.
TEST(Media, GridIntegralByRunsIsTheMarchedSumWithinFloatRounding) {
    const Media m(media_from(R"([
        {"sigma_s": 1.0, "bounds": {"box": {"min": [-1.2,-0.6,0], "max": [0.6,1.4,1.8]}},
         "density": {"source": "noise", "resolution": [36, 40, 36], "frequency": 1.6,
                     "octaves": 4, "threshold": 0.45, "seed": 3}},
        {"sigma_s": 1.0, "bounds": {"box": {"min": [-3,-2,0], "max": [3,2.5,2]}},
         "density": {"source": "noise", "resolution": [20, 1, 12], "frequency": 1.1,
                     "octaves": 2, "threshold": 0.3, "seed": 5}}])"));
    CounterRng rng(21, 22, 23, 24);
    int compared = 0;
    for (size_t gi = 0; gi < m.size(); ++gi) {
        const DensityGrid& g = *m.grid(gi);
        ASSERT_TRUE(g.has_runs()) << "grid " << gi;
        const vec3 size = g.box_max() - g.box_min();
        const vec3 voxel = size / vec3(g.resolution());
        const double row = double(g.max_value()) * std::max({size.x, size.y, size.z});
        const int crossings = g.resolution().x + g.resolution().y + g.resolution().z + 2;
        double error_sum = 0.0, bound_sum = 0.0;
        for_each_grid_test_ray(
            g, rng, [&](int i, vec3 o, vec3 d, double t0, double t1, double marched) {
                // |d| along the run axis: the varying axis of the largest |d| in voxels.
                double d_run = 0.0, best = 0.0;
                for (int a = 0; a < 3; ++a)
                    if (g.resolution()[a] > 1 && std::abs(d[a]) / voxel[a] > best) {
                        best = std::abs(d[a]) / voxel[a];
                        d_run = std::abs(d[a]);
                    }
                const double rounding = d_run > 0.0 ? crossings * 0x1p-24 * 4.0 * row / d_run : 0.0;
                const double bound = 1e-12 * (1.0 + marched) + face_rounding(g, d) + rounding;
                const double error = std::abs(g.integral_by_runs(o, d, t0, t1) - marched);
                EXPECT_LE(error, bound) << "grid " << gi << " ray " << i << " marched " << marched;
                error_sum += error;
                bound_sum += bound;
                compared += marched > 0.0;
            });
        EXPECT_LT(error_sum, 0.01 * bound_sum) << "grid " << gi;
    }
    EXPECT_GT(compared, 3000);  // most rays cross some density
}

// A run of empty voxels integrates to exactly 0 by runs, as by jumps, even where the rows the
// ray changes between carry different nonzero prefixes (a blob behind it): their differences
// are exact in double. Subtracted in float they left +-1e-7 of medium where there is none, and
// the vertex field divided by that sliver's tables (1e10 fireflies on smoke_room).
TEST(Media, GridIntegralByRunsIsExactlyZeroThroughEmptyVoxels) {
    // Behind the empty region (x < 0.4), a bar of one voxel's section per row along x, of
    // densities spread over two decades: neighbouring rows' prefixes differ by large factors.
    std::string brushes;
    CounterRng densities(41, 42, 43, 44);
    for (int j = 0; j < 10; ++j)
        for (int k = 0; k < 10; ++k) {
            const float y = 0.025f + 0.05f * float(j), z = 0.025f + 0.05f * float(k);
            const float density = std::exp(4.6f * densities.next_float()) * 0.1f;
            brushes += (brushes.empty() ? "" : ",") + std::string("{\"shape\": \"box\", ") +
                       "\"center\": [0.2," + std::to_string(y) + "," + std::to_string(z) +
                       "], \"size\": [0.4,0.05,0.05], \"density\": " + std::to_string(density) +
                       "}";
        }
    const Media m(
        media_from(R"([{"sigma_s": 1.0, "bounds": {"box": {"min": [0,0,0], "max": [1,1,1]}},
        "density": {"source": "brushes", "resolution": [20, 20, 20], "brushes": [)" +
                   brushes + "]}}]"));
    const DensityGrid& g = *m.grid(0);
    ASSERT_TRUE(g.has_runs());
    CounterRng rng(31, 32, 33, 34);
    int compared = 0;  // rays that change rows
    for (int i = 0; i < 2000; ++i) {
        // Inside [0.55, 0.95] x [0.02, 0.48]^2, empty (the bars end at x = 0.4), mostly along
        // x, so that the run axis is x and the rows along x pass through the bars.
        const vec3 o(0.55f + 0.1f * rng.next_float(), 0.1f + 0.3f * rng.next_float(),
                     0.1f + 0.3f * rng.next_float());
        const vec3 d = glm::normalize(
            vec3(1.0f, 0.4f * (rng.next_float() - 0.5f), 0.4f * (rng.next_float() - 0.5f)));
        const double length = 0.3 * rng.next_float();
        double marched = 0.0;
        g.march(o, d, 0.0, length, [&](double a, double b, float v) { marched += (b - a) * v; });
        ASSERT_EQ(marched, 0.0) << "ray " << i << " leaves the empty region";
        EXPECT_EQ(g.integral_by_runs(o, d, 0.0, length), 0.0) << "ray " << i;
        compared += d.y != 0.0f || d.z != 0.0f;
    }
    EXPECT_EQ(compared, 2000);
}

// Ratio tracking (Media::track): the mean transmittance and the mean optical thicknesses over
// many tracks equal the exact ones within 4 standard errors, through a noise grid plus a global
// homogeneous medium; through homogeneous media alone it draws nothing and equals integrate().
TEST(Media, RatioTrackingIsUnbiasedAndExactWithoutGrids) {
    const Media m(media_from(R"([
        {"sigma_s": 2.0, "sigma_a": 0.5, "g": 0.4, "density_scale": 0.8,
         "bounds": {"box": {"min": [-1,-2,0], "max": [1.5,1,1]}},
         "density": {"source": "noise", "resolution": [13, 17, 9], "frequency": 2, "seed": 7}},
        {"sigma_s": 0.1, "sigma_a": 0.02}])"));
    const vec3 o(-1.5f, -1.0f, 0.3f), d = glm::normalize(vec3(1.0f, 0.4f, 0.2f));
    const SegmentOptics exact = m.integrate(o, d, 4.0);
    ASSERT_GT(exact.tau_s, 0.5);
    const int n = 40000;
    double t_sum = 0, t_sq = 0, s_sum = 0, s_sq = 0, g_sum = 0, g_sq = 0;
    for (int i = 0; i < n; ++i) {
        CounterRng rng(9, 0, 0, uint64_t(i));
        const SegmentOptics s = m.track(o, d, 4.0, rng);
        const double t = s.transmittance();
        t_sum += t;
        t_sq += t * t;
        s_sum += s.tau_s;
        s_sq += s.tau_s * s.tau_s;
        g_sum += s.tau_gs;
        g_sq += s.tau_gs * s.tau_gs;
    }
    auto check = [&](double sum, double sq, double want, const char* what) {
        const double mean = sum / n, se = std::sqrt(std::max(0.0, sq / n - mean * mean) / n);
        EXPECT_NEAR(mean, want, 4.0 * se) << what << ": se " << se;
        EXPECT_GT(se, 0.0) << what;  // the estimates do vary: the grid is tracked
    };
    check(t_sum, t_sq, exact.transmittance(), "transmittance");
    check(s_sum, s_sq, exact.tau_s, "tau_s");
    check(g_sum, g_sq, exact.tau_gs, "tau_gs");

    const Media homogeneous(media_from(R"([
        {"sigma_s": 0.5, "sigma_a": 0.1, "bounds": {"box": {"min": [-1,-1,-1], "max": [1,1,1]}}},
        {"sigma_s": 0.1, "sigma_a": 0.02}])"));
    CounterRng a(1, 2, 3, 4), b(1, 2, 3, 4);
    const SegmentOptics tracked = homogeneous.track(o, d, 4.0, a);
    const SegmentOptics integrated = homogeneous.integrate(o, d, 4.0);
    EXPECT_DOUBLE_EQ(tracked.tau_s, integrated.tau_s);
    EXPECT_NEAR(tracked.transmittance(), integrated.transmittance(), 1e-15);
    EXPECT_EQ(a.next_u32(), b.next_u32());  // no random number was drawn
}

TEST(Media, FreeFlightsFollowTheTransmittanceLaw) {
    // Collisions before t must happen with probability 1 - T(t), for a superposition of a
    // brush grid and a global medium. Binomial test at 4.5 sigma per distance.
    const Media m(media_from(R"([
        {"sigma_s": 1.5, "sigma_a": 0.5, "bounds": {"box": {"min": [0,-1,-1], "max": [2,1,1]}},
         "density": {"source": "brushes", "resolution": [16, 8, 8],
                     "brushes": [{"shape": "ellipsoid", "center": [1,0,0], "size": [1.6,1.6,1.6]},
                                 {"shape": "box", "center": [0.3,0,0], "size": [0.4,2,2], "density": 0.5}]}},
        {"sigma_s": 0.1, "sigma_a": 0.05}])"));
    const vec3 o(-0.5f, 0.05f, 0.02f), d(1, 0, 0);
    const int n = 40000;
    std::vector<double> hits;
    for (int i = 0; i < n; ++i) {
        CounterRng rng(9, 0, uint64_t(i), 0);
        const MediumCollision c = m.sample_collision(o, d, 3.0, rng);
        if (c.happened) {
            hits.push_back(c.t);
            ASSERT_GT(c.sigma_t, 0.0);
            ASSERT_LE(c.sigma_s, c.sigma_t);
        }
    }
    for (double t : {0.4, 0.8, 1.2, 1.6, 2.2, 3.0}) {
        const double p = 1.0 - m.transmittance(o, d, t);
        const double count =
            double(std::count_if(hits.begin(), hits.end(), [t](double h) { return h < t; }));
        const double sigma = std::sqrt(n * p * (1 - p));
        EXPECT_NEAR(count, n * p, 4.5 * sigma + 1) << "t = " << t;
    }
}

// Several media (a grid inside a global medium, and a homogeneous box overlapping both): the
// conditioned law is inverted through their summed thickness, so every draw collides, with
// weight P; P(t < s | collision) = (1 - T(s)) / P, and the medium collided with is each one
// with probability (integral of sigma_t,m T) / P (midpoint quadrature, 40000 steps; each
// medium's sigma from a Media of it alone). Binomial, 4.5 sigma. The pdf each draw reports
// (the impulse bake's lit-medium points divide by it) is sigma_t T / P at its t, and E[1 / pdf]
// the segment's length.
TEST(Media, ForcedCollisionsThroughSeveralMediaInvertTheConditionedLaw) {
    const std::string grid = R"({"sigma_s": 0.3, "sigma_a": 0.1, "g": 0.5,
        "bounds": {"box": {"min": [0,-1,-1], "max": [2,1,1]}},
        "density": {"source": "brushes", "resolution": [16, 8, 8],
                    "brushes": [{"shape": "ellipsoid", "center": [1,0,0], "size": [1.6,1.6,1.6]}]}})";
    const std::string global = R"({"sigma_s": 0.02, "sigma_a": 0.01, "g": 0.1})";
    const std::string box = R"({"sigma_s": 0.2, "sigma_a": 0.05, "g": -0.3,
        "bounds": {"box": {"min": [1.5,-1,-1], "max": [2.6,1,1]}}})";
    const Media m(media_from("[" + grid + "," + global + "," + box + "]"));
    const Media alone[3] = {Media(media_from("[" + grid + "]")),
                            Media(media_from("[" + global + "]")),
                            Media(media_from("[" + box + "]"))};
    const double g_of[3] = {0.5, 0.1, -0.3};
    const vec3 o(-0.5f, 0.05f, 0.02f), d(1, 0, 0);
    const double t_max = 3.0, p = 1.0 - m.transmittance(o, d, t_max);
    double medium_share[3] = {};
    const int steps = 40000;
    for (int k = 0; k < steps; ++k) {
        const double t = (k + 0.5) * t_max / steps;
        const double T = m.transmittance(o, d, t);
        for (int i = 0; i < 3; ++i)
            medium_share[i] += alone[i].at(o + d * float(t)).sigma_t() * T * t_max / steps / p;
    }
    const int n = 40000;
    std::vector<double> ts;
    int picked[3] = {};
    double inverse_pdf = 0.0, inverse_pdf_sq = 0.0;
    for (int i = 0; i < n; ++i) {
        CounterRng rng(11, 0, uint64_t(i), 0);
        double weight = -1.0;
        const MediumCollision c = m.sample_forced_collision(o, d, t_max, rng, &weight);
        ASSERT_TRUE(c.happened) << i;
        ASSERT_EQ(weight, p);
        ASSERT_LT(c.t, t_max);
        ts.push_back(c.t);
        const int which = int(std::find(g_of, g_of + 3, c.g) - g_of);
        ASSERT_LT(which, 3) << c.g;
        ++picked[which];
        // The coefficients are that medium's at the point.
        const HomogeneousMedium at = alone[which].at(o + d * float(c.t));
        ASSERT_NEAR(c.sigma_t, at.sigma_t(), 1e-6 * at.sigma_t() + 1e-9) << c.t;
        ASSERT_NEAR(c.sigma_s, at.sigma_s, 1e-6 * at.sigma_s + 1e-9) << c.t;
        // t's density: every medium's sigma_t there times T(t), over P.
        const vec3 x = o + d * float(c.t);
        const double density =
            (alone[0].at(x).sigma_t() + alone[1].at(x).sigma_t() + alone[2].at(x).sigma_t()) *
            m.transmittance(o, d, c.t) / p;
        ASSERT_NEAR(c.pdf, density, 1e-6 * density) << c.t;
        inverse_pdf += 1.0 / c.pdf;
        inverse_pdf_sq += 1.0 / (c.pdf * c.pdf);
    }
    // The global medium has sigma_t > 0 everywhere: E[1 / pdf] is the segment's length.
    const double mean = inverse_pdf / n,
                 se = std::sqrt(std::max(0.0, inverse_pdf_sq / n - mean * mean) / n);
    EXPECT_NEAR(mean, t_max, 4.5 * se);
    for (double s : {0.2, 0.6, 1.0, 1.4, 1.7, 2.2, 2.8}) {
        const double expected = (1.0 - m.transmittance(o, d, s)) / p;
        const double share =
            double(std::count_if(ts.begin(), ts.end(), [&](double t) { return t < s; })) / n;
        EXPECT_NEAR(share, expected, 4.5 * std::sqrt(expected * (1.0 - expected) / n) + 1e-9)
            << "s = " << s;
    }
    for (int i = 0; i < 3; ++i) {
        const double e = medium_share[i];
        EXPECT_NEAR(double(picked[i]) / n, e, 4.5 * std::sqrt(e * (1.0 - e) / n) + 1e-4)
            << "medium " << i;
    }
}

// A thin gap (valley's floors 0.03 above the terrain, in thin air among other media): P is
// ~2e-4, and every draw still collides with weight P, not one draw in a thousand with
// ~1 / tries of it (the first version's analog retries).
TEST(Media, ForcedCollisionsInAThinGapAlwaysCollideWithWeightP) {
    const Media m(media_from(R"([
        {"sigma_s": 0.006, "sigma_a": 0.001, "bounds": {"box": {"min": [-100,-100,-5], "max": [100,100,40]}}},
        {"sigma_s": 0.8, "sigma_a": 0.08, "bounds": {"box": {"min": [4,4,4], "max": [8,8,8]}}}])"));
    const vec3 o(0.0f, 0.0f, 0.0f), d = glm::normalize(vec3(0.3f, 0.1f, 1.0f));
    const double t_max = 0.03, p = 1.0 - m.transmittance(o, d, t_max);
    ASSERT_NEAR(p, 0.007 * 0.03, 1e-6);
    for (int i = 0; i < 1000; ++i) {
        CounterRng rng(5, 0, uint64_t(i), 0);
        double weight = -1.0;
        const MediumCollision c = m.sample_forced_collision(o, d, t_max, rng, &weight);
        ASSERT_TRUE(c.happened) << i;
        ASSERT_EQ(weight, p);
        ASSERT_GE(c.t, 0.0);
        ASSERT_LT(c.t, t_max);
        ASSERT_NEAR(c.sigma_t, 0.007, 1e-12);
    }
}

// With one medium the conditioned law is inverted: every draw collides, with weight P, and
// the law is the same (the collision point's density and coefficients are those at it).
TEST(Media, ForcedCollisionsInOneMediumInvertTheConditionedLaw) {
    const Media m(media_from(R"([
        {"sigma_s": 0.3, "sigma_a": 0.1, "g": 0.4,
         "bounds": {"box": {"min": [0,-1,-1], "max": [2,1,1]}},
         "density": {"source": "brushes", "resolution": [16, 8, 8],
                     "brushes": [{"shape": "ellipsoid", "center": [1,0,0], "size": [1.6,1.6,1.6]}]}}])"));
    const vec3 o(-0.5f, 0.05f, 0.02f), d(1, 0, 0);
    const double t_max = 3.0, p = 1.0 - m.transmittance(o, d, t_max);
    const int n = 40000;
    std::vector<double> ts;
    for (int i = 0; i < n; ++i) {
        CounterRng rng(12, 0, uint64_t(i), 0);
        double weight = -1.0;
        const MediumCollision c = m.sample_forced_collision(o, d, t_max, rng, &weight);
        ASSERT_TRUE(c.happened) << i;
        ASSERT_EQ(weight, p);
        ASSERT_LT(c.t, t_max);
        const HomogeneousMedium at = m.at(o + d * float(c.t));
        ASSERT_NEAR(c.sigma_t, at.sigma_t(), 1e-6 * at.sigma_t() + 1e-9) << c.t;
        ASSERT_GT(c.sigma_t, 0.0);
        ASSERT_EQ(c.g, 0.4);
        ts.push_back(c.t);
    }
    // P(t < s | collision) = (1 - T(s)) / P: binomial, 4.5 sigma.
    for (double s : {0.4, 0.8, 1.2, 1.6, 2.2}) {
        const double expected = (1.0 - m.transmittance(o, d, s)) / p;
        const double share =
            double(std::count_if(ts.begin(), ts.end(), [&](double t) { return t < s; })) / n;
        EXPECT_NEAR(share, expected, 4.5 * std::sqrt(expected * (1.0 - expected) / n) + 1e-9)
            << "s = " << s;
    }
}

TEST(Media, BadInputNamesTheField) {
    auto expect_field = [](const std::string& text, const std::string& field) {
        try {
            media_from(text);
            ADD_FAILURE() << "accepted: " << text;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
        }
    };
    expect_field(R"([{"sigma_s": -1}])", "media[0].sigma_s");
    expect_field(R"([{"sigma_s": 1, "sigma_a": -0.1}])", "media[0].sigma_a");
    expect_field(R"([{"sigma_s": 1, "g": 1.0}])", "media[0].g");
    expect_field(R"([{"sigma_s": 1, "g": -1.5}])", "media[0].g");
    expect_field(R"([{"sigma_s": 1, "density": {"source": "noise"}}])", "media[0].density");
    expect_field(R"([{"sigma_s": 1, "bounds": {"box": {"min": [0,0,0], "max": [1,0,1]}}}])",
                 "media[0].bounds.box.max");
}

TEST(Media, VdbGridsLoadAndBadGridsAreErrors) {
    const auto dir = std::filesystem::temp_directory_path() / "freqlab_vdb_test";
    std::filesystem::create_directories(dir);
    VdbDensity g;
    g.box_min = vec3(0.0f);
    g.box_max = vec3(1.0f, 0.5f, 0.25f);
    g.resolution = ivec3(8, 4, 2);
    g.voxels.resize(64);
    for (size_t i = 0; i < g.voxels.size(); ++i) g.voxels[i] = 0.25f + float(i % 5);
    const std::string file = (dir / "smoke.vdb").string();
    write_vdb_density(file, "density", g);
    MediumDesc desc;
    desc.density = DensitySource::Vdb;
    desc.vdb_file = file;
    desc.sigma_s = 1.0;
    const Media m({desc}, "scene.json");
    ASSERT_NE(m.grid(0), nullptr);
    EXPECT_EQ(m.grid(0)->resolution(), g.resolution);
    EXPECT_NEAR(m.grid(0)->box_max().x, 1.0f, 1e-5f);
    // Voxel (3, 2, 1) read back where it was written.
    EXPECT_FLOAT_EQ(m.at(vec3(3.5f, 2.5f, 1.5f) * 0.125f).sigma_s, g.voxels[(1 * 4 + 2) * 8 + 3]);

    desc.vdb_grid = "smoke";
    try {
        Media bad({desc}, "scene.json");
        ADD_FAILURE() << "a missing grid name was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "media[0].density.grid");
        EXPECT_NE(e.message().find("density"), std::string::npos) << e.what();  // lists grids
    }
    g.voxels[10] = std::nanf("");
    write_vdb_density(file, "density", g);
    desc.vdb_grid = "density";
    EXPECT_THROW(Media({desc}, "scene.json"), Error);
    desc.vdb_file = (dir / "absent.vdb").string();
    EXPECT_THROW(Media({desc}, "scene.json"), Error);
}

TEST(Media, SceneWithoutMediaHasNone) {
    const Scene s =
        load_scene(std::string(FREQLAB_SOURCE_DIR) + "/scenes/analytic/sphere_on_plane.json");
    EXPECT_TRUE(Media(s.media).empty());
    const Scene f =
        load_scene(std::string(FREQLAB_SOURCE_DIR) + "/scenes/analytic/fog_receiver.json");
    EXPECT_EQ(Media(f.media).size(), 1u);
}
