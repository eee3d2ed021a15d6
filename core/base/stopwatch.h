// Wall-clock timing of stages for stats (never for results: time in results comes from the
// frame index, DESIGN.md "Determinism").
#pragma once

#include <chrono>

namespace freqlab {

using Clock = std::chrono::steady_clock;

inline double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

}  // namespace freqlab
