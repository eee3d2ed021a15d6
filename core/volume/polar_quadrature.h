// The polar-angle quadrature shared by method B's tabulators: panels over [0, pi] graded as
// theta = pi (i/panels)^2 (responses concentrate towards the emitter, theta = 0), 12-point
// Gauss-Legendre in each. The fine rule (40 panels, 480 nodes) tabulates; the coarse rule (20
// panels) runs beside it so that |fine - coarse| is recorded as each entry's error estimate
// (a conservative one: it is the coarse rule's error, the fine one's is smaller).
#pragma once

#include <utility>
#include <vector>

namespace freqlab {

struct PolarNode {
    double theta;
    double weight;  // for integrals d theta (no sin theta)
};

enum class PolarRule { Fine, Coarse };
const std::vector<PolarNode>& graded_polar_nodes(PolarRule rule = PolarRule::Fine);

// Nodes in mu = cos(theta) over [-1, 1] for directional emitters at optical depth `depth`
// (weights for integrals d mu): split at mu = 0, where the path to the boundary, depth / mu,
// jumps to infinity; panels graded towards mu = -1 below and towards mu = 1 above (HG's backward
// and forward peaks), plus geometric
// panels at depth / 16, depth / 4, ... where the radiance rises over a range of mu ~ depth.
struct MuNode {
    double mu;
    double weight;
};
std::vector<MuNode> directional_mu_nodes(double depth, int panels_per_half);

}  // namespace freqlab
