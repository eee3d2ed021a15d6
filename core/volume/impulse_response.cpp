#include "volume/impulse_response.h"

#include <boost/math/quadrature/gauss.hpp>

#include <cmath>

namespace freqlab {

namespace {

constexpr double kPiD = 3.14159265358979323846;

double zh_basis(int l, double cos_theta, double* p /* scratch, >= l+1 */) {
    p[0] = 1.0;
    if (l >= 1) p[1] = cos_theta;
    for (int k = 2; k <= l; ++k)
        p[k] = ((2.0 * k - 1.0) * cos_theta * p[k - 1] - (k - 1.0) * p[k - 2]) / k;
    return std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD)) * p[l];
}

// Single-scattered radiance arriving from direction theta (from the axis to the emitter),
// multiplied by sin(theta) so that it stays finite where the ray passes through the emitter.
double single_radiance_times_sin(const HomogeneousMedium& m, double d, double theta) {
    using boost::math::quadrature::gauss;
    const double ct = std::cos(theta), st = std::sin(theta);
    const double t0 = d * ct, h = d * st;  // closest approach along the ray, and its distance
    if (h < 1e-300) return 0.0;
    // Equi-angular: t = t0 + h tan(phi), r = h / cos(phi), dt / r^2 = dphi / h.
    const double phi_a = std::atan2(-t0, h);
    const double st_over_h = 1.0 / d;  // sin(theta) / h
    const double sigma_t = m.sigma_t();
    const double inner = gauss<double, 48>::integrate(
        [&](double phi) {
            const double t = t0 + h * std::tan(phi), r = h / std::cos(phi);
            // Light travels from the emitter (at d z) to x_t = t w, then towards the receiver
            // (-w): cos = u . (-w) with u = (t w - d z) / r, so u . w = (t - d cos theta) / r.
            const double cos_scatter = -(t - t0) / r;
            return std::exp(-sigma_t * (t + r)) * m.sigma_s * hg_phase(m.g, cos_scatter);
        },
        phi_a, 0.5 * kPiD);
    return inner * st_over_h;
}

}  // namespace

ZhVector point_direct_zh(const HomogeneousMedium& m, double d) {
    ZhVector z{};
    const double weight = std::exp(-m.sigma_t() * d) / (d * d);
    for (int l = 0; l < kImpulseOrder; ++l)
        z[size_t(l)] = weight * std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD));
    return z;
}

ZhVector point_single_zh(const HomogeneousMedium& m, double d) {
    using boost::math::quadrature::gauss;
    ZhVector z{};
    // Panels graded towards theta = 0, where the response to a forward-peaked phase function
    // and to short distances concentrates.
    const int panels = 40;
    for (int i = 0; i < panels; ++i) {
        const double a = kPiD * std::pow(double(i) / panels, 2.0);
        const double b = kPiD * std::pow(double(i + 1) / panels, 2.0);
        double p[kImpulseOrder];
        const auto& x = gauss<double, 12>::abscissa();
        const auto& w = gauss<double, 12>::weights();
        for (size_t k = 0; k < x.size(); ++k)
            for (double sign : {-1.0, 1.0}) {
                if (x[k] == 0.0 && sign < 0) continue;
                const double theta = 0.5 * (a + b) + sign * 0.5 * (b - a) * x[k];
                const double f =
                    single_radiance_times_sin(m, d, theta) * 2.0 * kPiD * w[k] * 0.5 * (b - a);
                for (int l = 0; l < kImpulseOrder; ++l)
                    z[size_t(l)] += f * zh_basis(l, std::cos(theta), p);
            }
    }
    return z;
}

ZhVector directional_direct_zh(const HomogeneousMedium& m, double depth) {
    ZhVector z{};
    const double weight = std::exp(-m.sigma_t() * depth);
    for (int l = 0; l < kImpulseOrder; ++l)
        z[size_t(l)] = weight * std::sqrt((2.0 * l + 1.0) / (4.0 * kPiD));
    return z;
}

