// Area-emitter tables (issue "Method B, part 1"): the table's remaps (sigma_s, sigma_a, g) against
// direct computation at the medium, projected on the table's own axis; the direct term; the
// facing emitter's axis is the light axis.
#include <gtest/gtest.h>

#include <cmath>

#include "shared_tables.h"
#include "volume/area_impulse.h"
#include "volume/area_tables.h"

using namespace freqlab;

namespace {

glm::dvec3 tilted_axis(double tilt) {
    return {std::sin(tilt), 0.0, std::cos(tilt)};  // light axis z, emitter tangent +x
}

}  // namespace

TEST(AreaTables, RemapsMatchDirectComputationOnTheTablesAxis) {
    const AreaSingleScatterTable& table = test_support::shared_impulse_tables().area_single();
    int compared = 0;
    for (double sigma_s : {0.1, 0.3, 3.0, 10.0})
        for (double sigma_a : {0.0, 0.1, 1.0})
            // Every g panel (volume/impulse_response.h): -0.93, -0.75 and 0.75, 0.92 are the
            // outer ones.
            for (double g : {-0.93, -0.75, -0.3, 0.2, 0.5, 0.75, 0.92}) {
                // Shifts on bins (between bins the lobe is interpolated, not re-fitted).
                const int bin = (compared * 3) % kShiftBins;
                const double shift = shift_of_bin(bin), d = 0.7 / (sigma_s + sigma_a);
                const HomogeneousMedium m{sigma_s, sigma_a, g};
                const TiltedZh q = table.single(m, d, shift);
                const ShVector sh = area_single_sh(m, d, std::asin(shift));
                const ZhVector direct = zh_about_axis(sh, tilted_axis(q.tilt), nullptr);
                for (int l = 0; l < kImpulseOrder; ++l) {
                    if (std::fabs(direct[size_t(l)]) < 1e-3 * std::fabs(direct[0])) continue;
                    EXPECT_NEAR(q.zh[size_t(l)], direct[size_t(l)],
                                0.005 * std::fabs(direct[size_t(l)]))
                        << "sigma_s " << sigma_s << " sigma_a " << sigma_a << " g " << g
                        << " shift " << shift << " l " << l;
                }
                ++compared;
            }
    EXPECT_EQ(compared, 84);
}

TEST(AreaTables, DistancesBetweenBinsInterpolate) {
    const AreaSingleScatterTable& table = test_support::shared_impulse_tables().area_single();
    const HomogeneousMedium m{1.0, 0.0, 0.0};
    for (double d : {0.013, 0.21, 1.7, 6.3}) {
        const TiltedZh q = table.single(m, d, shift_of_bin(5));
        const ZhVector direct = zh_about_axis(area_single_sh(m, d, std::asin(shift_of_bin(5))),
                                              tilted_axis(q.tilt), nullptr);
        for (int l = 0; l < kImpulseOrder; ++l) {
            if (std::fabs(direct[size_t(l)]) < 1e-3 * std::fabs(direct[0])) continue;
            EXPECT_NEAR(q.zh[size_t(l)], direct[size_t(l)], 0.005 * std::fabs(direct[size_t(l)]))
                << "d " << d << " l " << l;
        }
    }
}

TEST(AreaTables, FacingEmitterKeepsTheLightAxisAndDirectTermIsCosineWeighted) {
    const AreaSingleScatterTable& table = test_support::shared_impulse_tables().area_single();
    const HomogeneousMedium m{0.5, 0.2, 0.1};
    EXPECT_NEAR(table.single(m, 1.0, 0.0).tilt, 0.0, 1e-6);
    EXPECT_GT(table.single(m, 1.0, 1.0).tilt, 0.05);  // skews towards the emitter's normal
    const ZhVector z = area_direct_zh(m, 2.0, 0.6);
    EXPECT_NEAR(z[0], 0.8 * std::exp(-1.4) / 4.0 * std::sqrt(1 / (4 * M_PI)), 1e-15);
    EXPECT_LT(table.worst_relative_error(), 2e-3);
}
