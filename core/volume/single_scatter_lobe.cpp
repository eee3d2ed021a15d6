#include "volume/single_scatter_lobe.h"

#include <boost/math/tools/roots.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

#include "math/sampling.h"

namespace freqlab {

double HalfSpaceSingleModel::base(double mu) const {
    return sigma_s * hg_phase(g, mu) * std::exp(-sigma_t * depth);
}

double HalfSpaceSingleModel::integral(double mu, double a, double b) const {
    const double t_boundary = mu > 1e-9 ? depth / mu : INFINITY;
    b = std::min(b, t_boundary);
    const double b0 = base(mu);
    if (!(a < b) || b0 == 0.0) return 0.0;
    const double k = sigma_t * (1.0 - mu);
    const double ea = std::exp(-k * a);
    return b0 * (k > 1e-12 ? (ea - (std::isfinite(b) ? std::exp(-k * b) : 0.0)) / k : b - a);
}

double HalfSpaceSingleModel::at(double mu, double t) const {
    const double t_boundary = mu > 1e-9 ? depth / mu : INFINITY;
    return t < t_boundary ? base(mu) * std::exp(-sigma_t * (1.0 - mu) * t) : 0.0;
}

SingleScatterLobe::SingleScatterLobe(const HalfSpaceSingleModel& model, const vec3& l,
                                     const vec3& n)
    : l_(l), n_(n) {
    if (model.empty()) return;
    c_n_ = std::clamp(double(glm::dot(l, n)), -1.0, 1.0);
    s_n_ = std::sqrt(std::max(0.0, 1.0 - c_n_ * c_n_));
    const vec3 across = n - l * float(c_n_);
    const float across_length = glm::length(across);
    if (across_length > 1e-6f) {
        e1_ = across / across_length;
        e2_ = glm::cross(l, e1_);
    } else {
        const Frame frame(l);
        e1_ = frame.t;
        e2_ = frame.b;
    }
    // The cosines to l that n's hemisphere reaches: angles to l within 90 degrees of n's.
    const double theta = std::acos(c_n_);
    mu_hi_ = std::cos(std::max(0.0, theta - 0.5 * kPiD));
    mu_lo_ = std::cos(std::min(kPiD, theta + 0.5 * kPiD));
    // Bins uniform in s = sqrt(1 - mu): finest about mu = 1, where a forward-scattering
    // phase function peaks (HG g = 0.85: width ~0.01 in mu), coarser backwards, where the
    // model is smooth.
    s_lo_ = std::sqrt(std::max(0.0, 1.0 - mu_hi_));
    s_step_ = (std::sqrt(std::max(0.0, 1.0 - mu_lo_)) - s_lo_) / kBins;
    if (!(s_step_ > 0.0)) return;
    for (int j = 0; j <= kBins; ++j) {
        const double mu = bin_top(j);
        node_[j] = model.radiance(mu) * azimuth_integral(mu);
        if (!std::isfinite(node_[j]) || node_[j] < 0.0) return;
    }
    double sum = 0.0;
    for (int j = 0; j < kBins; ++j) sum += 0.5 * (node_[j] + node_[j + 1]) * bin_width(j);
    if (!(sum > 0.0) || !std::isfinite(sum)) return;
    for (double& v : node_) v /= sum;  // the density in mu at the bins' edges
    cdf_[0] = 0.0;
    for (int j = 0; j < kBins; ++j)
        cdf_[j + 1] = cdf_[j] + 0.5 * (node_[j] + node_[j + 1]) * bin_width(j);
    cdf_[kBins] = 1.0;
    shaped_ = true;
}

double SingleScatterLobe::azimuth_integral(double mu) const {
    // max(0, a + b cos phi) over phi in [-pi, pi].
    const double a = mu * c_n_, b = std::sqrt(std::max(0.0, 1.0 - mu * mu)) * s_n_;
    if (b <= std::abs(a)) return a > 0.0 ? 2.0 * kPiD * a : 0.0;
    const double phi0 = std::acos(-a / b);
    return 2.0 * (a * phi0 + b * std::sin(phi0));
}

double SingleScatterLobe::bin_top(int j) const {
    const double s = s_lo_ + j * s_step_;
    return j == 0 ? mu_hi_ : j == kBins ? mu_lo_ : 1.0 - s * s;
}

double SingleScatterLobe::bin_width(int j) const {
    return bin_top(j) - bin_top(j + 1);
}

double SingleScatterLobe::lobe_pdf(const vec3& w) const {
    const double mu = glm::dot(w, l_), cos_n = glm::dot(w, n_);
    if (!(cos_n > 0.0) || mu < mu_lo_ || mu > mu_hi_) return 0.0;
    const int j =
        std::clamp(int((std::sqrt(std::max(0.0, 1.0 - mu)) - s_lo_) / s_step_), 0, kBins - 1);
    const double c = azimuth_integral(mu);
    if (!(c > 0.0)) return 0.0;
    const double x = std::clamp((bin_top(j) - mu) / bin_width(j), 0.0, 1.0);
    return ((1.0 - x) * node_[j] + x * node_[j + 1]) * cos_n / c;
}

double SingleScatterLobe::pdf(const vec3& w) const {
    const double cos_n = glm::dot(w, n_);
    if (!(cos_n > 0.0)) return 0.0;
    if (!shaped_) return cos_n * kInvPi;
    return kCosineFraction * cos_n * kInvPi + (1.0 - kCosineFraction) * lobe_pdf(w);
}

bool SingleScatterLobe::sample(float u1, float u2, vec3* w, double* weight) const {
    if (!shaped_ || u1 < float(kCosineFraction)) {
        // The cosine (u1 rescaled when it shares u1 with the lobe).
        const float u = shaped_ ? u1 / float(kCosineFraction) : u1;
        const vec3 local = sample_cosine_hemisphere(std::min(u, 0.99999994f), u2);
        if (local.z <= 1e-6f) return false;
        *w = Frame(n_).to_world(local);
        if (!shaped_) {
            *weight = kPiD;
            return true;
        }
    } else {
        const double u = (double(u1) - kCosineFraction) / (1.0 - kCosineFraction);
        const int j = int(std::upper_bound(cdf_ + 1, cdf_ + kBins, u) - (cdf_ + 1));
        const double v = cdf_[j + 1] > cdf_[j]
                             ? std::clamp((u - cdf_[j]) / (cdf_[j + 1] - cdf_[j]), 0.0, 1.0)
                             : 0.5;
        // The density is linear across the bin, a at its top, b at its bottom: invert
        // a x + (b - a) x^2 / 2 = v (a + b) / 2.
        const double a0 = node_[j], b0 = node_[j + 1];
        const double x =
            std::abs(a0 - b0) < 1e-6 * (a0 + b0)
                ? v
                : std::clamp((a0 - std::sqrt(std::max(0.0, a0 * a0 + (b0 * b0 - a0 * a0) * v))) /
                                 (a0 - b0),
                             0.0, 1.0);
        const double mu = bin_top(j) - x * bin_width(j);
        // The azimuth about l by the cosine's density a + b cos(phi) over where it is
        // positive, |phi| < phi_max: invert a phi + b sin(phi) (increasing there).
        const double a = mu * c_n_, b = std::sqrt(std::max(0.0, 1.0 - mu * mu)) * s_n_;
        if (b <= -a) return false;
        const double phi_max = b <= a ? kPiD : std::acos(-a / b);
        const bool negative = u2 >= 0.5f;
        const double target = (negative ? 2.0 * double(u2) - 1.0 : 2.0 * double(u2)) *
                              (a * phi_max + b * std::sin(phi_max));
        const auto f = [&](double phi) {
            return std::make_pair(a * phi + b * std::sin(phi) - target, a + b * std::cos(phi));
        };
        double phi = boost::math::tools::newton_raphson_iterate(f, 0.5 * phi_max, 0.0, phi_max, 40);
        if (negative) phi = -phi;
        const double s = std::sqrt(std::max(0.0, 1.0 - mu * mu));
        *w = glm::normalize(l_ * float(mu) +
                            (e1_ * float(std::cos(phi)) + e2_ * float(std::sin(phi))) * float(s));
    }
    const double cos_n = glm::dot(*w, n_);
    const double density = pdf(*w);
    if (!(cos_n > 1e-6) || !(density > 0.0)) return false;
    *weight = cos_n / density;
    return std::isfinite(*weight);
}

}  // namespace freqlab
