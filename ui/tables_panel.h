// The Tables panel (method B): ZH impulse responses live on sliders — coefficient ratios
// z_l / z_0 against distance (the seed's Fig. 28, normalised so shapes compare across
// distances) and a polar cross-section of the lobe at one distance. Tables load (or build) in
// a background job the first time the panel opens.
#pragma once

#include <memory>
#include <mutex>
#include <string>

#include "base/job.h"
#include "volume/impulse_tables.h"

namespace freqlab::ui {

struct TablesPanelState {
    std::unique_ptr<Job> job;
    std::mutex mutex;
    std::shared_ptr<ImpulseTables> tables;
    std::string path;
    int emitter = 0;  // EmitterKind: 0 point, 1 directional, 2 area
    float sigma_s = 1.0f, sigma_a = 0.0f, g = 0.0f, lobe_distance = 1.0f, shift = 0.5f;
    bool surface_variant = false;
    float glyph_yaw = 35.0f;  // degrees, view of the 3D lobe glyph
    int bounces = 1;
    bool open = false;  // panel opened by default
};

std::unique_ptr<TablesPanelState> make_tables_panel();
void draw_tables_panel(TablesPanelState& state);

}  // namespace freqlab::ui
