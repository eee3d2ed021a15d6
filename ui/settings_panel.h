// ImGui widgets generated from a settings declaration (core/settings): one slider, checkbox
// or combo per field, with its unit and tooltip. Returns the invalidation flags of what the
// user changed this frame.
#pragma once

#include <cstdint>

#include "settings/settings_group.h"

namespace freqlab::ui {

// `open` decides whether the sections start expanded.
uint32_t draw_settings(const SettingsGroup& group, bool open = true);

}  // namespace freqlab::ui
