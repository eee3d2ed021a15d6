// All of method B's impulse-response tables in one versioned file: tabulated once (canonical
// medium), cached on disk, verified on load (parameters and an FNV-1a checksum of the payload).
//
// | part                         | size                                    |
// |------------------------------|-----------------------------------------|
// | point single scattering      | kPhaseTerms x kBins x kImpulseOrder      |
// | directional single scatter.  | kPhaseTerms x kBins x kImpulseOrder      |
// | point multiple scattering    | bounces x kBins x (kImpulseOrder + 1)    |
// Stored as float32 (the tables' own error is ~1e-4; float rounding is 6e-8).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "base/job.h"
#include "volume/impulse_response.h"
#include "volume/multiple_scatter.h"

namespace freqlab {

class ImpulseTables {
  public:
    static constexpr int kFormatVersion = 1;

    static ImpulseTables build(int bounces, Progress* progress = nullptr);
    void save(const std::filesystem::path& path) const;            // atomic
    static ImpulseTables load(const std::filesystem::path& path);  // throws Error naming the field
    // The cached file for `bounces` (built and saved when absent or invalid).
    static ImpulseTables cached(int bounces, std::string* path_used = nullptr);
    static std::filesystem::path default_path(int bounces);

    const SingleScatterTable& point_single() const { return *point_single_; }
    const SingleScatterTable& directional_single() const { return *directional_single_; }
    const PointMultipleScatter& point_multiple() const { return *point_multiple_; }

  private:
    std::shared_ptr<SingleScatterTable> point_single_, directional_single_;
    std::shared_ptr<PointMultipleScatter> point_multiple_;
};

}  // namespace freqlab
