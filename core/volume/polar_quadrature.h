// The polar-angle quadrature shared by method B's tabulators: 40 panels over [0, pi] graded as
// theta = pi (i/40)^2 (responses concentrate towards the emitter, theta = 0), 12-point
// Gauss-Legendre in each: 480 (theta, weight) nodes, computed once.
#pragma once

#include <utility>
#include <vector>

namespace freqlab {

struct PolarNode {
    double theta;
    double weight;  // for integrals d theta (no sin theta)
};

const std::vector<PolarNode>& graded_polar_nodes();

}  // namespace freqlab