ZhVector directional_single_zh(const HomogeneousMedium& m, double s) {
    using boost::math::quadrature::gauss;
    const double sigma_t = m.sigma_t();
    auto radiance = [&](double mu) {
        const double k = sigma_t * (1.0 - mu);
        double path;  // int_0^t_max e^{-sigma_t t (1 - mu)} dt
        if (mu > 0) {
            const double t_max = s / mu;
            path = k * t_max < 1e-8 ? t_max : -std::expm1(-k * t_max) / k;
        } else {
            path = 1.0 / k;
        }
        return m.sigma_s * hg_phase(m.g, mu) * std::exp(-sigma_t * s) * path;
    };
    ZhVector z{};
    double p[kImpulseOrder];
    // Panels split at mu = 0 (where t_max becomes infinite) and graded towards mu = 1.
    const int panels = 24;
    for (int half = 0; half < 2; ++half)
        for (int i = 0; i < panels; ++i) {
            double a, b;
            if (half == 0)
                a = -1.0 + double(i) / panels, b = -1.0 + double(i + 1) / panels;
            else
                a = 1.0 - std::pow(1.0 - double(i) / panels, 2.0),
                b = 1.0 - std::pow(1.0 - double(i + 1) / panels, 2.0);
            const auto& x = gauss<double, 12>::abscissa();
            const auto& w = gauss<double, 12>::weights();
            for (size_t k = 0; k < x.size(); ++k)
                for (double sign : {-1.0, 1.0}) {
                    const double mu = 0.5 * (a + b) + sign * 0.5 * (b - a) * x[k];
                    const double f = 2.0 * kPiD * radiance(mu) * w[k] * 0.5 * (b - a);
                    for (int l = 0; l < kImpulseOrder; ++l) z[size_t(l)] += f * zh_basis(l, mu, p);
                }
        }
    return z;
}

ZhDistanceTable::ZhDistanceTable(Trend trend, const std::function<ZhVector(double)>& canonical)
    : trend_(trend), scaled_(kBins) {
    for (int i = 0; i < kBins; ++i) {
        const double D = kMinD * std::pow(kMaxD / kMinD, double(i) / (kBins - 1));
        const ZhVector z = canonical(D);
        for (int l = 0; l < kImpulseOrder; ++l)
            scaled_[size_t(i)][size_t(l)] = z[size_t(l)] / this->trend(D);
    }
}

double ZhDistanceTable::trend(double D) const {
    return trend_ == Trend::PointLike ? std::exp(-D) / D : std::exp(-D);
}

ZhVector ZhDistanceTable::at(double D) const {
    ZhVector z{};
    if (!(D > 0) || D >= kMaxD) return z;  // beyond kMaxD the response is below e^-40
    const double u = std::log(std::max(D, kMinD) / kMinD) / std::log(kMaxD / kMinD) * (kBins - 1);
    const int i = std::min(int(u), kBins - 2);
    const double f = u - i;
    // Catmull-Rom in log D: linear interpolation left 0.8 % errors on high-order coefficients
    // near their zero crossings (tests/test_impulse_response.cpp); the cubic is exact for
    // quadratics and costs four reads.
    const int i0 = std::max(i - 1, 0), i3 = std::min(i + 2, kBins - 1);
    const double f2 = f * f, f3 = f2 * f;
    const double w0 = -0.5 * f3 + f2 - 0.5 * f, w1 = 1.5 * f3 - 2.5 * f2 + 1.0,
                 w2 = -1.5 * f3 + 2.0 * f2 + 0.5 * f, w3 = 0.5 * f3 - 0.5 * f2;
    for (int l = 0; l < kImpulseOrder; ++l)
        z[size_t(l)] =
            (w0 * scaled_[size_t(i0)][size_t(l)] + w1 * scaled_[size_t(i)][size_t(l)] +
             w2 * scaled_[size_t(i) + 1][size_t(l)] + w3 * scaled_[size_t(i3)][size_t(l)]) *
            trend(D);
    return z;
}

SingleScatterTable::SingleScatterTable(Emitter emitter, double g)
    : emitter_(emitter),
      g_(g),
      table_(emitter == Emitter::Point ? ZhDistanceTable::Trend::PointLike
                                       : ZhDistanceTable::Trend::DirectionalLike,
             [emitter, g](double D) {
                 const HomogeneousMedium canonical{1.0, 0.0, g};
                 return emitter == Emitter::Point ? point_single_zh(canonical, D)
                                                  : directional_single_zh(canonical, D);
             }) {}

ZhVector SingleScatterTable::single(const HomogeneousMedium& m, double distance) const {
    // Optical-distance substitution (see the header): the factors were derived, then tested.
    ZhVector z = table_.at(m.sigma_t() * distance);
    const double factor =
        emitter_ == Emitter::Point ? m.sigma_s * m.sigma_t() : m.sigma_s / m.sigma_t();
    for (double& v : z) v *= factor;
    return z;
}

}  // namespace freqlab
