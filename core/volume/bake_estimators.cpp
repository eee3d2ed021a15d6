#include "volume/bake_estimators.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "base/error.h"
#include "math/sampling.h"
#include "math/sh.h"
#include "volume/emitter_roulette.h"
#include "volume/vertex_corrections.h"

namespace freqlab {

const std::vector<BakeMethod>& bake_methods() {
    static const std::vector<BakeMethod> all = [] {
        std::vector<BakeMethod> v;
        for (const EnumName<BakeMethod>& e : kBakeMethodNames) v.push_back(e.value);
        return v;
    }();
    return all;
}

std::string bake_method_list(const std::string& separator) {
    return enum_name_list(kBakeMethodNames, separator);
}

bool is_bake_method(const std::string& name) {
    for (const EnumName<BakeMethod>& e : kBakeMethodNames)
        if (name == e.name) return true;
    return false;
}

BakeMethod parse_bake_method(const std::string& text) {
    return enum_from_name(kBakeMethodNames, text, "--method");
}

BakeEstimator::BakeEstimator(const RayScene& scene, const Media& media, const ImpulseTables* tables,
                             BakeMethod method, const BakeSettings& settings)
    : scene_(scene),
      media_(media),
      tables_(tables),
      method_(method),
      settings_(settings),
      near_lights_(scene.scene().lights, settings.near_light_fraction) {
    if (method == BakeMethod::Impulse && !media.empty() && !tables)
        throw Error("", "--method", "impulse needs the impulse-response tables");
    if (tables) {
        table_bounces_ = tables->bounces();
        if (settings.tabulated_irradiance)
            irradiance_ = std::make_unique<ImpulseIrradianceCache>(*tables);
    }
    for (const Light& light : scene.scene().lights)
        if (light.type == LightType::Point) ++point_lights_;
    distant_strength_ = distant_light_strength(scene.scene().lights, scene.environment());
    attenuates_ = method != BakeMethod::Surface && !media.empty();
    scatters_ = method == BakeMethod::Impulse && !media.empty();
    zh_clamped_cosine(kImpulseOrder, cosine_zh_);
    check_media();
}

void BakeEstimator::check_media() const {
    if (!scatters_) return;
    for (size_t i = 0; i < media_.size(); ++i) {
        const MediumDesc& d = media_.desc(i);
        if (!(std::fabs(d.g) <= kGRange)) {
            char text[200];
            std::snprintf(text, sizeof text,
                          "g = %.4g: method B's impulse tables cover |g| <= %.2f (HG's response "
                          "is singular at |g| = 1); bake with --method vpt or lower |g|",
                          d.g, kGRange);
            throw Error("", "media[" + std::to_string(i) + "].g (" + d.name + ")", text);
        }
    }
}

bool BakeEstimator::texel_walk() const {
    return scatters_ && settings_.texel_multiple == TexelMultiple::Walk &&
           settings_.media_bounces > 1;
}

bool BakeEstimator::surface_light_walk() const {
    return scatters_ && settings_.texel_surface_light == TexelSurfaceLight::Walk;
}

vec3 BakeEstimator::origin(const vec3& p, const vec3& n) const {
    return spawn_point(p, n);
}

bool BakeEstimator::visible(const vec3& from, const vec3& n, const vec3& dir, double distance,
                            BakeCounters& counters) const {
    ++counters.rays;
    return !scene_.occluded(shadow_ray(origin(from, n), dir, distance));
}

void BakeEstimator::sample_emitters(const vec3& p, CounterRng& rng,
                                    std::vector<EmitterSample>& out) const {
    out.clear();
    struct {
        vec4 u;
        int texel = 0, slot = -1;
    } environment;
    const std::vector<Light>& lights = scene_.scene().lights;
    for (size_t index = 0; index < lights.size(); ++index) {
        const Light& light = lights[index];
        EmitterSample s;
        s.light = int(index);
        switch (light.type) {
            case LightType::Point:
            case LightType::Directional:
            case LightType::Quad: {
                vec2 u(0.0f);
                if (light_sample_dimensions(light) == 2) {
                    u.x = rng.next_float();
                    u.y = rng.next_float();
                }
                const LightSample ls = sample_light(light, p, u);
                if (!ls.valid) {
                    // p behind a quad: no direct light, but the medium in front of the quad
                    // it sees is lit (smoke_room's ceiling: single 0.31x VPT's without it).
                    if (!scatters_ || light.type != LightType::Quad || !(ls.distance > 0.0f))
                        continue;
                    s.kind = EmitterKind::Area;
                    s.dir = ls.direction;
                    s.distance = ls.distance;
                    s.emitter_normal = ls.emitter_normal;
                    s.intensity = ls.intensity;
                    s.behind = true;
                    out.push_back(s);
                    continue;
                }
                s.kind = light.type == LightType::Point         ? EmitterKind::Point
                         : light.type == LightType::Directional ? EmitterKind::Directional
                                                                : EmitterKind::Area;
                s.dir = ls.direction;
                s.distance = ls.distance;
                s.irradiance = ls.irradiance;
                s.intensity = ls.intensity;
                s.fixed = light.type != LightType::Quad;
                if (light.type == LightType::Quad) {
                    s.emitter_normal = ls.emitter_normal;
                    s.shift = std::sqrt(std::max(0.0f, 1.0f - ls.emitter_cos * ls.emitter_cos));
                }
                break;
            }
            case LightType::Environment:
            case LightType::Sky: {
                const EnvironmentMap* env = scene_.environment();
                if (!env) continue;
                // The texel is read once the other lights are sampled: its cache miss (a
                // 2048 x 1024 sky is 32 MB of texels) overlaps their work.
                environment.u =
                    vec4(rng.next_float(), rng.next_float(), rng.next_float(), rng.next_float());
                environment.texel = env->sample_texel(environment.u);
                env->prefetch_texel(environment.texel);
                environment.slot = int(out.size());
                s.kind = EmitterKind::Directional;
                break;
            }
        }
        out.push_back(s);
    }
    if (environment.slot >= 0) {
        EmitterSample& s = out[size_t(environment.slot)];
        float pdf = 0.0f;
        const vec3 radiance =
            scene_.environment()->sample_at(environment.texel, environment.u, &s.dir, &pdf);
        if (pdf > 0.0f)
            s.irradiance = s.intensity = radiance / pdf;
        else
            out.erase(out.begin() + environment.slot);
    }
}

SegmentOptics BakeEstimator::segment_optics(const vec3& p, const vec3& dir, double length,
                                            CounterRng& rng) const {
    return settings_.tracking == Tracking::Ratio ? media_.track(p, dir, length, rng)
                                                 : media_.integrate(p, dir, length);
}

IrradianceParts BakeEstimator::estimate(const vec3& p, const vec3& n, const vec3& albedo,
                                        CounterRng& rng, BakeCounters& counters, FixedDirect* fixed,
                                        IrradianceParts* deferred, float mc_rate,
                                        UnoccludedSingle* unoccluded) const {
    const bool reuse = fixed && settings_.tracking == Tracking::Exact;
    IrradianceParts later;
    UnoccludedSingle single;
    IrradianceParts parts = method_ == BakeMethod::Vpt
                                ? volume_path(p, n, rng, counters)
                                : surface_path(p, n, albedo, 0, rng, counters,
                                               reuse ? fixed : nullptr, deferred ? &later : nullptr,
                                               false, mc_rate, unoccluded ? &single : nullptr);
    if (!all_finite(parts.total()) || !all_finite(later.total()) ||
        !all_finite(single.tables + single.real + single.paired_tables +
                    single.surface_light_multiple)) {
        ++counters.guarded;
        return {};
    }
    if (deferred) *deferred += later;
    if (unoccluded) {
        single.paths = 1.0f;
        *unoccluded += single;
    }
    return parts;
}

IrradianceParts BakeEstimator::estimate_texel(const LightmapTexel& t, size_t map, size_t texel,
                                              CounterRng& rng, BakeCounters& counters,
                                              FixedDirect* fixed, IrradianceParts* deferred,
                                              float mc_rate, UnoccludedSingle* unoccluded) const {
    if (!texel_reads_field_)
        return estimate(t.position, t.normal, t.albedo, rng, counters, fixed, deferred, mc_rate,
                        unoccluded);
    // The texel as a deeper vertex landing on it: the field at itself. Its fixed lights'
    // shadows (FixedDirect::shadows, known from the first path) decide whether it holds.
    FieldRead read;
    const IrradianceParts parts =
        field_corrected_path(corrections_->at_texel(map, texel), t.position, t.normal, t.albedo, 0,
                             rng, counters, fixed, nullptr, read);
    if (TexelPathRecord* record = PathRecording::current()) {
        record->texel_field.read = true;
        record->texel_field.holds = read.holds;
        record->texel_field.drew_corrections = read.drew_corrections;
        record->texel_field.added = read.added;
    }
    if (!all_finite(parts.total())) {
        ++counters.guarded;
        return {};
    }
    return parts;
}

void BakeEstimator::set_vertex_corrections(const VertexCorrectionField* field) {
    corrections_ = field;
    // The prepass's own estimator runs the texels' terms itself.
    texel_reads_field_ = field && !field->empty() && scatters_ && texels_read_field(settings_) &&
                         settings_.lit_medium_depth >= 0 && prepass_surface_depth_ < 0;
}

bool BakeEstimator::seen(const EmitterSample& s, const vec3& p, const vec3& n,
                         BakeCounters& counters) const {
    // Below the horizon the segment to the emitter enters the receiver's own surface at once:
    // no ray is cast, and like an occluded one the connection brings no direct light; the
    // light scattered by the lit medium around the receiver is lit_medium_single's.
    return !s.behind && glm::dot(n, s.dir) > 0.0f && visible(p, n, s.dir, s.distance, counters);
}

uint64_t BakeEstimator::fixed_light_shadows(const vec3& p, const vec3& n,
                                            BakeCounters& counters) const {
    // The point and directional lights as sample_emitters makes them (no random numbers).
    uint64_t shadows = 0;
    const std::vector<Light>& lights = scene_.scene().lights;
    for (size_t index = 0; index < lights.size(); ++index) {
        const Light& light = lights[index];
        if (light.type != LightType::Point && light.type != LightType::Directional) continue;
        const LightSample ls = sample_light(light, p, vec2(0.0f));
        if (!ls.valid) continue;
        EmitterSample s;
        s.light = int(index);
        s.dir = ls.direction;
        s.distance = ls.distance;
        if (!seen(s, p, n, counters)) shadows |= shadow_bit(s.light);
    }
    return shadows;
}

bool BakeEstimator::direct_light(const EmitterSample& s, const vec3& p, const vec3& n,
                                 float albedo_lum, CounterRng& rng, BakeCounters& counters,
                                 IrradianceParts& parts, OccludedConnection* occluded,
                                 bool no_multiple) const {
    const float cos_x = glm::dot(n, s.dir);
    if (!seen(s, p, n, counters)) {
        if (!scatters_ || !occluded) return false;
        occluded->occluded = true;
        // Behind an area light the tables have no response (they are of its front).
        if (!no_multiple && !s.behind && settings_.media_bounces > 2)
            occluded->multiple = unoccluded_higher_orders(s, p, n, albedo_lum, rng, counters);
        return false;
    }
    SegmentOptics optics;
    // An infinite distance ends where the ray leaves the media (optics.length).
    if (attenuates_) optics = segment_optics(p, s.dir, s.distance, rng);
    parts.surface += s.irradiance * cos_x * optics.transmittance_float();
    if (scatters_) {
        const double distance = std::isfinite(s.distance) ? s.distance : optics.length;
        IrradianceParts scattered;
        add_scattered(s.kind, s.intensity, s.dir, distance, s.shift, s.emitter_normal, optics, n,
                      albedo_lum, scattered, counters);
        parts.single += scattered.single;
        if (!no_multiple) parts.multiple += scattered.multiple;
    }
    return true;
}

IrradianceParts BakeEstimator::surface_path(const vec3& p, const vec3& n, const vec3& albedo,
                                            int depth, CounterRng& rng, BakeCounters& counters,
                                            FixedDirect* fixed, IrradianceParts* deferred,
                                            bool corrected, float mc_rate,
                                            UnoccludedSingle* unoccluded) const {
    IrradianceParts parts;
    const float albedo_lum = luminance(albedo);
    // One buffer per path depth and thread: no allocation per vertex.
    thread_local std::vector<std::vector<EmitterSample>> buffers;
    if (buffers.size() <= size_t(depth)) buffers.resize(size_t(depth) + 1);
    std::vector<EmitterSample> local = std::move(buffers[size_t(depth)]);
    sample_emitters(p, rng, local);
    IrradianceParts fixed_parts;
    const bool learn = fixed && !fixed->known;
    // Occluded connections' lit-medium estimates run after every connection is resolved, in
    // emitter order, whether or not the fixed lights were reused: the same random numbers
    // either way.
    thread_local std::vector<std::vector<OccludedConnection>> occluded_buffers;
    if (occluded_buffers.size() <= size_t(depth)) occluded_buffers.resize(size_t(depth) + 1);
    std::vector<OccludedConnection>& occluded = occluded_buffers[size_t(depth)];
    // Up to bake.lit_medium_depth (the texel itself by default: deeper vertices' shadows reach
    // it through a diffuse bounce, and cost as much).
    const bool lit_here =
        scatters_ && depth <= settings_.lit_medium_depth && !(depth == 0 && texel_reads_field_);
    occluded.assign(lit_here ? local.size() : 0, OccludedConnection{});
    const bool walk_here = lit_here && texel_walk();
    // Without the tables' multiple scattering where a walk supplies it (here or in the field).
    const bool no_multiple = walk_here || (corrected && texel_walk());
    // Other surfaces' light scattered on its way here comes from the texel's walk, not from
    // the indirect segment's vertex in the tables' infinite medium.
    const bool prepass = prepass_surface_depth_ >= 0;
    const bool surface_walk_here =
        lit_here && surface_light_walk() &&
        (prepass ? prepass_surface_depth_ <= settings_.bounces : depth < settings_.bounces);
    // A vertex whose field value holds its surface light's scattering (vertex_corrections.h).
    const bool field_surface_light =
        corrected && depth < settings_.bounces && corrections_->has_surface_light();
    // A deeper vertex reading the field keeps the tables' multiple scattering until it knows
    // whether the field holds for it (vertex_irradiance).
    const bool keep_multiple = no_multiple && unoccluded && !lit_here;
    // A vertex drawing its own corrections (no ratio in its field texel) takes their real
    // part alone as its single scattering: unbiased and >= 0. The tables' value plus the
    // difference, unbiased too, went negative wherever a rare connection through a gap drew a
    // model larger than its tables (valley, 1 texel/unit: irradiance -0.11 where VPT reads
    // 0.006); there the real media are dark and the model is no control variate.
    const bool draw = unoccluded && unoccluded->draw_corrections;
    vec3 drawn_tables(0.0f);
    for (size_t i = 0; i < local.size(); ++i) {
        const EmitterSample& s = local[i];
        OccludedConnection c;
        OccludedConnection* want = lit_here ? &c : nullptr;
        if (!fixed || !s.fixed) {
            IrradianceParts own;
            const bool seen = direct_light(s, p, n, albedo_lum, rng, counters, draw ? own : parts,
                                           want, no_multiple && !keep_multiple);
            if (!seen && s.fixed && unoccluded) unoccluded->shadows |= shadow_bit(s.light);
            if (draw) {
                parts.surface += own.surface;
                parts.multiple += own.multiple;
                drawn_tables += own.single;
                if (seen) parts.single += connection_single_correction(s, p, n, rng, counters).real;
            }
            if (!seen && lit_here) occluded[i] = c;
        } else if (learn) {
            if (!direct_light(s, p, n, albedo_lum, rng, counters, fixed_parts, want,
                              no_multiple && !keep_multiple)) {
                fixed->shadows |= shadow_bit(s.light);
                if (lit_here) fixed->occluded.emplace_back(s.light, c);
            }
        }
    }
    if (fixed) {
        if (learn) {
            fixed->known = true;
            fixed->parts = fixed_parts;
        }
        parts += fixed->parts;
        if (unoccluded) unoccluded->shadows |= fixed->shadows;
        for (const auto& [light, c] : fixed->occluded)
            for (size_t i = 0; i < local.size(); ++i)
                if (local[i].light == light && local[i].fixed) occluded[i] = c;
    }
    // The Monte Carlo terms through the real media (corrections of the tables' single
    // scattering, the lit medium of connections below the horizon, hidden surfaces' light, the
    // multiple-scattering walk) run on a fraction of the paths (bake.texel_mc_rate), weighted
    // up: Russian roulette, decided once per vertex. At the texel they may be deferred: the
    // baker sums them apart and filters them over neighbouring texels (bake.texel_mc_radius).
    bool mc_here = lit_here;
    float mc_weight = 1.0f;
    const float rate = mc_rate > 0.0f ? mc_rate : settings_.texel_mc_rate;
    if (lit_here && rate < 1.0f) {
        mc_here = rng.next_float() < rate;
        mc_weight = 1.0f / rate;
    }
    TexelPathRecord* record = depth == 0 ? PathRecording::current() : nullptr;
    if (record) {
        record->mc_ran = mc_here;
        record->mc_weight = mc_here ? mc_weight : 0.0f;
    }
    // Here parts.single holds the tables' single scattering of the unoccluded connections.
    // (A drawing vertex's parts.single holds the real parts instead.)
    if (unoccluded) unoccluded->tables += draw ? drawn_tables : parts.single;
    if (keep_multiple) {
        unoccluded->left_multiple = parts.multiple;
        parts.multiple = vec3(0.0f);
    }
    IrradianceParts mc;
    if (mc_here && !occluded.empty()) {
        // Each emitter's terms by roulette on its strength (bake.mc_emitter_budget).
        const std::vector<float> keep = mc_keep(local, occluded, n);
        for (size_t i = 0; i < occluded.size(); ++i) {
            if (!has_mc_term(local[i], occluded[i], n)) continue;
            const float w = emitter_roulette_weight(keep[i], rng);
            if (w == 0.0f) continue;
            IrradianceParts term;
            vec3 drawn(0.0f);  // what the term filed (recorded)
            if (occluded[i].occluded) {
                add_lit_medium(local[i], p, n, occluded[i].multiple, rng, counters, term,
                               walk_here);
            } else {
                const SingleCorrection drawn_parts =
                    connection_single_correction(local[i], p, n, rng, counters);
                // What is filed: the real part apart, or the control variate into the term.
                drawn = unoccluded ? drawn_parts.real : drawn_parts.difference();
                // The real part filed apart, its ratio to tables applied to a texel's or
                // vertex's own tables: the field's to the tables of every path of its prepass
                // (drawn on every path), the texel filter's to the tables of the very
                // connections drawn. Added to the tables of every path, a rare correction
                // weighted 1 / rate (an environment sample through a gap under a house, about
                // minus its tables' value) left a texel there at -1.5 where VPT reads 0
                // (valley, 4 texels/unit); as tables + corrections the ratio still went below
                // 0 where a window's models outweighed its tables.
                if (unoccluded) {
                    const float weight = w * mc_weight;
                    unoccluded->real += drawn_parts.real * weight;
                    if (!prepass)
                        unoccluded->paired_tables +=
                            unoccluded_scatter(local[i], p, n, albedo_lum, rng, counters).single *
                            weight;
                } else {
                    term.single += drawn;
                }
            }
            mc.single += term.single * w;
            mc.multiple += term.multiple * w;
            if (record) {
                IrradianceParts value = term;
                if (!occluded[i].occluded) value.single = drawn;
                value.single *= w;
                value.multiple *= w;
                record->terms.push_back({local[i].light, occluded[i].occluded, w, value});
            }
        }
    }
    buffers[size_t(depth)] = std::move(local);
    if (mc_here && settings_.hidden_surface_light && !surface_walk_here && !prepass && depth == 0 &&
        settings_.bounces > 0) {
        const ScatteredSurfaceLight hidden = surface_light_scattered(p, n, rng, counters);
        mc.single += hidden.single;
        mc.multiple += hidden.multiple;
        if (record) {
            record->hidden.single = hidden.single;
            record->hidden.multiple = hidden.multiple;
        }
    }
    if ((walk_here || surface_walk_here) && mc_here) {
        // Through the real media: VPT's walk from the receiver, ending at the first surface;
        // emitters' orders 2+ by NEE from its second scattering event on (texel_multiple =
        // walk), the surface it ends on after scattering as the light of that surface
        // (texel_surface_light = walk).
        IrradianceParts surface_light;
        TexelWalk texel;
        texel.emitters_multiple = walk_here;
        texel.surface_light_depth = !surface_walk_here ? -1
                                    : prepass          ? prepass_surface_depth_
                                                       : depth + 1;
        texel.surface_light = &surface_light;
        const vec3 walked = texel_walk_from(p, n, rng, counters, texel).multiple;
        mc.multiple += walked;
        if (record) {
            record->walk = surface_light;
            record->walk.multiple += walked;
        }
        // The prepass files surface light under `surface`, where nothing else of the texel's
        // own Monte Carlo terms lands (no indirect segment runs there): the field keeps it apart.
        if (prepass) {
            mc.surface += surface_light.total();
            if (unoccluded)
                unoccluded->surface_light_multiple += surface_light.multiple * mc_weight;
        } else {
            mc += surface_light;
        }
    }
    if (depth < settings_.bounces && !(prepass && depth == 0))
        indirect_segment(p, n, albedo_lum, depth, rng, counters, parts,
                         mc_here && settings_.single_correction ? &mc.single : nullptr, deferred,
                         !surface_walk_here && !field_surface_light);
    if (mc_here) {
        mc.surface *= mc_weight;
        mc.single *= mc_weight;
        mc.multiple *= mc_weight;
        (deferred ? *deferred : parts) += mc;
    }
    return parts;
}

void BakeEstimator::indirect_segment(const vec3& p, const vec3& n, float albedo_lum, int depth,
                                     CounterRng& rng, BakeCounters& counters,
                                     IrradianceParts& parts, vec3* correction,
                                     IrradianceParts* deferred, bool scatter) const {
    // One indirect segment, cosine-sampled: irradiance = pi x radiance on average.
    const float u1 = rng.next_float(), u2 = rng.next_float();
    const vec3 local_dir = sample_cosine_hemisphere(u1, u2);
    if (local_dir.z <= 1e-6f) return;
    const vec3 dir = Frame(n).to_world(local_dir);
    ++counters.rays;
    const SurfaceHit hit = scene_.intersect(Ray{origin(p, n), dir, 0.0f, INFINITY});
    if (!hit.valid) return;  // environment light arrives by NEE only
    const Material& material = scene_.scene().materials[size_t(hit.material)];
    if (material.type == BrdfType::Mirror) return;
    const vec3 albedo_y = material.albedo.eval(hit.uv);
    if (glm::all(glm::equal(albedo_y, vec3(0.0f)))) return;
    // y's deferred Monte Carlo terms travel to p apart from the rest (the response to y's
    // light is linear in it), so that the baker filters them too.
    IrradianceParts sub_deferred;
    TexelPathRecord* record = depth == 0 ? PathRecording::current() : nullptr;
    if (record) record->in_bounce = true;
    const IrradianceParts sub = vertex_irradiance(hit, albedo_y, depth + 1, rng, counters,
                                                  deferred ? &sub_deferred : nullptr);
    if (record) {
        record->in_bounce = false;
        record->bounce.hit = true;
        record->bounce.object = hit.object;
        record->bounce.position = hit.position;
        record->bounce.distance = hit.distance;
        record->bounce.vertex = sub;
    }
    const vec3 radiance = albedo_y * kInvPi * sub.total();  // L(y -> p), diffuse
    const vec3 radiance_deferred = albedo_y * kInvPi * sub_deferred.total();
    // A vertex that gathered nothing (its emitters hidden, its own path lost) sends nothing to
    // attenuate or scatter: no tracking, no table lookup.
    const bool any_deferred = !glm::all(glm::equal(radiance_deferred, vec3(0.0f)));
    if (glm::all(glm::equal(radiance, vec3(0.0f))) && !any_deferred) return;
    SegmentOptics optics;
    if (attenuates_) optics = segment_optics(p, dir, hit.distance, rng);
    parts.surface += kPi * radiance * optics.transmittance_float();
    if (any_deferred) deferred->surface += kPi * radiance_deferred * optics.transmittance_float();
    if (scatters_ && scatter) {
        // y as a differential-area emitter of intensity L dA cos_y max(n_y . u, 0) / cos_y: with
        // dA = d^2 domega / cos_y and domega = 1 / pdf, I0 = L d^2 / (cos_y pdf).
        const float cos_y = std::max(1e-3f, std::abs(glm::dot(hit.shading_normal, dir)));
        const float pdf = local_dir.z * kInvPi;
        const double d = hit.distance;
        const float to_intensity = float(d * d / (double(cos_y) * pdf));
        const vec3 intensity = radiance * to_intensity;
        const double shift = std::sqrt(std::max(0.0f, 1.0f - cos_y * cos_y));
        // The infinite medium's multiple response counts the medium behind y's surface, where
        // there is none: kSurfaceEmitterMultipleWeight of it (area_response_rescattered).
        IrradianceParts response;
        add_scattered(EmitterKind::Area, intensity, dir, d, shift, hit.shading_normal, optics, n,
                      albedo_lum, response, counters);
        response.multiple *= kSurfaceEmitterMultipleWeight;
        parts += response;
        if (any_deferred) {
            response = {};
            add_scattered(EmitterKind::Area, radiance_deferred * to_intensity, dir, d, shift,
                          hit.shading_normal, optics, n, albedo_lum, response, counters);
            response.multiple *= kSurfaceEmitterMultipleWeight;
            *deferred += response;
        }
        if (correction) {
            // y's light scattered once on the way is the area tables' infinite medium too.
            EmitterSample y;
            y.kind = EmitterKind::Area;
            y.dir = dir;
            y.distance = d;
            y.intensity = intensity + radiance_deferred * to_intensity;
            y.emitter_normal = hit.shading_normal;
            *correction += local_single_correction(y, p, n, rng, counters).difference();
        }
    }
}

IrradianceParts BakeEstimator::field_corrected_path(const VertexCorrectionField::Texel& field,
                                                    const vec3& p, const vec3& n,
                                                    const vec3& albedo, int depth, CounterRng& rng,
                                                    BakeCounters& counters, FixedDirect* fixed,
                                                    IrradianceParts* deferred,
                                                    FieldRead& read) const {
    UnoccludedSingle single;
    // A field texel whose prepass met no unoccluded connection (a pocket under a house's floor,
    // a wall's cavity) has no ratio: the tables' infinite medium, lit along a sky sample or
    // sunbeam through a gap, went uncorrected there. Valley (low, seed 0): the houses' darkest
    // texels (VPT < 5e-4) read 1.53x VPT's irradiance, their bounces' vertices' scattered light
    // ~4x; drawn at the vertex (0.8 M corrections, 1 % of the rays), 1.13x.
    single.draw_corrections =
        field.found() && settings_.single_correction && !field.single_ratio_known();
    read.drew_corrections = single.draw_corrections;
    IrradianceParts parts = surface_path(p, n, albedo, depth, rng, counters, fixed, deferred,
                                         field.found(), -1.0f, field.found() ? &single : nullptr);
    // Read after the vertex's own path, which hides the read's cache miss. The corrections of
    // the unoccluded connections scale with the vertex's own tables' value of them. A vertex
    // shadowed otherwise than the texel (a pocket of a layered wall whose texel's centre sees
    // a lamp) keeps its tables' multiple scattering instead.
    if (field.found()) {
        read.holds = field.holds_for(single.shadows);
        const bool with_surface_light = depth < settings_.bounces;
        read.added = read.holds
                         ? field.value(with_surface_light) + field.single_ratio() * single.tables
                         : vec3(0.0f);
        if (read.holds) {
            // In-scattered light: its multiple part where the field reports it (a texel's
            // read, at_texel), else all of it as single (a deeper vertex's: only the total
            // reaches the texel).
            const vec3 multiple = field.multiple(with_surface_light);
            parts.single += read.added - multiple;
            parts.multiple += multiple;
        } else {
            parts.multiple += single.left_multiple;
        }
    }
    return parts;
}

IrradianceParts BakeEstimator::vertex_irradiance(const SurfaceHit& hit, const vec3& albedo,
                                                 int depth, CounterRng& rng, BakeCounters& counters,
                                                 IrradianceParts* deferred) const {
    VertexCorrectionField::Texel field;
    if (corrections_ && scatters_ && depth > settings_.lit_medium_depth)
        field = corrections_->locate(hit, &counters.rays);
    FieldRead read;
    const IrradianceParts parts =
        field_corrected_path(field, hit.position, hit.shading_normal, albedo, depth, rng, counters,
                             nullptr, deferred, read);
    TexelPathRecord* record = depth == 1 ? PathRecording::current() : nullptr;
    if (field.found() && record && record->in_bounce) {
        record->bounce.field_read = read.holds;
        record->bounce.drew_corrections = read.drew_corrections;
        record->bounce.field = read.added;
    }
    return parts;
}

}  // namespace freqlab
