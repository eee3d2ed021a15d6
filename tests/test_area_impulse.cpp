// Differential-area emitters (issue "Method B, part 1", acceptance 5): the Brent-fitted ZH axis
// gives a lower L2 error than both candidate axes (the direction to the light and the optimal
// linear direction) in every angle bin; a facing emitter is symmetric about the light axis.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "math/sh.h"
#include "volume/area_impulse.h"

using namespace freqlab;

TEST(AreaImpulse, FacingEmitterIsSymmetricAboutTheLightAxis) {
    const ShVector sh = area_single_sh(HomogeneousMedium{1.0, 0.0, 0.0}, 1.0, 0.0);
    const ZhAxisFit fit = fit_zh_axis(sh);
    double norm2 = 0;
    for (double v : sh) norm2 += v * v;
    EXPECT_LT(fit.error_light, 1e-8 * norm2);
    EXPECT_NEAR(glm::dot(fit.optimal_linear_axis, glm::dvec3(0, 0, 1)), 1.0, 1e-6);
}

TEST(AreaImpulse, FittedAxisBeatsBothCandidatesInEveryBin) {
    const HomogeneousMedium m{1.0, 0.0, 0.0};
    std::printf("alpha(deg)  err(l)/|f|^2  err(l_opt)/|f|^2  err(fit)/|f|^2  fit angle(deg)\n");
    for (int bin = 0; bin < 8; ++bin) {
        const double alpha = (bin + 0.5) / 8.0 * 0.5 * M_PI;  // 8 bins over [0, 90) degrees
        const ShVector sh = area_single_sh(m, 1.0, alpha);
        double norm2 = 0;
        for (double v : sh) norm2 += v * v;
        const ZhAxisFit fit = fit_zh_axis(sh);
        std::printf("%9.1f  %13.3e  %16.3e  %14.3e  %14.2f\n", alpha * 180 / M_PI,
                    fit.error_light / norm2, fit.error_optimal_linear / norm2,
                    fit.error_fitted / norm2, fit.fit_angle * 180 / M_PI);
        EXPECT_LE(fit.error_fitted, fit.error_light);
        EXPECT_LE(fit.error_fitted, fit.error_optimal_linear);
        // Strictly better than both once the lobe is visibly skewed.
        if (bin >= 2) {
            EXPECT_LT(fit.error_fitted, 0.999 * fit.error_light);
            EXPECT_LT(fit.error_fitted, 0.999 * fit.error_optimal_linear);
        }
    }
}
