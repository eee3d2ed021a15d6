// The tables' model of a distant emitter's single scattering at a receiver, and directions
// drawn in proportion to it (issue "Method B, part 4"; the control variate of
// BakeEstimator::single_correction, seed Deuxième article §5.2: the tables' half-space
// response to a directional light).
//
// The model is a half-space of one homogeneous medium whose boundary, normal to the light
// direction l, lies D along l from the receiver. Along a direction w (mu = w . l) the light
// scattered once towards the receiver at distance t is
//   sigma_s f_HG(g, mu) e^(-sigma_t D) e^(-k t),  k = sigma_t (1 - mu),
// for t < D / mu (mu > 0; no bound for mu <= 0), and its integral over t, the radiance L(mu),
// is closed-form. The correction's Monte Carlo estimate is (real - model) along one drawn
// direction over that direction's density. Drawn by the cosine (density cos / pi), the model
// part alone ranged 0 .. 10x its mean on valley's terrain (one prepass sample per texel: the
// vertex correction field read -2.8 where it should read ~0, in gaps under houses); drawn in
// proportion to L(mu) cos, it is the same number for every direction, so where the real
// media are dark (gaps, occluded medium) the correction is exactly minus the model's value.
//
// The density: mu piecewise linear over kBins bins of the mu the hemisphere about n spans
// (bins uniform in sqrt(1 - mu), finest where a forward phase function peaks at mu = 1; the
// density L(mu) C(mu) at their edges, C the cosine's integral over the azimuth about l), the
// azimuth exactly by the cosine's density given mu; mixed with the cosine (kCosineFraction,
// one-sample MIS, balance heuristic) so that the weight cos / pdf stays below pi /
// kCosineFraction where the real media outshine the model.
//
// | parameter        | meaning                                                              |
// |------------------|----------------------------------------------------------------------|
// | kBins            | bins in sqrt(1 - mu) (32: the model part's spread < 12 %, g <= 0.85)|
// | kCosineFraction  | share of directions drawn by the cosine (0.1)                        |
#pragma once

#include <cmath>

#include "math/types.h"
#include "volume/receiver_directions.h"

namespace freqlab {

struct HalfSpaceSingleModel {
    double sigma_s = 0.0, sigma_t = 0.0, g = 0.0, depth = 0.0;
    bool empty() const { return !(sigma_s > 0.0); }
    // sigma_s f e^(-sigma_t D): the integrand at t = 0 along a direction of cosine mu to l.
    double base(double mu) const;
    // The integrand's integral over [a, b] along a direction of cosine mu (b may be infinite).
    double integral(double mu, double a, double b) const;
    // The integrand at t.
    double at(double mu, double t) const;
    // L(mu): the integral over all t.
    double radiance(double mu) const { return integral(mu, 0.0, INFINITY); }
};

class SingleScatterLobe final : public ReceiverDirections {
  public:
    static constexpr int kBins = 32;
    static constexpr double kCosineFraction = 0.1;

    // l: towards the emitter; n: the receiver's normal. Without a model (empty) or with the
    // emitter behind n's hemisphere's reach, directions are the cosine's alone.
    SingleScatterLobe(const HalfSpaceSingleModel& model, const vec3& l, const vec3& n);

    // A direction over n's hemisphere and its weight cos / pdf (pi for the cosine alone, the
    // direction sample_cosine_hemisphere(u1, u2) gives); u1 also picks the strategy. False
    // when the draw fell outside the hemisphere (weight 0: measure zero).
    bool sample(float u1, float u2, vec3* w, double* weight) const override;
    // The mixture's density of w (solid angle), 0 below the hemisphere.
    double pdf(const vec3& w) const;
    // Whether the model's lobe takes part (not the cosine alone).
    bool shaped() const { return shaped_; }

  private:
    double lobe_pdf(const vec3& w) const;
    // The cosine's integral over the azimuth about l at cosine mu to l.
    double azimuth_integral(double mu) const;
    vec3 l_, n_, e1_, e2_;  // e1: n's part across l, e2 = l x e1
    double c_n_ = 1.0, s_n_ = 0.0;
    // The largest mu of bin j (bins run from mu_hi down to mu_lo, uniform in sqrt(1 - mu)).
    double bin_top(int j) const;
    double bin_width(int j) const;
    double mu_lo_ = -1.0, mu_hi_ = 1.0, s_lo_ = 0.0, s_step_ = 0.0;
    double node_[kBins + 1] = {};  // the lobe's density in mu at the bins' edges (L C there)
    double cdf_[kBins + 1] = {};
    bool shaped_ = false;
};

}  // namespace freqlab
