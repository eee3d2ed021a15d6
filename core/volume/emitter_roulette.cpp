#include "volume/emitter_roulette.h"

#include <algorithm>
#include <cmath>

namespace freqlab {

void emitter_keep_probabilities(const std::vector<float>& strength, float budget,
                                std::vector<float>& keep) {
    keep.assign(strength.size(), 1.0f);
    if (!(budget > 0.0f) || strength.size() < 2) return;
    double sum = 0.0;
    for (float s : strength)
        if (s > 0.0f && std::isfinite(s)) sum += s;
    if (!(sum > 0.0) || !std::isfinite(sum)) return;
    for (size_t i = 0; i < strength.size(); ++i) {
        const float s = strength[i] > 0.0f && std::isfinite(strength[i]) ? strength[i] : 0.0f;
        keep[i] = std::min(1.0f, std::max(kEmitterKeepFloor, float(budget * s / sum)));
    }
}

}  // namespace freqlab
