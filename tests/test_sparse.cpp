// Method A's sparse sampling and reconstruction (issue "Method A, part 2", acceptance 1): the
// rejection sampler's exact ends and its rate; upsampling and reconstruction keep a constant
// field constant and never mix objects; textures multiply after reconstruction.
#include <gtest/gtest.h>

#include <cmath>

#include <cstdio>

#include "render/reconstruction.h"
#include "render/sparse_sampling.h"

using namespace freqlab;

TEST(SparseSampling, RejectionSamplerEndsAreExactAndItsRateMatches) {
    long zero = 0, one = 0;
    for (uint64_t i = 0; i < 100000; ++i) {
        CounterRng a(1, 0, i, 0), b(2, 0, i, 0);
        zero += rejection_sample(0.0, a);
        one += rejection_sample(1.0, b);
    }
    EXPECT_EQ(zero, 0);
    EXPECT_EQ(one, 100000);
    for (double d : {0.0625, 0.3, 0.77}) {
        const long n = 1000000;
        long hits = 0;
        for (long i = 0; i < n; ++i) {
            CounterRng rng(7, 1, uint64_t(i), 0);
            hits += rejection_sample(d, rng);
        }
        const double sigma = std::sqrt(n * d * (1 - d));
        EXPECT_LE(std::fabs(hits - n * d), 3 * sigma) << "density " << d;
    }
    SparseSettings s;  // f_max = 8: B_min = 1/16
    s.density_scale = 1.0f;
    EXPECT_DOUBLE_EQ(sampling_density(0.0, 1e-3, s), 1.0 / 16);
    EXPECT_DOUBLE_EQ(sampling_density(1e6, 1e-3, s), 1.0);
    EXPECT_DOUBLE_EQ(sampling_density(300.0, 1e-3, s), 0.3);
    EXPECT_DOUBLE_EQ(sampling_density(NAN, 1e-3, s), 1.0);
}

namespace {

// Two objects side by side (left half object 0, right half object 1) on a plane z = 0.
std::vector<PixelFeature> two_objects(int w, int h) {
    std::vector<PixelFeature> f(size_t(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            f[size_t(y) * w + x] = {true, x < w / 2 ? 0 : 1, vec3(0.01f * x, 0.01f * y, 0),
                                    vec3(0, 0, 1), 0.01f};
    return f;
}

}  // namespace

TEST(SparseSampling, UpsamplingKeepsConstantsAndObjects) {
    const int w = 64, h = 32;
    const std::vector<PixelFeature> f = two_objects(w, h);
    std::vector<int> sources;
    std::vector<VisibilityStats> values;
    for (int y = 2; y < h; y += 4)
        for (int x = 2; x < w; x += 4) {
            sources.push_back(y * w + x);
            values.push_back(x < w / 2 ? VisibilityStats{0.25f, 1.0f, 2.0f, 3.0f}
                                       : VisibilityStats{0.75f, -1.0f, 5.0f, 7.0f});
        }
    std::vector<VisibilityStats> out;
    std::vector<char> found;
    upsample_statistics(w, h, f, sources, values, 4, out, found);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            ASSERT_TRUE(found[i]);
            const VisibilityStats& want = x < w / 2 ? values.front() : values.back();
            for (int c = 0; c < kUpsampledStats; ++c)
                EXPECT_FLOAT_EQ(out[i][size_t(c)], want[size_t(c)]) << x << "," << y;
        }
}

TEST(Reconstruction, ConstantStaysConstantObjectsNeverMixAndTexturesComeAfter) {
    const int w = 64, h = 32;
    ReconstructionInput in;
    in.width = w;
    in.height = h;
    in.features = two_objects(w, h);
    const size_t n = size_t(w) * h;
    in.mu_v.assign(n, 0.0f);
    in.sigma_v.assign(n, 0.0f);
    in.radius.assign(n, 4.0f);
    in.sampled.assign(n, 0);
    in.value.assign(n, vec3(0.0f));
    for (size_t i = 0; i < n; i += 7) {
        in.sampled[i] = 1;
        in.value[i] = int(i % size_t(w)) < w / 2 ? vec3(0.3f, 0.2f, 0.1f) : vec3(2.0f);
    }
    const ReconstructionOutput out = reconstruct(in, SparseSettings{});
    EXPECT_EQ(out.fallback_pixels, 0);
    // A checker texture applied after reconstruction stays a crisp checker.
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            const vec3 expected = x < w / 2 ? vec3(0.3f, 0.2f, 0.1f) : vec3(2.0f);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(out.value[i][c], expected[c], 1e-6f) << x << "," << y;
            const float texture = ((x / 3 + y / 3) % 2) ? 0.9f : 0.1f;
            const vec3 shaded = out.value[i] * texture;
            EXPECT_NEAR(shaded.x, expected.x * texture, 1e-6f);
        }
    // A pixel far from every sample of its object: the radius grows, then it is reported.
    ReconstructionInput lonely = in;
    lonely.sampled.assign(n, 0);
    lonely.sampled[0] = 1;
    const ReconstructionOutput out2 = reconstruct(lonely, SparseSettings{});
    EXPECT_GT(out2.fallback_pixels, 0);
    for (size_t i = 0; i < n; ++i)
        if (!out2.fallback[i]) {
            EXPECT_TRUE(std::isfinite(out2.value[i].x));
            EXPECT_GT(out2.weight[i], 0.0f);
        }
    EXPECT_EQ(out2.fallback[size_t(w - 1)], 1);  // object 1 has no sample at all
}

