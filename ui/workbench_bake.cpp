// Method B in the workbench: a lightmap bake as a progressive background job whose every pass
// lands in the viewport as the lightmapped scene (volume/lightmap_preview.h) with its layers;
// media sliders that re-bake without re-tabulating (Media::set_coefficients, LightmapBaker::
// reset), bake settings from their declaration, and an orbit of the preview camera.
#include <imgui.h>

#include <algorithm>

#include "base/error.h"
#include "base/stopwatch.h"
#include "math/sh.h"
#include "scene/provenance.h"
#include "settings/settings_group.h"
#include "settings_panel.h"
#include "volume/impulse_tables.h"
#include "volume/lightmap_preview.h"
#include "workbench_state.h"

namespace freqlab::ui {

struct BakeSession {
    BakeMethod method = BakeMethod::Impulse;
    BakeSettings settings;
    std::unique_ptr<Media> media;
    std::unique_ptr<RayScene> rays;
    std::unique_ptr<ImpulseTables> tables;  // loaded by the first impulse job (media only)
    std::unique_ptr<LightmapBaker> baker;   // rebuilt when the atlas or method changes
    bool baker_dirty = true;
    std::unique_ptr<Job> job;
    float yaw = 0.0f, pitch = 0.0f, zoom = 1.0f;
    std::vector<LayerSet> baked;  // the last pass's lightmaps (guarded by results_mutex)
    double first_pass_ms = -1.0;  // since the last (re)start: the first preview's latency
    bool show_lobes = true;       // probes' SH lobes over the preview
    std::vector<LightmapBaker::Probe> probes;  // of the last pass (guarded by results_mutex)
};

void BakeSessionDeleter::operator()(BakeSession* b) const {
    if (b) b->job.reset();  // cancels and joins before anything it uses goes
    delete b;
}

void make_bake_session(Workbench::State& s, const std::string& method,
                       const std::vector<std::string>& assignments) {
    BakeSessionPtr b(new BakeSession);
    b->method = parse_bake_method(method);
    SettingsGroup group;
    group.bind(BakeSettings::schema(), &b->settings);
    for (const std::string& a : assignments) group.apply_assignment(a);
    b->media = std::make_unique<Media>(s.scene.media, s.scene.source);
    b->rays = std::make_unique<RayScene>(s.scene, *s.device);
    b->rays->update(0.0f);
    s.bake = std::move(b);
}

namespace {

FrameResult preview_result(const Workbench::State& s, const BakeSession& b,
                           const std::vector<LayerSet>& baked) {
    FrameResult r;
    r.frame = 0;
    const CameraPose pose = orbit_pose(s.scene.camera.at(0.0f), b.yaw, b.pitch, b.zoom);
    r.layers = render_lightmap_preview(*b.rays, pose, s.config.frame.width, s.config.frame.height,
                                       b.baker->lightmaps(), baked);
    const BakeStats& st = b.baker->stats();
    r.stats = {{"frame", 0},
               {"time_ms", st.bake_ms},
               {"rays", st.rays},
               {"pixels_shaded", st.texels_valid},
               {"spp", st.samples},
               {"impulse_queries", st.impulse_queries},
               {"nonfinite", st.guarded}};
    return r;
}

}  // namespace

void start_bake(Workbench::State& s) {
    BakeSession& b = *s.bake;
    b.job.reset();
    b.first_pass_ms = -1.0;
    Workbench::State* sp = &s;
    b.job = std::make_unique<Job>([sp](Progress& progress) {
        BakeSession& bk = *sp->bake;
        const auto t0 = Clock::now();
        const bool needs_tables = bk.method == BakeMethod::Impulse && !bk.media->empty();
        if (needs_tables && !bk.tables) {
            progress.begin_stage("impulse tables", 1);
            bk.tables = std::make_unique<ImpulseTables>(ImpulseTables::cached(30));
        }
        if (!bk.baker || bk.baker_dirty) {
            progress.begin_stage("lightmap atlases", 1);
            bk.baker = std::make_unique<LightmapBaker>(*bk.rays, *bk.media, bk.tables.get(),
                                                       bk.method, bk.settings);
            bk.baker_dirty = false;
        } else {
            bk.baker->reset();
        }
        int passes = 0;
        for (int n = 1, done = 0; done < bk.settings.spp; n *= 2, ++passes)
            done += std::min(n, bk.settings.spp - done);
        progress.set_stage_count(std::max(1, passes));
        for (int n = 1; bk.baker->samples() < bk.settings.spp; n *= 2) {
            bk.baker->run_pass(std::min(n, bk.settings.spp - bk.baker->samples()), &progress);
            const std::vector<LayerSet> baked = bk.baker->all_layers();
            FrameResult r = preview_result(*sp, bk, baked);
            std::lock_guard<std::mutex> lock(sp->results_mutex);
            if (bk.first_pass_ms < 0.0) bk.first_pass_ms = ms_since(t0);
            bk.baked = std::move(baked);
            bk.probes = bk.baker->probes();
            keep_result(*sp, std::move(r));
            attach_reference(*sp, 0);  // a VPT comparison made earlier stays attached
            sp->view_dirty = true;
        }
    });
}

bool bake_busy(const Workbench::State& s) {
    return s.bake && s.bake->job && !s.bake->job->done();
}

void wait_for_bake(Workbench::State& s) {
    if (s.bake && s.bake->job) s.bake->job->wait();
}

void stop_bake_jobs(Workbench::State& s) {
    s.reference_job.reset();
    s.bake->job.reset();
}

void restart_bake(Workbench::State& s) {
    // The comparison belongs to the media and settings it was baked with.
    s.reference_job.reset();
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        s.references.clear();
        s.reference_note.clear();
    }
    s.metrics.clear();
    start_bake(s);
}

