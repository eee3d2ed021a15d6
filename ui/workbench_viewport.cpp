// The workbench's viewport: the shown layer through its colormap (or over colour), zoom and pan,
// the colorbar or legend, the picked pixel, the reference split.
#include <glad/gl.h>
#include <imgui.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include "image/colormap.h"
#include "layer_view.h"
#include "render/frame_renderer.h"
#include "workbench.h"
#include "workbench_state.h"

namespace freqlab::ui {

namespace {

ImU32 to_u32(const vec3& c) {
    return ImGui::ColorConvertFloat4ToU32(ImVec4(c.r, c.g, c.b, 1.0f));
}

void draw_colorbar(Workbench::State& s, const Layer& layer, ImVec2 origin, float width) {
    ImDrawList* dl = ImGui::GetWindowDrawList();
    s.colorbar_rect = {};
    s.legend.clear();
    if (layer.kind == LayerKind::Color || layer.channels >= 3) return;
    if (layer.kind == LayerKind::Categorical) {
        // Swatch + name per category, wrapping to new lines within the viewport's width.
        const float right = origin.x + std::max(width, ImGui::GetContentRegionAvail().x);
        float x = origin.x, y = origin.y;
        for (size_t i = 0; i < layer.legend.size(); ++i) {
            const float item = 18 + ImGui::CalcTextSize(layer.legend[i].c_str()).x + 14;
            if (x > origin.x && x + item > right) x = origin.x, y += 20;
            const ImVec2 a(x, y + 2), b(x + 14, y + 16);
            dl->AddRectFilled(a, b, to_u32(category_colour(layer, int(i))));
            dl->AddText(ImVec2(x + 18, y + 2), IM_COL32(230, 230, 230, 255),
                        layer.legend[i].c_str());
            s.legend.push_back({layer.legend[i], ScreenRect{a.x, a.y, b.x, b.y}});
            x += item;
        }
        ImGui::Dummy(ImVec2(width, y - origin.y + 20));
        return;
    }
    // Gradient in 128 steps drawn from the same colormap functions as the LUTs.
    const int steps = 128;
    const float h = 14;
    const DisplayRange r = s.shown_range;
    for (int i = 0; i < steps; ++i) {
        const float t0 = float(i) / steps, t1 = float(i + 1) / steps;
        const vec3 c0 = layer.kind == LayerKind::Signed ? diverging(2 * t0 - 1) : viridis(t0);
        const vec3 c1 = layer.kind == LayerKind::Signed ? diverging(2 * t1 - 1) : viridis(t1);
        dl->AddRectFilledMultiColor(ImVec2(origin.x + t0 * width, origin.y),
                                    ImVec2(origin.x + t1 * width + 0.5f, origin.y + h), to_u32(c0),
                                    to_u32(c1), to_u32(c1), to_u32(c0));
    }
    s.colorbar_rect = {origin.x, origin.y, origin.x + width, origin.y + h};
    for (double t : colorbar_ticks(r.lo, r.hi)) {
        // A one-pixel rectangle on a whole pixel: crisp, where an anti-aliased line would
        // smear over two columns at half intensity.
        const float x = std::floor(origin.x + float((t - r.lo) / (r.hi - r.lo)) * width);
        dl->AddRectFilled(ImVec2(x, origin.y + h), ImVec2(x + 1, origin.y + h + 5),
                          IM_COL32(230, 230, 230, 255));
        char label[32];
        std::snprintf(label, sizeof label, "%g", t);
        const float tw = ImGui::CalcTextSize(label).x;
        dl->AddText(
            ImVec2(std::clamp(x - tw / 2, origin.x, origin.x + width - tw), origin.y + h + 6),
            IM_COL32(230, 230, 230, 255), label);
    }
    ImGui::Dummy(ImVec2(width, h + 24));
}

// A sparse layer's samples as 2 x 2 screen-pixel points when its texels are smaller than
// that on screen (the nearest-texel image then skips most of them); one point per 2 x 2 cell
// of the screen, the first sample found there.
void draw_sparse_points(const Workbench::State& s, const Layer& layer, const LayerSet& L,
                        ImVec2 origin, ImVec2 size, ImVec2 uv0, ImVec2 uv1) {
    const float texel_px = size.x / (L.width() * (uv1.x - uv0.x));
    if (texel_px >= 2.0f) return;
    const int cells_x = int(size.x / 2) + 1, cells_y = int(size.y / 2) + 1;
    std::vector<char> taken(size_t(cells_x) * cells_y, 0);
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const int x0 = std::max(0, int(uv0.x * L.width())),
              x1 = std::min(L.width(), int(uv1.x * L.width()) + 1);
    const int y0 = std::max(0, int(uv0.y * L.height())),
              y1 = std::min(L.height(), int(uv1.y * L.height()) + 1);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const float v = layer.at(L.width(), x, y);
            if (v == 0.0f || !std::isfinite(v)) continue;
            const float px = origin.x + ((x + 0.5f) / L.width() - uv0.x) / (uv1.x - uv0.x) * size.x;
            const float py =
                origin.y + ((y + 0.5f) / L.height() - uv0.y) / (uv1.y - uv0.y) * size.y;
            const int cx = int((px - origin.x) / 2), cy = int((py - origin.y) / 2);
            if (cx < 0 || cy < 0 || cx >= cells_x || cy >= cells_y) continue;
            char& cell = taken[size_t(cy) * cells_x + size_t(cx)];
            if (cell) continue;
            cell = 1;
            const vec3 c = layer.kind == LayerKind::Categorical
                               ? category_colour(layer, int(std::lround(v)))
                               : viridis((v - s.shown_range.lo) /
                                         std::max(s.shown_range.hi - s.shown_range.lo, 1e-20f));
            dl->AddRectFilled(ImVec2(px - 1, py - 1), ImVec2(px + 1, py + 1), to_u32(c));
        }
}

}  // namespace

