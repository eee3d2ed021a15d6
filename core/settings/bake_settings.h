// Settings of method B's lightmap bakers (issue "Method B, part 2"; seed, Deuxième article §5,
// §5.2, §6). The method itself (surface / extinction / impulse / vpt) is chosen on the command
// line or in the workbench, like render methods.
#pragma once

#include <cstdint>

#include "settings/schema.h"

namespace freqlab {

enum class BackScatter { Off, Albedo, On };
// How a bake path's segments cross density grids (core/volume/media.h).
enum class Tracking { Exact, Ratio };
// Where impulse's multiple scattering at a texel comes from (issue "Method B, part 3").
enum class TexelMultiple { Walk, Tables };
// Where impulse's in-scattered light of other surfaces at a texel comes from.
enum class TexelSurfaceLight { Walk, Tables };
// Where impulse's Monte Carlo terms at the texel itself come from (issue "Method B, part 4").
enum class TexelTerms { Own, Field };
// A preset of spp, bounces and texel density (BakeSettings::schema()).
enum class BakeQuality { Custom, Low, High };

struct BakeSettings {
    int spp = 64;            // paths per texel
    int bounces = 2;         // indirect surface bounces after the first vertex
    int media_bounces = 30;  // scattering events in media: 1 = single scattering only
    BackScatter back_scatter = BackScatter::Off;
    // Impulse: path vertices (0 = the texel) whose occluded emitter connections get the light
    // scattered by the lit medium around them; -1: none (the seed's §5.2).
    int lit_medium_depth = 0;
    // Impulse, at the texel: light of surfaces it cannot see (a coplanar floor, what lies
    // behind an occluder) scattered in the medium in front of it (issue "Method B, part 3").
    bool hidden_surface_light = true;
    // Impulse, at the texel: distant emitters' unoccluded single scattering corrected by the
    // real media and geometry (a control variate on the tables' half-space model).
    bool single_correction = true;
    TexelMultiple texel_multiple = TexelMultiple::Walk;
    TexelSurfaceLight texel_surface_light = TexelSurfaceLight::Walk;
    // Impulse, texel_surface_light = walk: point-lit surfaces' light also by light tracing,
    // MIS-weighted against the walk's landing (volume/bake_surface_light.cpp).
    bool surface_light_mis = true;
    // Walks through media (impulse's texel walks, vpt): the chance a direction is aimed past a
    // point light (volume/near_light_directions.h).
    float near_light_fraction = 0.1f;
    // Impulse: deeper path vertices read the texels' Monte Carlo terms of their emitters,
    // estimated before the bake (volume/vertex_corrections.h).
    bool vertex_corrections = true;
    // Impulse: the texel itself reads the field's Monte Carlo terms, as deeper vertices do,
    // instead of running its own on texel_mc_rate of its paths (the quality presets' choice).
    TexelTerms texel_terms = TexelTerms::Own;
    // Impulse, at the texel: the fraction of paths on which the Monte Carlo terms through the
    // real media run (single-scattering corrections, hidden surfaces' light, the multiple-
    // scattering walk), weighted up by its inverse (Russian roulette: unbiased at any spp).
    float texel_mc_rate = 0.02f;
    // The Monte Carlo terms' emitters (per-texel terms, texel walks, vpt's scattering events):
    // each kept by Russian roulette with a probability that follows its strength, about this
    // many kept per vertex (volume/emitter_roulette.h); 0: every emitter, every time.
    float mc_emitter_budget = 2.0f;
    // Their per-texel sums filtered over the texels within this many of it (texel_filter.h).
    int texel_mc_radius = 3;
    float texel_density = 16.0f;  // texels per scene unit
    int max_size = 1024;          // atlas side limit
    int padding = 2;              // gutter texels per chart
    float backface_tolerance = 0.3f;
    int dilation = 2;
    bool tabulated_irradiance = true;  // impulse: double products tabulated per medium
    Tracking tracking = Tracking::Exact;
    int seed = 0;
    // Light probes: a grid over the scene's bounds shrunk by 10 % (0 on any axis: none).
    int probes_x = 4, probes_y = 4, probes_z = 3;
    BakeQuality quality = BakeQuality::Custom;  // the preset last chosen
    static const SettingsSchema& schema();
};

}  // namespace freqlab
