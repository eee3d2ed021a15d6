// All of method B's impulse-response tables in one versioned file: tabulated once (canonical
// medium), cached on disk, verified on load (parameters and an FNV-1a checksum of the payload).
//
// | part                         | size (floats)                                          |
// |------------------------------|--------------------------------------------------------|
// | point single scattering      | kSingleColumns x kBins x kImpulseOrder + kBins errors  |
// | directional single scatter.  | the same                                               |
// | area single scattering       | kBins x kShiftBins x (tilt, error estimate) and, as     |
// |                              | half floats, kBins x kShiftBins x kGNodeCount x order  |
// | point multiple scattering    | bounces x kBins x kImpulseOrder + (bounces+1) x kBins  |
// | directional multiple scatter.| bounces x kBins x kImpulseOrder                        |
// | the same, receiver on the    | bounces x kBins x kImpulseOrder                        |
// | bottom face of a slab        |                                                        |
// Stored as float32 (the tables' own error is ~1e-4; float rounding is 6e-8) except the area
// responses (half floats, see impulse_tables.cpp): 2.2 MB at 30 bounces.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "base/job.h"
#include "volume/area_tables.h"
#include "volume/impulse_response.h"
#include "volume/multiple_scatter.h"
#include "volume/slab_bottom_multiple_scatter.h"
#include "volume/slab_multiple_scatter.h"

namespace freqlab {

class ImpulseTables {
  public:
    static constexpr int kFormatVersion = 4;

    static ImpulseTables build(int bounces, Progress* progress = nullptr);
    void save(const std::filesystem::path& path) const;            // atomic
    static ImpulseTables load(const std::filesystem::path& path);  // throws Error naming the field
    // The cached file for `bounces` (built and saved when absent or invalid).
    static ImpulseTables cached(int bounces, std::string* path_used = nullptr);
    static std::filesystem::path default_path(int bounces);

    const SingleScatterTable& point_single() const { return *point_single_; }
    const SingleScatterTable& directional_single() const { return *directional_single_; }
    const AreaSingleScatterTable& area_single() const { return *area_single_; }
    const PointMultipleScatter& point_multiple() const { return *point_multiple_; }
    const SlabMultipleScatter& directional_multiple() const { return *directional_multiple_; }
    // Directional multiple scattering at a receiver on the bottom face of a slab whose
    // thickness is the depth (slab_bottom_multiple_scatter.h): lightmap texels.
    const SlabMultipleScatter& directional_multiple_bottom() const {
        return *directional_multiple_bottom_;
    }
    int bounces() const { return point_multiple_->bounces(); }

    // Queries against direct computation (deterministic quadrature, impulse_response.h) over a
    // spread of media and distances: point and directional single scattering, every ZH
    // coefficient above 1e-3 of the DC term. `freqlab tables` refuses a file beyond
    // kVerifyTolerance.
    struct Verification {
        double worst_point = 0.0, worst_directional = 0.0;  // relative, per coefficient
        int queries = 0;
        double worst() const { return std::max(worst_point, worst_directional); }
    };
    static constexpr double kVerifyTolerance = 0.005;
    Verification verify() const;

  private:
    std::shared_ptr<SingleScatterTable> point_single_, directional_single_;
    std::shared_ptr<AreaSingleScatterTable> area_single_;
    std::shared_ptr<PointMultipleScatter> point_multiple_;
    std::shared_ptr<SlabMultipleScatter> directional_multiple_, directional_multiple_bottom_;
};

}  // namespace freqlab
