// Tables for differential-area emitters (seed, Deuxième article §4.2 Eq. 4.3, Fig. 23, §5.1):
// the single-scattered response, tabulated over optical distance (256 bins) and 8 shift bins,
// each entry a ZH lobe about its Brent-fitted axis (volume/area_impulse.h) and the fitted
// axis's tilt from the light axis.
//
// | parameter | value                                                                          |
// |-----------|--------------------------------------------------------------------------------|
// | shift     | sin(alpha), alpha the angle between the emitter's normal and the direction from |
// |           | the emitter to the receiver; 8 bins at shift = j / 7 (alpha in [0, 90] degrees), |
// |           | linear interpolation between them (the seed's "shift distance" d = sin theta)  |
// | axis      | cos(tilt) l + sin(tilt) t, l towards the emitter, t the unit tangential part of  |
// |           | the emitter's normal (n - (n . l) l); tilt is fitted at g = 0                   |
// | g         | the kGNodeCount panel nodes of volume/impulse_response.h, projected on that axis|
// | quadrature| graded polar rule x 32 azimuths over half the circle (the response is mirror-  |
// |           | symmetric about the plane of l and n) x 96 equi-angular points per ray          |
// | remap     | as for point emitters: sigma_s sigma_t x canonical at D = sigma_t d (tested)     |
// | emitter   | radiant intensity I0 max(n . u, 0), I0 = 1: the direct term is I0 cos(alpha)    |
// |           | e^{-sigma_t d} / d^2 on the light axis                                          |
#pragma once

#include <vector>

#include "volume/impulse_response.h"

namespace freqlab {

constexpr int kShiftBins = 8;
inline double shift_of_bin(int j) {
    return double(j) / (kShiftBins - 1);
}

struct TiltedZh {
    ZhVector zh{};
    double tilt = 0.0;  // radians, from the light axis towards the emitter normal's tangent
};

// One distance of the table: per shift bin, the responses at the g nodes about the fitted axis.
struct AreaTableRow {
    std::array<GNodeResponses, kShiftBins> zh;
    std::array<double, kShiftBins> tilt{};
    std::array<double, kShiftBins> error{};  // |fine - coarse|, max over g nodes and orders
};
AreaTableRow area_single_row(double optical_distance);

class AreaSingleScatterTable {
  public:
    AreaSingleScatterTable();  // tabulates (~10 s on 2 cores)
    explicit AreaSingleScatterTable(std::vector<AreaTableRow> rows);
    const std::vector<AreaTableRow>& rows() const { return rows_; }
    // Single scattering at `distance` from the emitter with shift sin(alpha) in [0, 1].
    TiltedZh single(const HomogeneousMedium& medium, double distance, double shift) const;
    double worst_relative_error() const;

  private:
    std::vector<AreaTableRow> rows_;  // kBins, canonical values
    // [bin][shift][node][l] scaled by 1 / (e^-D / D); float: the stored values are floats or
    // halves already, and half the bytes per query
    std::vector<float> packed_;
    std::vector<double> tilt_;  // [bin][shift]
    void pack();
};

// The direct term of an area emitter (a delta on the light axis).
ZhVector area_direct_zh(const HomogeneousMedium& medium, double distance, double shift);

}  // namespace freqlab
