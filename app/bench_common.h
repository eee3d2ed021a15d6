// Pieces the `freqlab bench` studies share.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cluster.h"
#include "commands.h"
#include "render/frame_renderer.h"

namespace freqlab {

// The part of a study's configurations this process computes: MPI's rank, or --part I/N.
// Throws Error for --part under mpirun.
WorkPart bench_work_part(const BenchArgs& args);
// A Slurm array task's share of a study: OUT/bench_part.json holds the study, the part, the
// report's header and this part's rows; `freqlab merge` joins the parts (app/merge.cpp).
void write_bench_part(const BenchArgs& args, WorkPart part, const nlohmann::json& header,
                      const nlohmann::json& rows);
// The bake-thickness study's files from its header and rows in order (bench_bake.cpp): what
// one process writes and what `freqlab merge` writes from the parts.
void write_bake_thickness_outputs(const std::string& out, const nlohmann::json& header,
                                  const nlohmann::json& rows);

// The MIS sample count whose frame takes `target_ms`: frames at 8 and 64 spp (a warm-up, then
// the median of 3 timings each) fit t(spp) = t_0 + c spp, t_0 being the G-buffer and set-up.
// Throws Error when the two times give no positive slope.
// `mis_config(spp)` builds the MIS configuration at a sample count.
int equal_time_mis_spp(const Scene& scene, const std::function<RenderConfig(int spp)>& mis_config,
                       const EmbreeDevice& device, int frame, double target_ms, Progress& progress);

double median(std::vector<double> v);

// A render configuration for a study: `method`, the user's --set assignments then the study's
// own `extra` ones, at width x height.
RenderConfig bench_config(RenderMethod method, const std::vector<std::string>& sets,
                          const std::vector<std::string>& extra, int width, int height);

}  // namespace freqlab
