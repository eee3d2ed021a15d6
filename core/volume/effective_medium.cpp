#include "volume/effective_medium.h"

namespace freqlab {

HomogeneousMedium effective_medium(const std::vector<MediumPiece>& pieces) {
    double length = 0, tau_s = 0, tau_a = 0, g_weighted = 0;
    for (const MediumPiece& p : pieces) {
        if (!(p.length > 0)) continue;
        length += p.length;
        tau_s += p.medium.sigma_s * p.length;
        tau_a += p.medium.sigma_a * p.length;
        g_weighted += p.medium.g * p.medium.sigma_s * p.length;
    }
    HomogeneousMedium m{0.0, 0.0, 0.0};
    if (length <= 0) return m;
    m.sigma_s = tau_s / length;
    m.sigma_a = tau_a / length;
    m.g = tau_s > 0 ? g_weighted / tau_s : 0.0;
    return m;
}

}  // namespace freqlab
