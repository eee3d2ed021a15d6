#include "volume/impulse_query.h"

#include <cmath>

#include "base/error.h"

namespace freqlab {

void validate(const ImpulseQuery& q, int table_bounces) {
    if (!(q.distance > 0) || !std::isfinite(q.distance))
        throw Error("--distance", std::to_string(q.distance), "expected a finite distance > 0");
    if (!(q.shift >= 0 && q.shift <= 1))
        throw Error("--shift", std::to_string(q.shift), "expected sin(angle) in [0, 1]");
    if (!(q.medium.sigma_s > 0) || !(q.medium.sigma_a >= 0) || !std::isfinite(q.medium.sigma_t()))
        throw Error("--sigma-s/--sigma-a", "", "expected sigma_s > 0 and sigma_a >= 0, finite");
    if (!(std::fabs(q.medium.g) <= kGRange))
        throw Error("--g", std::to_string(q.medium.g),
                    "expected |g| <= " + std::to_string(kGRange) + " (the tables' range)");
    if (q.last_bounce < 1 || q.last_bounce > table_bounces)
        throw Error("--bounces", std::to_string(q.last_bounce),
                    "expected all or 1 to " + std::to_string(table_bounces));
}

ImpulseResponse query_impulse(const ImpulseTables& t, const ImpulseQuery& q) {
    ImpulseResponse r;
    const HomogeneousMedium& m = q.medium;
    double d = q.distance;
    switch (q.emitter) {
        case EmitterKind::Point:
            r.direct = point_direct_zh(m, d);
            break;
        case EmitterKind::Directional:
            r.direct = directional_direct_zh(m, d);
            break;
        case EmitterKind::Area:
            r.direct = area_direct_zh(m, d, q.shift);
            break;
    }
    if (q.variant == TableVariant::Surface)
        d = std::max(d - kBackScatterShift / m.sigma_t(), ZhDistanceTable::kMinD / m.sigma_t());
    HomogeneousMedium similar = m;
    similar.sigma_s = m.sigma_s * (1.0 - m.g);
    similar.g = 0.0;
    const bool multiple = q.last_bounce >= 2;
    switch (q.emitter) {
        case EmitterKind::Point:
            r.single = t.point_single().single(m, d, q.collapsed);
            if (multiple)
                r.multiple =
                    t.point_multiple().bounces_in(similar, d, 2, q.last_bounce, q.collapsed);
            break;
        case EmitterKind::Directional:
            r.single = t.directional_single().single(m, d, q.collapsed);
            if (multiple)
                r.multiple = (q.receiver == Receiver::OnSurface ? t.directional_multiple_bottom()
                                                                : t.directional_multiple())
                                 .bounces_in(similar, d, 2, q.last_bounce);
            break;
        case EmitterKind::Area: {
            const TiltedZh s = t.area_single().single(m, d, q.shift);
            r.single = s.zh;
            r.axis_tilt = s.tilt;
            if (multiple) {
                r.multiple =
                    t.point_multiple().bounces_in(similar, d, 2, q.last_bounce, q.collapsed);
                for (double& v : r.multiple) v *= 0.25;
            }
            break;
        }
    }
    for (int l = 0; l < kImpulseOrder; ++l)
        r.total[size_t(l)] = r.direct[size_t(l)] + r.single[size_t(l)] + r.multiple[size_t(l)];
    return r;
}

const char* normalization_of(EmitterKind e) {
    switch (e) {
        case EmitterKind::Point:
            return "point emitter of intensity I0 = 1 W/sr; radiance ZH (W/m^2/sr x sr) about the "
                   "axis from the receiver to the emitter";
        case EmitterKind::Directional:
            return "irradiance E0 = 1 W/m^2 across the beam at the medium boundary; ZH about the "
                   "direction to the light";
        case EmitterKind::Area:
            return "differential area emitter of intensity I0 max(n . u, 0), I0 = 1 W/sr; direct "
                   "and multiple about the axis to the emitter, single about the axis tilted by "
                   "axis_tilt towards the emitter normal's tangential part";
    }
    return "";
}

}  // namespace freqlab