void draw_bake_notes(const Workbench::State& s) {
    // Densities the atlases could not honour (volume/lightmap_atlas.h): said, not hidden (fixed
    // when the baker is built).
    if (!s.bake->baker) return;
    for (const std::string& note : s.bake->baker->stats().atlas_notes)
        ImGui::TextWrapped("atlas: %s", note.c_str());
}

void draw_bake_panel(Workbench::State& s) {
    BakeSession& b = *s.bake;
    if (b.job && b.job->done()) {
        const ProgressSnapshot snap = b.job->snapshot();
        if (!snap.error.empty()) s.error = snap.error;
    }
    bool restart = false;
    if (ImGui::CollapsingHeader("Media", ImGuiTreeNodeFlags_DefaultOpen)) {
        if (b.media->empty()) ImGui::TextDisabled("no media: the tables are never loaded");
        for (size_t i = 0; i < b.media->size(); ++i) {
            const MediumDesc& d = b.media->desc(i);
            float sigma_s = float(d.sigma_s), sigma_a = float(d.sigma_a), g = float(d.g),
                  scale = float(d.density_scale);
            ImGui::PushID(int(i));
            ImGui::Text("%s (%s)", d.name.c_str(), to_string(d.density));
            bool changed = false;
            changed |= ImGui::SliderFloat("sigma_s", &sigma_s, 0.0f, 20.0f, "%.3f",
                                          ImGuiSliderFlags_Logarithmic);
            changed |= ImGui::SliderFloat("sigma_a", &sigma_a, 0.0f, 5.0f, "%.3f",
                                          ImGuiSliderFlags_Logarithmic);
            // The impulse tables' range: a bake refuses more (BakeEstimator::check_media).
            changed |= ImGui::SliderFloat("g", &g, -float(kGRange), float(kGRange), "%.2f");
            if (ImGui::IsItemHovered())
                ImGui::SetTooltip(
                    "Henyey-Greenstein anisotropy. |g| <= %.2f: method B's impulse "
                    "tables end there (HG is singular at |g| = 1); a scene file may "
                    "give VPT any |g| < 1.",
                    kGRange);
            changed |= ImGui::SliderFloat("density scale", &scale, 0.0f, 10.0f, "%.2f",
                                          ImGuiSliderFlags_Logarithmic);
            if (changed) {
                stop_bake_jobs(s);  // the jobs read the media
                b.media->set_coefficients(i, sigma_s, sigma_a, g, scale);
                restart = true;
            }
            ImGui::PopID();
        }
    }
    ImGui::Checkbox("probe lobes", &b.show_lobes);
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip(
            "Each light probe's incident radiance (order-3 SH, luminance) drawn as a polar "
            "curve in the image plane at the probe, scaled to its own maximum: the lobe points "
            "where light comes from.");
    if (ImGui::CollapsingHeader("Preview camera")) {
        bool moved = ImGui::SliderFloat("yaw", &b.yaw, -180.0f, 180.0f, "%.0f deg");
        moved |= ImGui::SliderFloat("pitch", &b.pitch, -60.0f, 60.0f, "%.0f deg");
        moved |= ImGui::SliderFloat("zoom", &b.zoom, 0.3f, 4.0f, "%.2f");
        if (moved && !bake_busy(s) && b.baker) {
            s.reference_job.reset();  // a comparison holds the old view
            std::lock_guard<std::mutex> lock(s.results_mutex);
            s.references.clear();
            s.reference_note.clear();
            s.metrics.clear();
            keep_result(s, preview_result(s, b, b.baked));
            s.view_dirty = true;
        }
    }
    // Edited on a copy: the jobs read b.settings, so it changes only once they are stopped.
    BakeSettings edited = b.settings;
    SettingsGroup group;
    group.bind(BakeSettings::schema(), &edited);
    // With the tables panel asked for (--tables) the bake settings start closed: it is in view.
    if (draw_settings(group, !s.options.show_tables) & kInvalidatesBake) {
        stop_bake_jobs(s);
        b.settings = edited;
        b.baker_dirty = true;  // the atlas and the estimator's settings live in the baker
        restart = true;
    }
    if (b.baker) {
        const BakeStats& st = b.baker->stats();
        ImGui::Text("%d / %d spp, %ld texels, %.0f ms", b.baker->samples(), b.settings.spp,
                    st.texels_valid, st.bake_ms);
        if (b.first_pass_ms >= 0.0) ImGui::Text("first preview after %.0f ms", b.first_pass_ms);
    }
    if (restart) restart_bake(s);
}

