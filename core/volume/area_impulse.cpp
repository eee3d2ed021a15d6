#include "volume/area_impulse.h"

#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/tools/minima.hpp>

#include <cmath>

#include "math/sh.h"
#include "volume/polar_quadrature.h"

namespace freqlab {

namespace {}  // namespace

ShVector area_single_sh(const HomogeneousMedium& m, double d, double alpha) {
    using boost::math::quadrature::gauss;
    const glm::dvec3 n(std::sin(alpha), 0.0, -std::cos(alpha));  // alpha = 0 faces the receiver
    const double sigma_t = m.sigma_t();
    ShVector out{};
    const auto& xr = gauss<double, 48>::abscissa();
    const auto& wr = gauss<double, 48>::weights();
    const int n_phi = 64;
    double y[kAreaShCount];
    for (const PolarNode& node : graded_polar_nodes()) {
        const double ct = std::cos(node.theta), st = std::sin(node.theta);
        const double t0 = d * ct, h = d * st;
        if (h < 1e-300) continue;
        const double phi_a = std::atan2(-t0, h);
        const double mid = 0.5 * (phi_a + 0.5 * kPiD), half = 0.5 * (0.5 * kPiD - phi_a);
        for (int k = 0; k < n_phi; ++k) {
            const double azimuth = 2.0 * kPiD * (k + 0.5) / n_phi;
            const glm::dvec3 w(st * std::cos(azimuth), st * std::sin(azimuth), ct);
            // Equi-angular along the ray: dt / r^2 = dphi / h; times sin(theta) = 1/d.
            double radiance_sin = 0.0;
            for (size_t e = 0; e < xr.size(); ++e)
                for (double s2 : {-1.0, 1.0}) {
                    const double phi = mid + s2 * half * xr[e];
                    const double t = t0 + h * std::tan(phi), r = h / std::cos(phi);
                    const glm::dvec3 u = (t * w - glm::dvec3(0, 0, d)) / r;  // emitter -> x_t
                    const double emission = std::max(glm::dot(n, u), 0.0);
                    if (emission <= 0) continue;
                    radiance_sin += wr[e] * half / d * std::exp(-sigma_t * (t + r)) * m.sigma_s *
                                    hg_phase(m.g, -glm::dot(u, w)) * emission;
                }
            sh_eval(kImpulseOrder, w, y);
            const double weight = node.weight * 2.0 * kPiD / n_phi;
            for (int i = 0; i < kAreaShCount; ++i) out[size_t(i)] += weight * radiance_sin * y[i];
        }
    }
    return out;
}

ZhVector zh_about_axis(const ShVector& sh, const glm::dvec3& axis, double* squared_error) {
    double y[kAreaShCount];
    sh_eval(kImpulseOrder, axis, y);
    ZhVector c{};
    double norm2 = 0.0, captured = 0.0;
    for (int l = 0; l < kImpulseOrder; ++l) {
        double dot = 0.0;
        for (int m = -l; m <= l; ++m) {
            const double f = sh[size_t(sh_index(l, m))];
            norm2 += f * f;
            dot += f * y[sh_index(l, m)];
        }
        c[size_t(l)] = std::sqrt(4.0 * kPiD / (2.0 * l + 1.0)) * dot;
        captured += c[size_t(l)] * c[size_t(l)];
    }
    if (squared_error) *squared_error = std::max(norm2 - captured, 0.0);
    return c;
}

ZhAxisFit fit_zh_axis(const ShVector& sh) {
    ZhAxisFit fit;
    fit.light_axis = glm::dvec3(0, 0, 1);
    const glm::dvec3 opt(sh[size_t(sh_index(1, 1))], sh[size_t(sh_index(1, -1))],
                         sh[size_t(sh_index(1, 0))]);
    fit.optimal_linear_axis = glm::length(opt) > 0 ? glm::normalize(opt) : fit.light_axis;
    zh_about_axis(sh, fit.light_axis, &fit.error_light);
    zh_about_axis(sh, fit.optimal_linear_axis, &fit.error_optimal_linear);
    // Axis on the great-circle arc from l (s = 0) to l_opt (s = 1).
    const double arc =
        std::acos(std::clamp(glm::dot(fit.light_axis, fit.optimal_linear_axis), -1.0, 1.0));
    auto axis_at = [&](double s) {
        if (arc < 1e-12) return fit.light_axis;
        return (std::sin((1 - s) * arc) * fit.light_axis +
                std::sin(s * arc) * fit.optimal_linear_axis) /
               std::sin(arc);
    };
    auto error_at = [&](double s) {
        double e;
        zh_about_axis(sh, axis_at(s), &e);
        return e;
    };
    const auto [s_best, e_best] = boost::math::tools::brent_find_minima(error_at, 0.0, 1.0, 40);
    // Brent brackets the interior; the endpoints are candidates too, so the fit is never worse.
    double s = s_best, e = e_best;
    if (fit.error_light <= e) s = 0.0, e = fit.error_light;
    if (fit.error_optimal_linear < e) s = 1.0, e = fit.error_optimal_linear;
    fit.fitted_axis = axis_at(s);
    fit.error_fitted = e;
    fit.fit_angle = s * arc;
    fit.zh = zh_about_axis(sh, fit.fitted_axis, nullptr);
    return fit;
}

}  // namespace freqlab