// Acceptance 2: sphere_on_plane through the whole sparse pipeline, against the closed forms.
#include "render/frame_renderer.h"
#include "scene/scene_loader.h"

// History: at 320 x 180 without an edge-aware density floor the band n_z in [-0.5, -0.125) read
// +3.1 % (points alone: 0.2 %): under a constant map B_L = 0 and the Lambertian band-limit keep
// the lower sphere at B_min, and pixels by its silhouette extrapolated from brighter samples
// above. The density floor (2 / d)^2 at d px from an object's edge halved that; at 640 x 360 the
// f_max = 8 px radius spans half the angle and the band means fall within 0.5 %.
namespace {

// sphere_on_plane's closed forms (green channel): the worst relative error of `color`'s mean
// over 8 bands of distance on the plane / normal on the sphere (away from the contact point);
// the mean |relative error| per pixel on each object in *plane, *sphere.
double worst_band_error(const LayerSet& layers, const Layer& color, double* plane_mean = nullptr,
                        double* sphere_mean = nullptr) {
    const Layer& position = layers.get("position");
    const Layer& object = layers.get("object");
    double sum_plane = 0, sum_sphere = 0, worst_region = 0;
    long n_plane = 0, n_sphere = 0;
    std::vector<double> band_sum(8, 0.0), band_exact(8, 0.0);
    for (size_t i = 0; i < layers.pixel_count(); ++i) {
        const vec3 p(position.data[3 * i], position.data[3 * i + 1], position.data[3 * i + 2]);
        const double value = color.data[3 * i + 1];
        double exact = 0;
        int band = -1;
        if (object.data[i] == 1.0f) {  // plane (object index + 1)
            const double d = std::hypot(p.x, p.y);
            if (d < 0.5 || d > 6) continue;
            exact = 0.5 * (1.0 - std::pow(1.0 / (d * d + 1.0), 1.5));
            band = std::min(3, int(d / 1.5));
            sum_plane += std::fabs(value - exact) / exact;
            ++n_plane;
        } else if (object.data[i] == 2.0f) {  // sphere
            const vec3 nn = glm::normalize(p - vec3(0, 0, 1));
            if (nn.z < -0.5f) continue;  // near the contact point
            exact = 0.5 * (1.0 + nn.z) / 2.0;
            band = 4 + std::min(3, int((nn.z + 0.5f) / 0.375f));
            sum_sphere += std::fabs(value - exact) / exact;
            ++n_sphere;
        } else {
            continue;
        }
        band_sum[size_t(band)] += value;
        band_exact[size_t(band)] += exact;
    }
    for (int b = 0; b < 8; ++b)
        if (band_exact[size_t(b)] > 0) {
            std::printf("band %d: mean %.5f exact %.5f\n", b, band_sum[size_t(b)],
                        band_exact[size_t(b)]);
            worst_region = std::max(worst_region,
                                    std::fabs(band_sum[size_t(b)] / band_exact[size_t(b)] - 1.0));
        }
    if (plane_mean) *plane_mean = sum_plane / double(std::max(n_plane, 1L));
    if (sphere_mean) *sphere_mean = sum_sphere / double(std::max(n_sphere, 1L));
    return worst_region;
}

}  // namespace