namespace {

constexpr int kReferenceMaxFactor = 64;  // at most 64 x bake.spp for the reference

// One VPT bake at `spp` from `seed`, seen from the preview camera.
LayerSet vpt_preview(const Workbench::State& s, const BakeSession& b, int spp, uint64_t seed,
                     Progress& progress) {
    BakeSettings settings = b.settings;
    settings.spp = spp;
    settings.seed = seed;
    LightmapBaker vpt(*b.rays, *b.media, nullptr, BakeMethod::Vpt, settings);
    vpt.run(&progress);
    const std::vector<LayerSet> baked = vpt.all_layers();
    const CameraPose pose = orbit_pose(s.scene.camera.at(0.0f), b.yaw, b.pitch, b.zoom);
    return render_lightmap_preview(*b.rays, pose, s.config.frame.width, s.config.frame.height,
                                   vpt.lightmaps(), baked);
}

}  // namespace

// The reference is the mean of two independent VPT bakes of N / 2 samples each, so that its
// own noise is measured, not assumed: relMSE(mean) = relMSE(half A, half B) / 4 (the halves'
// difference has twice a half's variance, their mean half of it). N starts at 4 x bake.spp and
// doubles (up to 64 x) until that noise is below a quarter of the measured error of the bake
// against it; the compare panel says where it stopped.
void start_bake_reference(Workbench::State& s) {
    s.reference_job_frame = 0;
    s.reference_note.clear();
    Workbench::State* sp = &s;
    LayerSet test;
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        const std::shared_ptr<FrameResult> r = s.results.find(0);
        if (r && r->layers.find("color")) {
            test = LayerSet(r->layers.width(), r->layers.height());
            test.add("color", LayerKind::Color, 3).data = r->layers.get("color").data;
        }
    }
    s.reference_job = std::make_unique<Job>([sp, test](Progress& progress) {
        const BakeSession& bk = *sp->bake;
        const int base = std::max(2, 4 * bk.settings.spp);
        for (int n = base;; n *= 2) {
            const LayerSet a = vpt_preview(*sp, bk, n / 2, bk.settings.seed + 7919, progress);
            const LayerSet b = vpt_preview(*sp, bk, n / 2, bk.settings.seed + 15838, progress);
            LayerSet mean(a.width(), a.height());
            Layer& c = mean.add("color", LayerKind::Color, 3);
            const std::vector<float>&ca = a.get("color").data, &cb = b.get("color").data;
            for (size_t i = 0; i < c.data.size(); ++i) c.data[i] = 0.5f * (ca[i] + cb[i]);
            const double noise = compare_layers(a, b).relmse / 4.0;
            const double error =
                test.find("color") && test.width() == mean.width() && test.height() == mean.height()
                    ? compare_layers(test, mean).relmse
                    : 0.0;
            const bool enough = noise <= 0.25 * error;
            char note[240];
            std::snprintf(note, sizeof note,
                          "VPT reference: %d spp (two halves, seeds +7919 / +15838); its noise "
                          "relMSE %.2e = %.0f%% of the measured %.2e%s",
                          n, noise, error > 0 ? 100.0 * noise / error : 0.0, error,
                          enough ? ""
                                 : (n >= kReferenceMaxFactor * bk.settings.spp
                                        ? " (stopped at 64 x bake.spp: the metrics include it)"
                                        : ""));
            const bool last = enough || n >= kReferenceMaxFactor * bk.settings.spp;
            if (!last) continue;
            std::lock_guard<std::mutex> lock(sp->results_mutex);
            sp->references[0] = std::move(mean);
            sp->reference_note = note;
            return;
        }
    });
}

