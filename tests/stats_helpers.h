// Statistical helpers for Monte Carlo tests: Pearson's chi-square against expected counts.
#pragma once

#include <boost/math/distributions/chi_squared.hpp>
#include <vector>

namespace freqlab::test {

// p-value of observed counts against expected counts; bins with expected < 5 are pooled into
// one bin (the usual validity rule), so sparse tails neither dominate nor disappear.
inline double chi_square_p_value(const std::vector<double>& observed,
                                 const std::vector<double>& expected, double* chi2_out = nullptr) {
    double chi2 = 0, pooled_obs = 0, pooled_exp = 0;
    int bins = 0;
    for (size_t i = 0; i < observed.size(); ++i) {
        if (expected[i] < 5.0) {
            pooled_obs += observed[i];
            pooled_exp += expected[i];
            continue;
        }
        chi2 += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
        ++bins;
    }
    if (pooled_exp >= 5.0) {
        chi2 += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
        ++bins;
    } else if (pooled_obs > 10.0) {
        chi2 += 1e9;  // many samples where the pdf says almost none: certainly wrong
    }
    if (chi2_out) *chi2_out = chi2;
    const boost::math::chi_squared dist(std::max(1, bins - 1));
    return boost::math::cdf(boost::math::complement(dist, chi2));
}

}  // namespace freqlab::test
