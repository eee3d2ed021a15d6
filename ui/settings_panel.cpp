#include "settings_panel.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>

namespace freqlab::ui {

namespace {

std::string visible_label(const SettingField& f) {
    return f.key + (f.unit.empty() ? "" : " (" + f.unit + ")");
}

uint32_t draw_field(const SettingsSchema& schema, const SettingField& f, void* object) {
    const std::string label = visible_label(f) + "##" + schema.prefix() + "." + f.key;
    const double before = f.get(object);
    double after = before;
    switch (f.type) {
        case SettingType::Bool: {
            bool v = before != 0;
            if (ImGui::Checkbox(label.c_str(), &v)) after = v ? 1 : 0;
            break;
        }
        case SettingType::Int: {
            int v = int(before);
            // Wide integer ranges (sizes, seeds) get a drag field rather than a slider.
            const bool drag = f.max - f.min > 1000;
            const bool changed =
                drag ? ImGui::DragInt(label.c_str(), &v, 1.0f, int(f.min), int(f.max))
                     : ImGui::SliderInt(label.c_str(), &v, int(f.min), int(f.max));
            if (changed) after = std::clamp(double(v), f.min, f.max);
            break;
        }
        case SettingType::Float: {
            float v = float(before);
            // Ranges over decades (epsilons, exposures of spp) slide logarithmically.
            const bool log_scale = f.min > 0 && f.max / f.min > 100;
            if (ImGui::SliderFloat(label.c_str(), &v, float(f.min), float(f.max), "%.4g",
                                   log_scale ? ImGuiSliderFlags_Logarithmic : 0))
                after = std::clamp(double(v), f.min, f.max);
            break;
        }
        case SettingType::Choice: {
            int v = int(before);
            std::string items;
            for (const std::string& c : f.choices) items += c + '\0';
            if (ImGui::Combo(label.c_str(), &v, items.c_str())) after = v;
            break;
        }
    }
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("%s\nchanging it invalidates: %s", f.tooltip.c_str(),
                          invalidates_to_string(f.invalidates).c_str());
    if (after == before) return 0;
    schema.set_value(object, f, after, "gui", schema.prefix() + "." + f.key);
    return f.invalidates;
}

}  // namespace

float settings_label_width(const SettingsSchema& schema) {
    float widest = 0.0f;
    for (const SettingField& f : schema.fields())
        widest = std::max(widest, ImGui::CalcTextSize(visible_label(f).c_str()).x);
    return widest;
}

float settings_label_width(const SettingsGroup& group) {
    float widest = 0.0f;
    for (const SettingsGroup::Binding& b : group.bindings())
        widest = std::max(widest, settings_label_width(*b.schema));
    return widest;
}

void push_label_room(float label_width) {
    // Widgets take what the labels leave (labels were cut at "sigma_positi"), but never less
    // than 40 % of the panel: a narrow panel is widened by dragging its edge.
    const float avail = ImGui::GetContentRegionAvail().x;
    const float room = label_width + ImGui::GetStyle().ItemInnerSpacing.x;
    ImGui::PushItemWidth(std::max(avail - room, 0.4f * avail));
}

uint32_t draw_settings(const SettingsGroup& group, bool open) {
    uint32_t flags = 0;
    for (const SettingsGroup::Binding& b : group.bindings()) {
        if (!ImGui::CollapsingHeader(b.schema->title().c_str(),
                                     open ? ImGuiTreeNodeFlags_DefaultOpen : 0))
            continue;
        for (const SettingField& f : b.schema->fields())
            flags |= draw_field(*b.schema, f, b.object);
    }
    return flags;
}

}  // namespace freqlab::ui
