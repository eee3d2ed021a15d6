// A piecewise-constant 2D distribution, used for environment-map importance sampling. Built
// once per map; sampling is O(1) by alias table, or O(log) by inverting the CDFs.
//
// A smooth map is sampled by tiles: the density is constant over square tiles of f x f texels
// (f = tile(), a power of two) when that costs the sampling almost nothing. Why: a 2048 x 1024
// sky's alias table (16 MB) and CDFs miss the cache on every draw, and its sampling was 8-11 %
// of valley's bakes (perf, session 31); a 256 x 128 table stays in L2. What it costs: against
// the per-texel density, the second moment of an estimate of the weights' own integral grows
// by inflation() = sum_i w_i^2 / wbar_tile(i) / sum_i w_i (>= 1, 1 for weights constant over
// each tile); the coarsest f with inflation <= kMaxTileInflation is taken.
//
// | parameter          | meaning                                                            |
// |--------------------|--------------------------------------------------------------------|
// | kMaxTileInflation  | 1.01: at most 1 % more second moment on the weights themselves     |
// | kMinTiledTexels    | 65536: smaller maps stay per texel (their tables are cached anyway)|
// | kMaxTile           | 16 texels a side                                                   |
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "base/huge_pages.h"
#include "math/types.h"

namespace freqlab {

// Density over [0,1)^2 proportional to a width x height grid of weights (row 0 at v = 0),
// sampled in O(1) with Walker/Vose alias tables: one table access per sample instead of two
// binary searches, which matters when a sample costs tens of nanoseconds (profiled: the
// searches were 18 % of the MIS integrator's time on rotor.json).
class Distribution2D {
  public:
    static constexpr double kMaxTileInflation = 1.01;
    static constexpr size_t kMinTiledTexels = 65536;
    static constexpr int kMaxTile = 16;

    Distribution2D() = default;
    // tile: 0 chooses it (above); 1 keeps a density per texel; else a power of two dividing
    // width and height.
    Distribution2D(const std::vector<float>& weights, int width, int height, int tile = 0);
    // The second-moment growth of sampling `weights` by tiles of `tile` texels a side (above).
    static double tile_inflation(const std::vector<float>& weights, int width, int height,
                                 int tile);

    // u.x picks the tile, u.y is the alias coin, (u.z, u.w) the position inside the tile
    // (a texel when tile() is 1).
    vec2 sample(const vec4& u, float* pdf) const;
    // The texel index sample() picks (one alias-table read), and where in it sample() lands.
    int sample_texel(const vec4& u) const;
    vec2 texel_point(int texel, const vec4& u) const;
    // Texels a side of the tiles the density is constant over, and its cost (above).
    int tile() const { return 1 << tile_shift_; }
    int tile_shift() const { return tile_shift_; }
    double inflation() const { return inflation_; }
    // Continuous inversion of the rows' marginal CDF (u.y) and the row's conditional CDF
    // (u.x), over tiles: nearby u land nearby, so stratified u stay stratified over the map
    // (the alias table scatters them). Same density as sample_texel(); `within` is the
    // position inside the tile, what texel_point() takes as (u.z, u.w).
    int sample_texel_inverted(vec2 u, vec2* within) const;
    // The same in three stages, for loops over many samples: each stage prefetches what the
    // next reads, so the cache misses of all samples overlap (the column tables are megabytes).
    struct Inversion {
        float u_x;
        int row, column;  // column: the guide's starting step after stage 2 (-1: search)
        vec2 within;
    };
    Inversion invert_begin(vec2 u) const;   // the row (the marginal stays cached)
    void invert_guide(Inversion& s) const;  // reads the row's guide entry
    int invert_finish(Inversion& s) const;  // walks to the step; returns the texel
    // Starts loading the alias entry sample_texel(u) will read: a loop over many samples can
    // overlap those cache misses.
    void prefetch(const vec4& u) const { __builtin_prefetch(&alias_[alias_slot(u)]); }
    float pdf(vec2 uv) const;
    float texel_pdf(int index) const { return pdf_[tile_index(index % width_, index / width_)]; }
    int width() const { return width_; }
    int height() const { return height_; }
    // Probability mass of texel (x, y): what a chi-square test compares counts against.
    double texel_probability(int x, int y) const;

  private:
    size_t alias_slot(const vec4& u) const {
        return std::min(size_t(u.x * float(alias_.size())), alias_.size() - 1);
    }
    // The texel of tile (tile_x, tile_y) at position `within` inside it.
    int texel_in_tile(int tile_x, int tile_y, vec2 within) const;
    // The tile holding texel (x, y).
    size_t tile_index(int x, int y) const {
        return size_t(y >> tile_shift_) * size_t(tiles_x_) + size_t(x >> tile_shift_);
    }
    int width_ = 0, height_ = 0;
    int tile_shift_ = 0, tiles_x_ = 0, tiles_y_ = 0;  // the tables below are over tiles
    double inflation_ = 1.0;
    struct AliasEntry {
        float keep;      // probability of keeping texel i
        uint32_t alias;  // the texel taken otherwise
    };
    std::vector<float> pdf_;            // density over [0,1)^2 of each tile
    HugePageVector<AliasEntry> alias_;  // packed: one cache line per draw, not two
    // Double precision so that a dim texel keeps its own mass (a float sum of a 2048-texel row
    // rounds masses below ~1e-7 of the row away).
    std::vector<double> row_cdf_;        // height + 1 entries, 0 ... 1
    HugePageVector<double> column_cdf_;  // per row width + 1 entries, 0 ... 1 (rows with mass)
    // Guide tables (Chen and Asau's cutpoints): entry g is the step holding u = g / steps, so an
    // inversion reads one entry and walks a step or two from there instead of binary-searching
    // a row (profiled: the search's cache misses were a third of a stratified points frame).
    std::vector<uint32_t> row_guide_;        // height entries
    HugePageVector<uint16_t> column_guide_;  // per row width entries (maps up to 65535 wide)
};

}  // namespace freqlab
