// Settings of a render, declared once. Method-specific structs join this file (or a sibling)
// as their methods land.
#pragma once

#include "settings/schema.h"

namespace freqlab {

// What every render shares: image size, sampling seed, display.
struct FrameSettings {
    int width = 640;
    int height = 360;
    int seed = 0;
    float exposure = 0.0f;
    static const SettingsSchema& schema();
};

// The G-buffer pass: primary rays only.
struct GBufferSettings {
    int aa_samples = 4;  // jittered primary rays averaged into the albedo/colour layers
    static const SettingsSchema& schema();
};

}  // namespace freqlab
