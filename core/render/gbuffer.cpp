#include "render/gbuffer.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include <tbb/parallel_for.h>

#include "math/rng.h"

namespace freqlab {

namespace {

constexpr int kTile = 16;

void set_flush_to_zero() {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

}  // namespace

GBufferOutput render_gbuffer(const RayScene& rs, int frame, const FrameSettings& fs,
                             const GBufferSettings& gs, Progress& progress, bool antialiased) {
    const Scene& scene = rs.scene();
    const int w = fs.width, h = fs.height;
    const CameraRayGenerator camera(scene.camera.at(rs.time()), w, h);

    GBufferOutput out;
    out.gbuffer.width = w;
    out.gbuffer.height = h;
    out.gbuffer.hits.resize(size_t(w) * h);
    out.gbuffer.view_dirs.resize(size_t(w) * h);
    out.layers = LayerSet(w, h);
    Layer& color = out.layers.add("color", LayerKind::Color, 3,
                                  "unlit preview: albedo x (0.2 + 0.8 |n.v|); background radiance");
    Layer& albedo = out.layers.add(
        "albedo", LayerKind::Color, 3,
        antialiased ? "surface albedo (AA averaged)" : "surface albedo at the pixel centre");
    Layer& normal = out.layers.add("normal", LayerKind::Signed, 3, "world shading normal");
    Layer& position = out.layers.add("position", LayerKind::Signed, 3, "world position");
    Layer& depth = out.layers.add("depth", LayerKind::Continuous, 1,
                                  "distance along the centre ray; 0 where nothing is hit");
    Layer& object = out.layers.add("object", LayerKind::Categorical, 1,
                                   "object index + 1; 0 is the background");
    object.legend.push_back("background");
    for (const SceneObject& o : scene.objects) object.legend.push_back(o.name);

    const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
    std::atomic<long> rays{0};
    progress.begin_stage("gbuffer", long(tiles_x) * tiles_y);

    auto shade_preview = [&](const SurfaceHit& hit, const vec3& dir, vec3* alb) {
        if (!hit.valid) {
            *alb = vec3(0.0f);
            return rs.background(dir);
        }
        const Material& m = scene.materials[size_t(hit.material)];
        *alb = m.albedo.eval(hit.uv);
        return *alb * (0.2f + 0.8f * std::fabs(glm::dot(hit.shading_normal, dir)));
    };

    tbb::parallel_for(0, tiles_x * tiles_y, [&](int tile) {
        progress.checkpoint();
        set_flush_to_zero();
        const int x0 = (tile % tiles_x) * kTile, y0 = (tile / tiles_x) * kTile;
        const int x1 = std::min(x0 + kTile, w), y1 = std::min(y0 + kTile, h);
        long tile_rays = 0;
        // Pixel-centre rays: 4x2 pixel blocks make coherent 8-wide packets.
        for (int by = y0; by < y1; by += 2)
            for (int bx = x0; bx < x1; bx += 4) {
                Ray rays8[8];
                bool active[8];
                SurfaceHit hits8[8];
                for (int i = 0; i < 8; ++i) {
                    const int x = bx + (i & 3), y = by + (i >> 2);
                    active[i] = x < x1 && y < y1;
                    rays8[i] = Ray{camera.origin, camera.direction((x + 0.5f) / w, (y + 0.5f) / h),
                                   0.0f, INFINITY};
                    tile_rays += active[i];
                }
                rs.intersect8(rays8, active, hits8);
                for (int i = 0; i < 8; ++i) {
                    if (!active[i]) continue;
                    const int x = bx + (i & 3), y = by + (i >> 2);
                    const size_t p = size_t(y) * w + x;
                    const SurfaceHit& hit = hits8[i];
                    out.gbuffer.hits[p] = hit;
                    out.gbuffer.view_dirs[p] = rays8[i].direction;
                    for (int c = 0; c < 3; ++c) {
                        normal.data[3 * p + c] = hit.shading_normal[c];
                        position.data[3 * p + c] = hit.position[c];
                    }
                    depth.data[p] = hit.valid ? hit.distance : 0.0f;
                    object.data[p] = float(hit.object + 1);
                    if (!antialiased) {
                        vec3 a;
                        const vec3 c = shade_preview(hit, rays8[i].direction, &a);
                        for (int ch = 0; ch < 3; ++ch) {
                            color.data[3 * p + ch] = c[ch];
                            albedo.data[3 * p + ch] = a[ch];
                        }
                    }
                }
            }
        // Jittered AA samples (when antialiased), eight at a time per pixel; keys (seed, frame,
        // pixel, sample).
        for (int y = y0; antialiased && y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const size_t p = size_t(y) * w + x;
                vec3 sum_color(0.0f), sum_albedo(0.0f);
                for (int s0 = 0; s0 < gs.aa_samples; s0 += 8) {
                    Ray rays8[8];
                    bool active[8];
                    SurfaceHit hits8[8];
                    for (int i = 0; i < 8; ++i) {
                        active[i] = s0 + i < gs.aa_samples;
                        CounterRng rng(uint64_t(fs.seed), uint64_t(frame), p, uint64_t(s0 + i));
                        const float jx = rng.next_float(), jy = rng.next_float();
                        rays8[i] = Ray{camera.origin, camera.direction((x + jx) / w, (y + jy) / h),
                                       0.0f, INFINITY};
                        tile_rays += active[i];
                    }
                    rs.intersect8(rays8, active, hits8);
                    for (int i = 0; i < 8; ++i) {
                        if (!active[i]) continue;
                        vec3 a;
                        sum_color += shade_preview(hits8[i], rays8[i].direction, &a);
                        sum_albedo += a;
                    }
                }
                const float inv = 1.0f / float(gs.aa_samples);
                for (int c = 0; c < 3; ++c) {
                    color.data[3 * p + c] = sum_color[c] * inv;
                    albedo.data[3 * p + c] = sum_albedo[c] * inv;
                }
            }
        rays.fetch_add(tile_rays, std::memory_order_relaxed);
        progress.advance();
    });
    out.rays = rays.load();
    return out;
}

}  // namespace freqlab
