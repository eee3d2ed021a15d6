// One query of method B's tables (seed, Deuxième article §4.3-4.5, §5.1-5.2): emitter type,
// distance, shift, medium and bounce count in; the ZH components about the emitter's axis out.
// The CLI (`freqlab tables --query`), the workbench's Tables panel and the bakers all call this.
//
// | component | point (I0 = 1 W/sr)     | directional (E0 = 1 W/m^2) | area (I0 max(n.u, 0), I0 =
// 1) |
// |-----------|-------------------------|----------------------------|-------------------------------|
// | direct    | delta, e^-st d / d^2    | delta, e^-st s             | delta, cos(a) e^-st d / d^2
// | | single    | table x sigma_s sigma_t | table x sigma_s / sigma_t  | table x sigma_s sigma_t,
// about | |           |                         |                            | the tilted axis | |
// multiple  | bounces 2..K, c^k sigma_t^2 | bounces 2..K, c^k      | point's, x 1/4 (see below) |
// Multiple scattering is isotropic with anisotropy through similarity, sigma_s' = sigma_s (1-g).
// An area emitter's multiple scattering uses the point tables at the power-equivalent intensity
// I0 / 4 (a cosine emitter radiates pi I0, an isotropic one 4 pi I0): after two scattering
// events the emitter's directionality is assumed forgotten (an approximation, not tabulated).
//
// Variants: `infinite` is the pure infinite medium. `surface` is the seed's back-scatter
// compensation (§5.2): the scattered components are those of a receiver shifted by
// kBackScatterShift (optical units of the canonical medium) towards the emitter and gathered over
// the whole sphere, attributed to the unshifted distance; the direct term is unchanged. The 1D
// tables fix the receiver's normal along the axis to the emitter, so the shift is a lookup at
// distance - shift / sigma_t (clamped to the tables' first bin).
#pragma once

#include <string>

#include "base/enum_names.h"
#include "volume/impulse_tables.h"

namespace freqlab {

enum class EmitterKind { Point, Directional, Area };
enum class TableVariant { Infinite, Surface };
// Where the receiver sits. InMedium: a probe, the medium all around it (the tables above).
// OnSurface: a lightmap texel, the medium ending at its surface; directional multiple
// scattering then comes from the slab whose bottom face holds the receiver
// (slab_bottom_multiple_scatter.h). Point and area emitters keep the infinite medium.
enum class Receiver { InMedium, OnSurface };
constexpr double kBackScatterShift = 0.125;

struct ImpulseQuery {
    EmitterKind emitter = EmitterKind::Point;
    double distance = 1.0;  // to the emitter (point, area) or to the medium boundary (directional)
    double shift = 0.0;     // area: sin of the angle between the emitter normal and the receiver
    HomogeneousMedium medium{1.0, 0.0, 0.0};
    int last_bounce = 1;  // 1: single scattering only; K: bounces 2..K as `multiple`
    TableVariant variant = TableVariant::Infinite;
    Receiver receiver = Receiver::InMedium;
    // Bakers: g and the albedo quantised (2^-20, 2^-24; relative change < 1e-6) so that the
    // sums over phase terms and bounces collapse once per medium (collapse_memo.h).
    bool collapsed = false;
};

struct ImpulseResponse {
    ZhVector direct{}, single{}, multiple{}, total{};
    double axis_tilt = 0.0;  // area: the scattered lobe's axis, tilted from the light axis
};

// Throws Error naming the field (as a CLI flag) for values outside the tables' domain.
void validate(const ImpulseQuery& query, int table_bounces);
ImpulseResponse query_impulse(const ImpulseTables& tables, const ImpulseQuery& query);
const char* normalization_of(EmitterKind emitter);
inline constexpr EnumName<EmitterKind> kEmitterKindNames[] = {
    {EmitterKind::Point, "point"},
    {EmitterKind::Directional, "directional"},
    {EmitterKind::Area, "area"}};
inline constexpr EnumName<TableVariant> kTableVariantNames[] = {
    {TableVariant::Infinite, "infinite"}, {TableVariant::Surface, "surface"}};
inline constexpr EnumName<Receiver> kReceiverNames[] = {{Receiver::InMedium, "medium"},
                                                        {Receiver::OnSurface, "surface"}};
inline EmitterKind parse_emitter(const std::string& text) {
    return enum_from_name(kEmitterKindNames, text, "--emitter");
}
inline TableVariant parse_variant(const std::string& text) {
    return enum_from_name(kTableVariantNames, text, "--variant");
}
inline Receiver parse_receiver(const std::string& text) {
    return enum_from_name(kReceiverNames, text, "--receiver");
}
inline const char* to_string(EmitterKind emitter) {
    return enum_name(kEmitterKindNames, emitter);
}
inline const char* to_string(TableVariant variant) {
    return enum_name(kTableVariantNames, variant);
}
inline const char* to_string(Receiver receiver) {
    return enum_name(kReceiverNames, receiver);
}

}  // namespace freqlab