void draw_viewport(Workbench::State& s) {
    if (!s.error.empty()) {
        ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1, 0.4f, 0.4f, 1));
        ImGui::TextWrapped("error: %s", s.error.c_str());
        ImGui::PopStyleColor();
    }
    if (!s.options.hint.empty()) {
        ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(0.55f, 0.8f, 1.0f, 1.0f));
        ImGui::TextWrapped("%s", s.options.hint.c_str());
        ImGui::PopStyleColor();
    }
    s.image_rect = {};
    if (!s.shown) {
        ImGui::TextDisabled("rendering frame %d ...", s.frame);
        return;
    }
    const LayerSet& L = s.shown->layers;
    // Wide enough for the longest layer name ("cache_decisions" was cut at --ui-scale 2),
    // at most 40 % of the viewport.
    const float k = ImGui::GetFontSize() / 13.0f;
    float names = 0.0f;
    for (const Layer& l : L.layers())
        names = std::max(names, ImGui::CalcTextSize(l.name.c_str()).x);
    ImGui::SetNextItemWidth(
        std::min(names + ImGui::GetFrameHeight() + 2 * ImGui::GetStyle().FramePadding.x,
                 0.4f * ImGui::GetContentRegionAvail().x));
    if (ImGui::BeginCombo("layer", s.layer_name.c_str())) {
        auto item = [&](const std::string& name) {
            if (ImGui::Selectable(name.c_str(), name == s.layer_name)) {
                s.layer_name = name;
                s.view_dirty = true;
            }
        };
        for (const Layer& l : L.layers()) item(l.name);
        for (const std::string& name : s.shown->unread_layers) item(name);  // on their way
        ImGui::EndCombo();
    }
    const Layer* layer = L.find(s.layer_name);
    if (!layer && (s.shown->preview || s.shown->partial)) {
        // A first image has only its colour, a frame just read back only its layers on screen
        // until the rest is read: the choice stays.
        layer = &L.get("color");
    } else if (!layer) {
        s.layer_name = "color";
        layer = &L.get("color");
        s.view_dirty = true;
    }
    ImGui::SameLine();
    ImGui::TextDisabled("[%s] %s", to_string(layer->kind), layer->description.c_str());
    if (layer->kind != LayerKind::Color) {
        if (ImGui::Checkbox("over colour", &s.overlay_on_color)) s.view_dirty = true;
        ImGui::SameLine();
        ImGui::SetNextItemWidth(100 * k);
        ImGui::SliderFloat("opacity", &s.overlay_opacity, 0.0f, 1.0f);
        ImGui::SameLine();
        if (ImGui::Checkbox("fixed range", &s.fixed_range)) s.view_dirty = true;
        if (s.fixed_range) {
            ImGui::SameLine();
            ImGui::SetNextItemWidth(140 * k);
            if (ImGui::InputFloat2("range", &s.range.lo)) s.view_dirty = true;
        }
    }
    if (s.view_dirty) {
        DisplayParams params;
        params.exposure_ev = s.config.frame.exposure;
        params.auto_range = !s.fixed_range;
        params.range = s.range;
        s.shown_range = s.view.render(L, *layer, params);
        if (!s.fixed_range) s.range = s.shown_range;
        if (s.overlay_on_color && layer->kind != LayerKind::Color)
            s.base_view.render(L, L.get("color"), params);
        render_reference_view(s, params);
        s.view_dirty = false;
    }

    const ImVec2 avail = ImGui::GetContentRegionAvail();
    const float colorbar_h = (layer->kind == LayerKind::Color || layer->channels >= 3) ? 0 : 44;
    const float fit = std::min(avail.x / L.width(), (avail.y - colorbar_h) / L.height());
    const ImVec2 size(L.width() * fit, L.height() * fit);
    const float half = 0.5f / s.zoom;
    s.centre.x = std::clamp(s.centre.x, half, 1 - half);
    s.centre.y = std::clamp(s.centre.y, half, 1 - half);
    const ImVec2 uv0(s.centre.x - half, s.centre.y - half),
        uv1(s.centre.x + half, s.centre.y + half);
    const ImVec2 origin = ImGui::GetCursorScreenPos();
    if (s.overlay_on_color && layer->kind != LayerKind::Color) {
        ImGui::Image(reinterpret_cast<ImTextureID>(intptr_t(s.base_view.texture())), size, uv0,
                     uv1);
        ImGui::SetCursorScreenPos(origin);
        ImGui::Image(reinterpret_cast<ImTextureID>(intptr_t(s.view.texture())), size, uv0, uv1,
                     ImVec4(1, 1, 1, s.overlay_opacity));
    } else {
        ImGui::Image(reinterpret_cast<ImTextureID>(intptr_t(s.view.texture())), size, uv0, uv1);
    }
    s.image_rect = {origin.x, origin.y, origin.x + size.x, origin.y + size.y};
    const bool item_hovered = ImGui::IsItemHovered();
    if (layer->sparse) draw_sparse_points(s, *layer, L, origin, size, uv0, uv1);
    if (s.split && s.references.count(s.shown->frame)) {
        // Split view: the reference's colour right of the split, same zoom and pan.
        const float split_u = uv0.x + s.split_position * (uv1.x - uv0.x);
        const ImVec2 a(origin.x + s.split_position * size.x, origin.y);
        ImGui::GetWindowDrawList()->AddImage(
            reinterpret_cast<ImTextureID>(intptr_t(s.reference_view.texture())), a,
            ImVec2(origin.x + size.x, origin.y + size.y), ImVec2(split_u, uv0.y), uv1);
        ImGui::GetWindowDrawList()->AddLine(a, ImVec2(a.x, origin.y + size.y),
                                            IM_COL32(255, 255, 255, 255), 1.5f);
        const bool ab = comparing_runs(s);
        ImGui::GetWindowDrawList()->AddText(ImVec2(a.x + 6, origin.y + 4),
                                            IM_COL32(255, 255, 255, 255), ab ? "A" : "reference");
        if (ab)
            ImGui::GetWindowDrawList()->AddText(ImVec2(origin.x + 6, origin.y + 4),
                                                IM_COL32(255, 255, 255, 255), "B");
    }
    const ImGuiIO& io = ImGui::GetIO();
    auto mouse_uv = [&] {
        return ImVec2(uv0.x + (io.MousePos.x - origin.x) / size.x * (uv1.x - uv0.x),
                      uv0.y + (io.MousePos.y - origin.y) / size.y * (uv1.y - uv0.y));
    };
    if (item_hovered) {
        if (ImGui::IsMouseClicked(0)) {
            const ImVec2 uv = mouse_uv();
            s.pick_x = std::clamp(int(uv.x * L.width()), 0, L.width() - 1);
            s.pick_y = std::clamp(int(uv.y * L.height()), 0, L.height() - 1);
        }
        if (io.MouseWheel != 0) {
            const ImVec2 before = mouse_uv();
            s.zoom = std::clamp(s.zoom * std::pow(1.25f, io.MouseWheel), 1.0f, 64.0f);
            const float h2 = 0.5f / s.zoom;
            // Keep the texel under the cursor where it is.
            const float fx = (io.MousePos.x - origin.x) / size.x,
                        fy = (io.MousePos.y - origin.y) / size.y;
            s.centre = ImVec2(before.x - (fx - 0.5f) * 2 * h2, before.y - (fy - 0.5f) * 2 * h2);
        }
        if (ImGui::IsMouseDragging(1)) {
            const ImVec2 d = io.MouseDelta;
            s.centre.x -= d.x / size.x / s.zoom;
            s.centre.y -= d.y / size.y / s.zoom;
        }
    }
    if (s.pick_x >= 0) {  // mark the inspected pixel
        const float px =
            origin.x + ((s.pick_x + 0.5f) / L.width() - uv0.x) / (uv1.x - uv0.x) * size.x;
        const float py =
            origin.y + ((s.pick_y + 0.5f) / L.height() - uv0.y) / (uv1.y - uv0.y) * size.y;
        if (s.image_rect.contains(px, py))
            ImGui::GetWindowDrawList()->AddCircle(ImVec2(px, py), 6, IM_COL32(255, 60, 200, 255),
                                                  12, 2);
    }
    draw_colorbar(s, *layer, ImGui::GetCursorScreenPos(), std::min(size.x, 420.0f));
}

}  // namespace freqlab::ui
