#include "volume/polar_quadrature.h"

#include <boost/math/quadrature/gauss.hpp>

#include <cmath>

namespace freqlab {

const std::vector<PolarNode>& graded_polar_nodes() {
    static const std::vector<PolarNode> nodes = [] {
        using boost::math::quadrature::gauss;
        constexpr double kPiD = 3.14159265358979323846;
        const int panels = 40;
        const auto& x = gauss<double, 12>::abscissa();
        const auto& w = gauss<double, 12>::weights();
        std::vector<PolarNode> out;
        for (int i = 0; i < panels; ++i) {
            const double a = kPiD * std::pow(double(i) / panels, 2.0);
            const double b = kPiD * std::pow(double(i + 1) / panels, 2.0);
            for (size_t k = 0; k < x.size(); ++k)
                for (double sign : {-1.0, 1.0})
                    out.push_back(
                        {0.5 * (a + b) + sign * 0.5 * (b - a) * x[k], w[k] * 0.5 * (b - a)});
        }
        return out;
    }();
    return nodes;
}

}  // namespace freqlab
