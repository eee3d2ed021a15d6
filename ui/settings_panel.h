// ImGui widgets generated from a settings declaration (core/settings): one slider, checkbox
// or combo per field, with its unit and tooltip. Returns the invalidation flags of what the
// user changed this frame.
#pragma once

#include <cstdint>

#include "settings/settings_group.h"

namespace freqlab::ui {

// `open` decides whether the sections start expanded.
uint32_t draw_settings(const SettingsGroup& group, bool open = true);
// The widest label ("key (unit)") of the group's fields, in pixels of the current font.
float settings_label_width(const SettingsGroup& group);
float settings_label_width(const SettingsSchema& schema);
// Sets the item width so that labels of `label_width` fit beside the widgets (pop with
// ImGui::PopItemWidth).
void push_label_room(float label_width);

}  // namespace freqlab::ui