std::vector<std::string> bake_trace(Workbench::State& s, int x, int y) {
    BakeSession& b = *s.bake;
    if (!b.baker || !s.shown) return {};
    const LayerSet& layers = s.shown->layers;
    const Layer* texel = layers.find("lightmap_texel");
    if (!texel || x < 0 || y < 0 || x >= layers.width() || y >= layers.height()) return {};
    const int tx = int(texel->at(layers.width(), x, y, 0)),
              ty = int(texel->at(layers.width(), x, y, 1));
    const int m = int(texel->at(layers.width(), x, y, 2));
    if (m < 0) return {"no lightmap here (background, sphere, mirror or moving object)"};
    const ObjectLightmap& map = b.baker->lightmaps()[size_t(m)];
    const LightmapTexel& t = map.texels[size_t(ty) * map.width + tx];
    std::vector<std::string> lines = {"lightmap " + lightmap_name(s.scene, map) + " texel " +
                                      std::to_string(tx) + "," + std::to_string(ty) + " (" +
                                      texel_state_legend()[size_t(t.state)] + ")"};
    if (t.state != TexelState::Valid) return lines;
    CounterRng rng = texel_random(b.settings.seed, size_t(m), size_t(ty) * map.width + tx, 0);
    for (std::string& l : b.baker->estimator().trace_texel(t.position, t.normal, t.albedo, rng))
        lines.push_back(std::move(l));
    return lines;
}

void draw_probe_lobes(Workbench::State& s) {
    s.probe_marks.clear();
    if (!s.bake || !s.bake->show_lobes || !s.shown) return;
    BakeSession& b = *s.bake;
    std::vector<LightmapBaker::Probe> probes;
    {
        std::lock_guard<std::mutex> lock(s.results_mutex);
        probes = b.probes;
    }
    if (probes.empty()) return;
    const int w = s.shown->layers.width(), h = s.shown->layers.height();
    const CameraPose pose = orbit_pose(s.scene.camera.at(0.0f), b.yaw, b.pitch, b.zoom);
    const CameraRayGenerator cam(pose, w, h);
    const ScreenRect& r = s.image_rect;
    ImDrawList* draw = ImGui::GetWindowDrawList();
    draw->PushClipRect(ImVec2(r.x0, r.y0), ImVec2(r.x1, r.y1), true);
    constexpr int kSteps = 48;
    // Each probe scaled to its own largest radius (22 px): lobe shapes, whatever the light's
    // fall-off; the inspector and probes.json have the values.
    std::vector<std::array<float, kSteps>> radii(probes.size());
    std::vector<float> largest(probes.size(), 0.0f);
    for (size_t i = 0; i < probes.size(); ++i)
        for (int k = 0; k < kSteps; ++k) {
            const float phi = kTwoPi * k / kSteps;
            const vec3 d = std::cos(phi) * cam.right + std::sin(phi) * cam.up;
            double y[9];
            sh_eval(3, glm::dvec3(d), y);
            vec3 v(0.0f);
            for (size_t c = 0; c < 9; ++c)
                v += float(y[c]) *
                     (probes[i].surface[c] + probes[i].single[c] + probes[i].multiple[c]);
            radii[i][size_t(k)] = std::max(0.0f, luminance(v));
            largest[i] = std::max(largest[i], radii[i][size_t(k)]);
        }
    for (size_t i = 0; i < probes.size(); ++i) {
        if (!(largest[i] > 0.0f)) continue;
        const vec3 v = probes[i].position - cam.origin;
        const float z = glm::dot(v, cam.forward);
        if (z <= 0.0f) continue;
        const float xn = glm::dot(v, cam.right) / (z * cam.tan_half_fov * cam.aspect);
        const float yn = glm::dot(v, cam.up) / (z * cam.tan_half_fov);
        // The image's uv, then the viewport's zoom and pan (workbench_viewport.cpp shows uv
        // centre +- 0.5 / zoom in the image rect): the lobes stay on their probes.
        const float u = (xn + 1.0f) * 0.5f, uv_y = (1.0f - yn) * 0.5f, half = 0.5f / s.zoom;
        const float px = r.x0 + (u - (s.centre.x - half)) / (2.0f * half) * (r.x1 - r.x0);
        const float py = r.y0 + (uv_y - (s.centre.y - half)) / (2.0f * half) * (r.y1 - r.y0);
        if (!r.contains(px, py)) continue;
        ImVec2 pts[kSteps];
        for (int k = 0; k < kSteps; ++k) {
            const float phi = kTwoPi * k / kSteps;
            const float len =
                22.0f * ImGui::GetFontSize() / 13.0f * radii[i][size_t(k)] / largest[i];
            pts[k] = ImVec2(px + len * std::cos(phi), py - len * std::sin(phi));
        }
        draw->AddPolyline(pts, kSteps, IM_COL32(255, 170, 60, 230), ImDrawFlags_Closed, 1.5f);
        draw->AddCircleFilled(ImVec2(px, py), 2.0f, IM_COL32(255, 255, 255, 230));
        s.probe_marks.push_back({px, py});
    }
    draw->PopClipRect();
}

