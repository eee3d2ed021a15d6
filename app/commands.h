// The sub-commands of `freqlab` (DESIGN.md "Command line"). Each returns the process exit
// code; errors are thrown as freqlab::Error and printed by main().
#pragma once

#include <string>
#include <vector>

namespace freqlab {

struct Scene;
// Prints what the loader changed in the scene's input (Scene::load_notes) to stderr.
void print_load_notes(const Scene& scene);

struct RenderArgs {
    std::string scene = "builtin:default";
    std::string method = "gbuffer";
    std::string frames = "0:1";  // A:B, half-open like a Python slice: frames A .. B-1
    std::string size;            // WxH; empty keeps frame.width/height
    int spp = 0;                 // 0 keeps the method's default
    int seed = -1;               // -1 keeps frame.seed
    int threads = 0;             // 0: all cores
    std::vector<std::string> sets;
    std::string debug_pixel;  // "X,Y"
    bool quiet = false;
    std::string out;
    // Past one process (app/cluster.h): "I/N" renders part I of N (a Slurm array task; merged
    // by `freqlab merge`); method cache: each part warms its cache over `warm_frames` frames
    // before the first frame it keeps.
    std::string part;
    int warm_frames = 10;
    // Stateful methods (render/frame_checkpoint.h): write the state before every K-th frame to
    // OUT/checkpoints (0: none); start from the newest checkpoint in DIR at or before the first
    // frame, rendering the frames in between without keeping them.
    int checkpoint_every = 0;
    std::string resume_from;
};
int run_render(const RenderArgs& args);  // render.cpp

// `freqlab merge OUT DIR...`: the parts of a split render into one run (merge.cpp).
int run_merge(const std::string& out, const std::vector<std::string>& parts);

struct CompareArgs {
    std::string test, ref;
    std::string metrics = "rmse,relmse,ssim,max_abs,nonfinite";
    std::string layer = "color";
};
int run_compare(const CompareArgs& args);

struct BenchArgs {
    std::string scene = "scenes/rotor.json";
    std::string study = "points";
    int frame = 0;
    std::string size = "320x180";
    int runs = 4;
    std::vector<std::string> sets;
    std::string out = "freqlab-out/bench";
    std::string frames;        // cache studies: A:B (default: every frame of the scene)
    int error_every = 10;      // cache studies: RMSE against the reference on every k-th frame
    int reference_spp = 4096;  // points: the stratified reference; bake: the VPT reference
    int max_spp = 1024;        // bake study: impulse and extinction curves
    int overhead_spp = 64;     // bake study: equal-sample overhead and re-bake
    bool full = false;         // stability study: every declared extreme (takes longer)
    bool quiet = false;        // stability study: no line per case
    std::string part;          // bake-thickness: "I/N", this Slurm array task's configurations
};
int run_bench(const BenchArgs& args);

struct BakeArgs {
    std::string scene = "builtin:default";
    std::string method = "impulse";
    int spp = 0;    // 0 keeps bake.spp
    int seed = -1;  // -1 keeps bake.seed
    int threads = 0;
    std::vector<std::string> sets;
    // Directories of a reference bake (errors per lightmap), or of two independent halves of
    // one (their mean is the reference; their difference measures its noise).
    std::vector<std::string> reference;
    bool compare_surface = false;
    std::string debug_texel;  // [LIGHTMAP:]X,Y
    std::string preview_size = "640x360";
    bool quiet = false;
    std::string out;
};
int run_bake(const BakeArgs& args);          // bake.cpp
int run_bench_cache(const BenchArgs& args);  // studies cache, cache-ablation (bench_cache.cpp)
int run_bench_bake(const BenchArgs& args);   // study bake (bench_bake.cpp)
int run_bench_bake_thickness(const BenchArgs& args);  // study bake-thickness (bench_bake.cpp)
int run_bench_sparse(const BenchArgs& args);          // study sparse (bench_sparse.cpp)
int run_bench_stability(const BenchArgs& args);       // study stability (bench_stability.cpp)

struct FigureArgs {
    std::string input;  // an EXR written by freqlab (or any EXR)
    std::string layer = "color";
    std::vector<std::string> insets;  // "X,Y,W,H"
    int scale = 2;
    float exposure = 0.0f;
    std::string title;
    std::string out;
};
int run_figure(const FigureArgs& args);

struct TablesQueryArgs {
    std::string emitter = "point";  // point | directional | area
    double distance = 1.0;          // point: to the emitter; directional: to the medium boundary
    double sigma_s = 1.0, sigma_a = 0.0, g = 0.0;
    std::string bounces = "1";         // all | N
    double shift = 0.0;                // area: sin of the emitter normal's angle to the receiver
    std::string variant = "infinite";  // infinite | surface
    std::string receiver = "medium";   // medium | surface
};
int run_tables_query(const TablesQueryArgs& args);
// Generates (or reuses) the table file, then verifies it against direct computation.
int run_tables_generate(const std::string& out, int bounces);
constexpr int kDefaultTableBounces = 30;

// A whole number >= 0 given to `flag` (`whole`: the full value quoted in the error, when
// `text` is part of it); throws Error naming the flag, never std::stoi's "stoi".
int parse_count(const std::string& text, const std::string& flag, const std::string& whole = "");
// Frames "A:B" → [A, B); "N" → [N, N+1). Throws Error naming --frames.
std::pair<int, int> parse_frame_range(const std::string& text, int frame_count);
// "WxH" → (W, H).
std::pair<int, int> parse_size(const std::string& text, const std::string& flag);

}  // namespace freqlab
