#include "settings/render_settings.h"

namespace freqlab {

const SettingsSchema& FrameSettings::schema() {
    static const SettingsSchema s =
        SchemaBuilder<FrameSettings>("frame", "Frame")
            .field(&FrameSettings::width, "width", 1, 16384, "px", kInvalidatesGBuffer,
                   "Image width in pixels.")
            .field(&FrameSettings::height, "height", 1, 16384, "px", kInvalidatesGBuffer,
                   "Image height in pixels.")
            .field(&FrameSettings::seed, "seed", 0, 2147483647, "", kInvalidatesGBuffer,
                   "Seed of the counter-based random numbers (seed, frame, pixel, sample).")
            .field(&FrameSettings::exposure, "exposure", -20, 20, "EV", kInvalidatesDisplay,
                   "Exposure applied before sRGB encoding of colour PNGs and the viewport.")
            .build();
    return s;
}

const SettingsSchema& GBufferSettings::schema() {
    static const SettingsSchema s =
        SchemaBuilder<GBufferSettings>("gbuffer", "G-buffer")
            .field(&GBufferSettings::aa_samples, "aa_samples", 1, 256, "samples/px",
                   kInvalidatesGBuffer,
                   "Jittered primary rays per pixel averaged into albedo and colour; normal, "
                   "depth and object come from the pixel-centre ray. Only the gbuffer preview "
                   "and the reference cast them: the shading methods shade the centre hits.")
            .build();
    return s;
}

}  // namespace freqlab