BakeMethod bake_method(const Workbench::State& s) {
    return s.bake->method;
}

void switch_bake_method(Workbench::State& s, BakeMethod method) {
    BakeSession& b = *s.bake;
    if (method == b.method) return;
    stop_bake_jobs(s);
    b.method = method;
    b.baker_dirty = true;
    restart_bake(s);
}

void follow_bake_media(Workbench::State& s) {
    const Media& media = *s.bake->media;
    if (media.empty() || s.tables_media_version == media.version()) return;
    s.tables_media_version = media.version();
    // A grid's coefficients are its density 1's: scaled as the bake scales them.
    const MediumDesc& d = media.desc(0);
    TablesPanelState& t = *s.tables;
    t.sigma_s = float(d.sigma_s * d.density_scale);
    t.sigma_a = float(d.sigma_a * d.density_scale);
    t.g = float(d.g);
}

void apply_bake_setting(Workbench::State& s, const std::string& assignment) {
    BakeSession& b = *s.bake;
    // Checked on a copy first: a bad assignment throws with the running bake untouched.
    BakeSettings edited = b.settings;
    SettingsGroup group;
    group.bind(BakeSettings::schema(), &edited);
    group.apply_assignment(assignment, "workbench");
    stop_bake_jobs(s);
    b.settings = edited;
    b.baker_dirty = true;
    restart_bake(s);
}

nlohmann::json bake_provenance(const Workbench::State& s) {
    const BakeSession& b = *s.bake;
    BakeSettings settings = b.settings;
    SettingsGroup group;
    group.bind(BakeSettings::schema(), &settings);
    std::vector<MediumDesc> media;  // the coefficients the sliders set, not the scene's
    for (size_t i = 0; i < b.media->size(); ++i) media.push_back(b.media->desc(i));
    return output_provenance(s.scene, to_string(bake_method(s)), group.to_json(),
                             long(settings.seed), media);
}

BakeSessionFile bake_session_file(const Workbench::State& s) {
    const BakeSession& b = *s.bake;
    BakeSessionFile f;
    f.settings = b.settings;
    for (size_t i = 0; i < b.media->size(); ++i) {
        const MediumDesc& d = b.media->desc(i);
        f.media.push_back({d.name, d.sigma_s, d.sigma_a, d.g, d.density_scale});
    }
    f.yaw = b.yaw, f.pitch = b.pitch, f.zoom = b.zoom;
    f.show_lobes = b.show_lobes;
    return f;
}

void apply_bake_session(Workbench::State& s, const BakeSessionFile& f) {
    BakeSession& b = *s.bake;
    stop_bake_jobs(s);
    b.settings = f.settings;
    for (size_t i = 0; i < f.media.size() && i < b.media->size(); ++i)
        b.media->set_coefficients(i, f.media[i].sigma_s, f.media[i].sigma_a, f.media[i].g,
                                  f.media[i].density_scale);
    b.yaw = f.yaw, b.pitch = f.pitch, b.zoom = f.zoom;
    b.show_lobes = f.show_lobes;
    b.baker_dirty = true;
}

}  // namespace freqlab::ui
