#include "tables_panel.h"

#include <imgui.h>

#include <cmath>
#include <cstdio>
#include <mutex>

#include "base/job.h"
#include "image/colormap.h"
#include "math/sh.h"
#include "volume/impulse_query.h"
#include "volume/impulse_tables.h"

namespace freqlab::ui {

std::unique_ptr<TablesPanelState> make_tables_panel() {
    return std::make_unique<TablesPanelState>();
}

namespace {

constexpr int kTableBounces = 30;

// In-scattered light only: the direct term is a delta towards the emitter (closed form). For
// area emitters the single-scattered lobe's axis is tilted; the plots show it about its own axis.
ZhVector response(const TablesPanelState& s, double d, double* tilt = nullptr) {
    ImpulseQuery q;
    q.emitter = EmitterKind(s.emitter);
    q.distance = d;
    q.shift = s.shift;
    q.medium = HomogeneousMedium{s.sigma_s, s.sigma_a, s.g};
    q.last_bounce = s.bounces;
    q.variant = s.surface_variant ? TableVariant::Surface : TableVariant::Infinite;
    const ImpulseResponse r = query_impulse(*s.tables, q);
    if (tilt) *tilt = r.axis_tilt;
    ZhVector z{};
    for (int l = 0; l < kImpulseOrder; ++l)
        z[size_t(l)] = r.single[size_t(l)] + r.multiple[size_t(l)];
    return z;
}

ImU32 colour(int l) {
    const vec3 c = viridis(float(l) / (kImpulseOrder - 1));
    return ImGui::ColorConvertFloat4ToU32(ImVec4(c.r, c.g, c.b, 1.0f));
}

// A 3D glyph of the ZH lobe r(w) = |f(w . axis)|: 16 meridians and 9 parallels of the surface,
// orthographic view from `yaw` degrees about the vertical and 25 degrees above; positive lobes
// amber, negative ones blue. The emitter lies along +x (tilted by `tilt` for area emitters).
void draw_lobe_glyph(ImDrawList* dl, const ZhVector& z, double tilt, float size, float yaw) {
    const ImVec2 o = ImGui::GetCursorScreenPos();
    const ImVec2 c(o.x + size / 2, o.y + size / 2);
    dl->AddRectFilled(o, ImVec2(o.x + size, o.y + size), IM_COL32(30, 30, 34, 255));
    constexpr int kTheta = 64;
    double value[kTheta + 1], peak = 0.0;
    for (int i = 0; i <= kTheta; ++i) {
        value[i] = zh_eval(kImpulseOrder, z.data(), std::cos(M_PI * i / kTheta));
        peak = std::max(peak, std::fabs(value[i]));
    }
    if (!(peak > 0)) return;
    const glm::dvec3 axis(std::cos(tilt), std::sin(tilt), 0.0);
    const glm::dvec3 u(-std::sin(tilt), std::cos(tilt), 0.0), v(0.0, 0.0, 1.0);
    const double ya = yaw * M_PI / 180.0, pitch = 25.0 * M_PI / 180.0;
    auto project = [&](int i, double phi) {
        const double th = M_PI * i / kTheta, r = std::fabs(value[i]) / peak;
        const glm::dvec3 p =
            r * (std::cos(th) * axis + std::sin(th) * (std::cos(phi) * u + std::sin(phi) * v));
        // Yaw about the vertical (y), then pitch: screen x right, y up.
        const double x1 = std::cos(ya) * p.x + std::sin(ya) * p.z,
                     z1 = -std::sin(ya) * p.x + std::cos(ya) * p.z;
        const double y2 = std::cos(pitch) * p.y - std::sin(pitch) * z1;
        return ImVec2(c.x + float(0.45 * size * x1), c.y - float(0.45 * size * y2));
    };
    auto colour_at = [&](int i) {
        return value[i] >= 0 ? IM_COL32(250, 200, 60, 220) : IM_COL32(90, 150, 250, 220);
    };
    for (int m = 0; m < 16; ++m) {
        const double phi = 2.0 * M_PI * m / 16;
        for (int i = 0; i < kTheta; ++i)
            dl->AddLine(project(i, phi), project(i + 1, phi), colour_at(i), 1.0f);
    }
    for (int k = 1; k < 10; ++k) {
        const int i = k * kTheta / 10;
        for (int m = 0; m < 48; ++m)
            dl->AddLine(project(i, 2.0 * M_PI * m / 48), project(i, 2.0 * M_PI * (m + 1) / 48),
                        colour_at(i), 1.0f);
    }
    dl->AddText(ImVec2(o.x + 4, o.y + 2), IM_COL32(200, 200, 200, 255), "3D lobe (emitter +x)");
    ImGui::Dummy(ImVec2(size, size + 4));
}

}  // namespace

void draw_tables_panel(TablesPanelState& s) {
    if (!ImGui::CollapsingHeader("Method B tables", s.open ? ImGuiTreeNodeFlags_DefaultOpen : 0))
        return;
    if (!s.tables && !s.job) {
        TablesPanelState* sp = &s;
        s.job = std::make_unique<Job>([sp](Progress&) {
            std::string path;
            auto t = std::make_shared<ImpulseTables>(ImpulseTables::cached(kTableBounces, &path));
            std::lock_guard<std::mutex> lock(sp->mutex);
            sp->tables = t;
            sp->path = path;
        });
    }
    {
        std::lock_guard<std::mutex> lock(s.mutex);
        if (!s.tables) {
            ImGui::TextDisabled("loading or building the tables (a few seconds, once)...");
            return;
        }
    }
    ImGui::Combo("emitter", &s.emitter, "point\0directional\0area\0");
    if (s.emitter == 2) ImGui::SliderFloat("shift sin(a)", &s.shift, 0.0f, 1.0f, "%.2f");
    ImGui::Checkbox("surface variant (back-scatter shift)", &s.surface_variant);
    ImGui::SliderFloat("sigma_s", &s.sigma_s, 0.01f, 10.0f, "%.3g", ImGuiSliderFlags_Logarithmic);
    ImGui::SliderFloat("sigma_a", &s.sigma_a, 0.0f, 5.0f, "%.3g");
    ImGui::SliderFloat("g", &s.g, -float(kGRange), float(kGRange), "%.2f");
    ImGui::SliderInt("bounces", &s.bounces, 1, kTableBounces);
    ImGui::SliderFloat("lobe at d", &s.lobe_distance, 0.01f, 10.0f, "%.3g",
                       ImGuiSliderFlags_Logarithmic);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("tables: %s", s.path.c_str());

    // Legendre moments <P_l> = z_l / (z_0 sqrt(2l+1)) of the in-scattered light against log
    // distance: 1 is a delta towards the emitter, 0 isotropic; they fall as light diffuses.
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const float k = ImGui::GetFontSize() / 13.0f;  // --ui-scale
    const float w = ImGui::GetContentRegionAvail().x, h = 110 * k;
    ImVec2 o = ImGui::GetCursorScreenPos();
    dl->AddRectFilled(o, ImVec2(o.x + w, o.y + h), IM_COL32(30, 30, 34, 255));
    dl->AddLine(ImVec2(o.x, o.y + h / 2), ImVec2(o.x + w, o.y + h / 2), IM_COL32(80, 80, 80, 255));
    const int n = 96;
    for (int l = 1; l < kImpulseOrder; ++l) {
        ImVec2 prev;
        for (int i = 0; i < n; ++i) {
            const double d = 0.01 * std::pow(1000.0, double(i) / (n - 1));
            const ZhVector z = response(s, d);
            const double moment =
                z[0] != 0 ? z[size_t(l)] / (z[0] * std::sqrt(2.0 * l + 1.0)) : 0.0;
            const ImVec2 p(o.x + w * i / (n - 1),
                           o.y + h * float(0.5 - 0.45 * std::clamp(moment, -1.0, 1.0)));
            if (i) dl->AddLine(prev, p, colour(l), 1.2f);
            prev = p;
        }
    }
    dl->AddText(ImVec2(o.x + 4, o.y + 2), IM_COL32(200, 200, 200, 255),
                "<P_l> of in-scattered light, l = 1..10, d = 0.01..10");
    ImGui::Dummy(ImVec2(w, h + 4));

    // Polar cross-section of the in-scattered response at one distance; emitter to the right.
    double tilt = 0.0;
    const ZhVector z = response(s, s.lobe_distance, &tilt);
    const float size = std::min(w, 160.0f * k);
    o = ImGui::GetCursorScreenPos();
    const ImVec2 c(o.x + size / 2, o.y + size / 2);
    dl->AddRectFilled(o, ImVec2(o.x + size, o.y + size), IM_COL32(30, 30, 34, 255));
    double peak = 0;
    std::vector<double> r(181);
    for (int i = 0; i <= 180; ++i) {
        r[size_t(i)] = std::fabs(zh_eval(kImpulseOrder, z.data(), std::cos(M_PI * i / 180.0)));
        peak = std::max(peak, r[size_t(i)]);
    }
    ImVec2 prev;
    for (int i = -180; i <= 180; ++i) {
        const double theta = M_PI * i / 180.0, rr = peak > 0 ? r[size_t(std::abs(i))] / peak : 0.0;
        // Area lobes are drawn about their tilted axis (the emitter's normal leans upwards).
        const ImVec2 p(c.x + float(0.45 * size * rr * std::cos(theta + tilt)),
                       c.y - float(0.45 * size * rr * std::sin(theta + tilt)));
        if (i > -180) dl->AddLine(prev, p, IM_COL32(250, 200, 60, 255), 1.5f);
        prev = p;
    }
    dl->AddLine(c, ImVec2(o.x + size - 4, c.y), IM_COL32(120, 120, 120, 255));
    char label[64];
    if (s.emitter == 2)
        std::snprintf(label, sizeof label, "lobe, d = %.3g (DC %.3g), axis tilt %.1f deg",
                      s.lobe_distance, z[0], tilt * 180.0 / M_PI);
    else
        std::snprintf(label, sizeof label, "in-scattered lobe, d = %.3g (DC %.3g)", s.lobe_distance,
                      z[0]);
    dl->AddText(ImVec2(o.x + 4, o.y + 2), IM_COL32(200, 200, 200, 255), label);
    ImGui::Dummy(ImVec2(size, size + 4));
    draw_lobe_glyph(dl, z, tilt, size, s.glyph_yaw);
    ImGui::SliderFloat("glyph yaw", &s.glyph_yaw, -180.0f, 180.0f, "%.0f deg");
}

}  // namespace freqlab::ui