TEST(SparsePipeline, SphereOnPlaneMatchesClosedFormsShadingFewPixels) {
    const Scene scene = load_scene(FREQLAB_SOURCE_DIR "/scenes/analytic/sphere_on_plane.json");
    EmbreeDevice device(2);
    RenderConfig config;
    config.method = RenderMethod::Sparse;
    config.frame.width = 640;
    config.frame.height = 360;
    // A constant environment has B_L = 0, so N_L would be points.min_samples = 8: fine for the
    // density, noisy for a 1 % comparison. 256 samples per point; the per-pixel noise left is
    // reported, the assertion is on means over bands of distance / normal (bias, not noise).
    config.points.min_samples = 256;
    config.points.max_pilot = 256;
    FrameRenderer renderer(scene, config, device);
    Progress progress;
    const FrameResult r = renderer.render(0, progress);
    double plane = 0, sphere = 0;
    const double worst_region = worst_band_error(r.layers, r.layers.get("color"), &plane, &sphere);
    const double shaded = r.stats["pixels_shaded"].get<double>() / double(r.layers.pixel_count());
    std::printf(
        "plane: mean |rel. error| %.4f; sphere %.4f; worst band mean %.4f; shaded %.1f %%\n", plane,
        sphere, worst_region, 100 * shaded);
    EXPECT_LE(worst_region, 0.01);
    EXPECT_LE(shaded, 0.20);
}

// The first image (render/sparse_pass.h PreviewSink): handed over once per frame before the
// frame, from the initial grid alone; on sphere_on_plane its band means follow the closed
// forms within 3 % (the frame's: 1 %), its background is the frame's exactly; with the cache, a
// second frame of the static scene stands every grid point in by an entry and gives the same.
TEST(SparsePipeline, FirstImageFromTheInitialGridFollowsTheClosedForms) {
    const Scene scene = load_scene(FREQLAB_SOURCE_DIR "/scenes/analytic/sphere_on_plane.json");
    EmbreeDevice device(2);
    RenderConfig config;
    config.method = RenderMethod::Cache;
    config.frame.width = 320;
    config.frame.height = 180;
    config.points.min_samples = 256;
    config.points.max_pilot = 256;
    FrameRenderer renderer(scene, config, device);
    std::vector<LayerSet> previews;
    renderer.set_preview_sink([&](LayerSet&& l) { previews.push_back(std::move(l)); });
    for (int frame = 0; frame < 2; ++frame) {
        Progress progress;
        const FrameResult r = renderer.render(frame, progress);
        ASSERT_EQ(previews.size(), size_t(frame + 1)) << "one first image per frame";
        const LayerSet& p = previews.back();
        ASSERT_EQ(p.width(), 320);
        ASSERT_EQ(p.height(), 180);
        const Layer& pc = p.get("color");
        const Layer& fc = r.layers.get("color");
        const Layer& object = r.layers.get("object");
        for (size_t i = 0; i < p.pixel_count(); ++i) {
            for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(pc.data[3 * i + size_t(c)]));
            if (object.data[i] == 0.0f) {
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(pc.data[3 * i + size_t(c)], fc.data[3 * i + size_t(c)]) << i;
            }
        }
        if (frame == 1) {
            EXPECT_EQ(r.stats["pixels_initial"].get<long>(), 0) << "stood in";
        }
        EXPECT_LE(worst_band_error(r.layers, pc), 0.03) << "frame " << frame;
    }
}
