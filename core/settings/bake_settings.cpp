#include "settings/bake_settings.h"

namespace freqlab {

const SettingsSchema& BakeSettings::schema() {
    static const SettingsSchema s =
        SchemaBuilder<BakeSettings>("bake", "Lightmap bake")
            .field(&BakeSettings::spp, "spp", 1, 1 << 20, "samples", kInvalidatesBake,
                   "Paths per texel (a progressive bake adds them in passes).")
            .field(&BakeSettings::bounces, "bounces", 0, 16, "", kInvalidatesBake,
                   "Indirect surface bounces: 0 bakes direct light only.")
            .field(&BakeSettings::media_bounces, "media_bounces", 1, 256, "", kInvalidatesBake,
                   "Scattering events in media: 1 = single scattering; impulse uses bounces "
                   "2..K of the tables (capped by the table file), vpt stops its walk there.")
            .choice(&BakeSettings::back_scatter, "back_scatter", {"off", "albedo", "on"},
                    kInvalidatesBake,
                    "Impulse's back-scatter compensation (seed §5.2): off = infinite-medium "
                    "tables; on = the receiver shifted 0.125 optical units towards the emitter "
                    "everywhere; albedo = that shift times the receiver's albedo (light the "
                    "surface itself reflects into the medium scales with it; a black receiver "
                    "gets none).")
            .field(&BakeSettings::lit_medium_depth, "lit_medium_depth", -1, 16, "",
                   kInvalidatesBake,
                   "Impulse: up to which path vertex (0 = the texel itself) an occluded or "
                   "below-horizon emitter connection still brings the light scattered by the lit "
                   "medium around the vertex (single: one point along a cosine-sampled "
                   "direction, 2 shadow rays; order 2: one more point by phase sampling, 2 rays; "
                   "orders 3+: the tables' unoccluded); -1: none, as the seed (§5.2: unoccluded "
                   "connections only).")
            .field(&BakeSettings::hidden_surface_light, "hidden_surface_light", 0, 1, "",
                   kInvalidatesBake,
                   "Impulse: the texel also gets the light of surfaces it cannot see (a coplanar "
                   "floor, what an occluder hides), scattered in the medium in front of it: one "
                   "medium point, a phase-sampled ray to a surface and that surface's direct "
                   "light with its tables (single exactly; order 2 by the in-medium area "
                   "response there). Needs bake.bounces >= 1, lit_medium_depth >= 0 and "
                   "texel_surface_light = tables (the walk gathers that light otherwise).")
            .field(&BakeSettings::single_correction, "single_correction", 0, 1, "",
                   kInvalidatesBake,
                   "Impulse: a distant emitter's (sun, sky) unoccluded single scattering at the "
                   "texel is the tables' half-space value plus, at one medium point, the real "
                   "media's and geometry's integrand minus the model's (a control variate: "
                   "media edges, heterogeneity and shadows the tables cannot see; 2 rays). Needs "
                   "lit_medium_depth >= 0.")
            .field(&BakeSettings::texel_mc_rate, "texel_mc_rate", 0.001, 1, "", kInvalidatesBake,
                   "Impulse: the fraction of a texel's paths that run its Monte Carlo terms "
                   "through the real media (single_correction, hidden_surface_light, the "
                   "texel_multiple walk), weighted by 1 / rate (Russian roulette: unbiased, "
                   "noisier). They are small corrections of smooth light, and cost as much as "
                   "the rest of the path. A texel whose filter window (texel_mc_radius) holds "
                   "fewer texels of its surface runs them more often: rate x (2r+1)^2 / those "
                   "texels, at most 8 x rate and 1.")
            .field(&BakeSettings::mc_emitter_budget, "mc_emitter_budget", 0, 64, "emitters",
                   kInvalidatesBake,
                   "Impulse and vpt: the Monte Carlo terms' emitters (the texel's corrections and "
                   "lit medium per connection, the walks' next-event estimation and light "
                   "tracing at scattering events) are each kept by Russian roulette with "
                   "probability min(1, max(0.1, budget x its share of the vertex's emitter "
                   "strength)), weighted by its inverse: unbiased, about this many emitters a "
                   "vertex instead of all of them (valley's 10 lights). The point lights' light "
                   "tracing and light along a segment also compete with the distant lights' "
                   "irradiance (a sun outshining far lamps). A lone emitter is always kept. 0: "
                   "every emitter, every time.")
            .field(&BakeSettings::texel_mc_radius, "texel_mc_radius", 0, 8, "texels",
                   kInvalidatesBake,
                   "Impulse: the texel's Monte Carlo terms (see texel_mc_rate) are the mean of "
                   "those of the texels within this many of it on its own surface (same chart "
                   "plane, valid): (2r+1)^2 times the samples for the bias of a box blur of a "
                   "smooth field; 0 keeps each texel's own estimate (unbiased).")
            .field(&BakeSettings::texel_density, "texel_density", 0.01, 4096, "texels/unit",
                   kInvalidatesBake, "Lightmap resolution: texels per scene unit.")
            .field(&BakeSettings::max_size, "max_size", 16, 8192, "texels", kInvalidatesBake,
                   "An atlas side never exceeds this; the density drops to fit.")
            .field(&BakeSettings::padding, "padding", 1, 16, "texels", kInvalidatesBake,
                   "Gutter around each chart.")
            .field(&BakeSettings::backface_tolerance, "backface_tolerance", 0, 1, "",
                   kInvalidatesBake,
                   "A texel whose rays hit back faces more often than this lies inside "
                   "geometry and is flagged invalid (then dilated over).")
            .field(&BakeSettings::dilation, "dilation", 0, 16, "texels", kInvalidatesBake,
                   "Rings of empty / invalid texels filled from their valid neighbours.")
            .field(&BakeSettings::tabulated_irradiance, "tabulated_irradiance", 0, 1, "",
                   kInvalidatesBake,
                   "Impulse: tabulate the ZH x clamped-cosine double product once per medium over "
                   "distance, as its polynomial in the cosine (one lookup per segment); off "
                   "queries the tables and integrates per segment.")
            .choice(&BakeSettings::texel_multiple, "texel_multiple", {"walk", "tables"},
                    kInvalidatesBake,
                    "Impulse: where the texel's light scattered twice or more by the media comes "
                    "from. walk: a random walk through the real media from the texel, ending at "
                    "the first surface (NEE from the second scattering event on; the tables "
                    "count medium beyond walls and floors: cornell_fog's floor 2.4x VPT's); "
                    "tables: the tables' multiple response (the seed's), with order 2 of "
                    "occluded connections through the lit medium. Deeper path vertices and "
                    "surface light use the tables either way.")
            .choice(&BakeSettings::texel_surface_light, "texel_surface_light", {"walk", "tables"},
                    kInvalidatesBake,
                    "Impulse: where the texel's light of other surfaces, scattered on its way, "
                    "comes from. walk: the texel's walk (at texel_mc_rate) takes, where it "
                    "reaches a surface after scattering, that surface's light (its direct light, "
                    "tables and bounces): single and multiple through the real media and "
                    "geometry, hidden surfaces included; tables: the indirect segment's vertex "
                    "as an area emitter in the tables' infinite medium, with a control variate "
                    "and hidden_surface_light (a grazing vertex weighs d^2 / cos: fireflies).")
            .field(&BakeSettings::surface_light_mis, "surface_light_mis", 0, 1, "",
                   kInvalidatesBake,
                   "Impulse, texel_surface_light = walk: the light of surfaces lit by point "
                   "lights also comes by light tracing: at each of the walk's scattering points, "
                   "one ray from every point light finds a lit point, connected to the "
                   "scattering point (2 rays), weighted against the walk landing there "
                   "(multiple importance sampling, power heuristic; unbiased). Without it the "
                   "hot spot next to a point light arrives only when a walk lands on it: "
                   "fireflies.")
            .field(&BakeSettings::near_light_fraction, "near_light_fraction", 0, 0.9, "",
                   kInvalidatesBake,
                   "Walks through media (impulse's texel walks and vpt): the chance that a "
                   "scattering or surface vertex aims its next direction at a cone about a point "
                   "light, tangent uniform (one-sample MIS with the phase function or cosine; "
                   "unbiased). A segment passing h from a point light gathers ~1 / h of its "
                   "light, which phase or cosine sampling alone finds with unbounded variance "
                   "(fireflies by lights in fog). 0: never.")
            .field(&BakeSettings::vertex_corrections, "vertex_corrections", 0, 1, "",
                   kInvalidatesBake,
                   "Impulse: path vertices deeper than lit_medium_depth take the texels' Monte "
                   "Carlo terms (single-scattering corrections, lit medium, the walk's multiple "
                   "scattering and other surfaces' light) from a field estimated before the "
                   "bake, at the nearest texel where they land: the tables' infinite medium "
                   "otherwise puts 1.2-1.4x the single and 2-2.8x the multiple scattering on "
                   "cornell_fog's walls, which every texel seeing them inherits. Costs "
                   "ceil(spp x texel_mc_rate / 2) prepass paths at every second texel.")
            .choice(&BakeSettings::texel_terms, "texel_terms", {"own", "field"}, kInvalidatesBake,
                    "Impulse: where the texel's own Monte Carlo terms come from. own: the texel "
                    "runs them on texel_mc_rate of its paths, filtered over texel_mc_radius; "
                    "field: it reads the vertex correction field at itself, as deeper vertices "
                    "do (ceil(spp x texel_mc_rate x 2.5) prepass paths every second texel, the "
                    "mean of those around it on its side of every shadow): no Monte Carlo "
                    "terms during the bake. Valley at "
                    "low quality: 0.76 -> ~0.4 of a surface bake added, lm_irradiance relMSE "
                    "0.40 -> 0.32; lit texels' 0.030 -> 0.036 (a 5x5 mean where own filters "
                    "7x7 at ~3x the paths). Used when the field is (vertex_corrections = 1, "
                    "lit_medium_depth >= 0) with texel_surface_light = walk; stats.json's "
                    "texel_terms says which ran.")
            .choice(&BakeSettings::tracking, "tracking", {"exact", "ratio"}, kInvalidatesBake,
                    "How extinction and impulse segments cross density grids: exact visits every "
                    "voxel (3D DDA; O(1) for grids that vary along one axis); ratio tracks "
                    "against the grid's majorant: unbiased transmittance and optical thickness "
                    "from a few density lookups, noisier (impulse queries its tables with the "
                    "noisy thickness: the response is not linear in it, so a small bias). "
                    "Homogeneous media are exact either way; vpt always samples exactly.")
            .field(&BakeSettings::probes_x, "probes_x", 0, 64, "", kInvalidatesBake,
                   "Light probes along x (order-3 SH of incident radiance; 0: no probes).")
            .field(&BakeSettings::probes_y, "probes_y", 0, 64, "", kInvalidatesBake,
                   "Light probes along y.")
            .field(&BakeSettings::probes_z, "probes_z", 0, 64, "", kInvalidatesBake,
                   "Light probes along z.")
            .field(&BakeSettings::seed, "seed", 0, 1 << 30, "", kInvalidatesBake,
                   "Random seed of the bake (results never depend on the thread count).")
            .preset(&BakeSettings::quality, "quality", {"custom", "low", "high"},
                    {{},
                     {{"spp", 16}, {"bounces", 2}, {"texel_density", 4}, {"texel_terms", 1}},
                     {{"spp", 128}, {"bounces", 4}, {"texel_density", 8}, {"texel_terms", 1}}},
                    kInvalidatesBake,
                    "A production baker's two modes: choosing one writes the settings below "
                    "(later --set or edits of them win; stats report the values used). custom "
                    "writes nothing.")
            .build();
    return s;
}

}  // namespace freqlab
