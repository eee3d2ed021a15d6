// Named result layers (DESIGN.md "Layers"). A frame or bake result is a LayerSet: float
// layers of one resolution, each with a kind that decides its colormap, its legend and how
// its EXR channels are named. The GUI's overlays are exactly these layers.
#pragma once

#include <deque>
#include <string>
#include <vector>

#include "base/enum_names.h"
#include "math/types.h"

namespace freqlab {

enum class LayerKind {
    Color,        // linear RGB radiance or reflectance: exposure + sRGB
    Continuous,   // non-negative scalar or vector: viridis with a colorbar
    Signed,       // values around 0: diverging map symmetric about 0
    Categorical,  // small integers with a legend: one palette colour per category
};

inline constexpr EnumName<LayerKind> kLayerKindNames[] = {{LayerKind::Color, "color"},
                                                          {LayerKind::Continuous, "continuous"},
                                                          {LayerKind::Signed, "signed"},
                                                          {LayerKind::Categorical, "categorical"}};
inline const char* to_string(LayerKind kind) {
    return enum_name(kLayerKindNames, kind);
}
inline LayerKind layer_kind_from_string(const std::string& s) {  // throws Error naming "kind"
    return enum_from_name(kLayerKindNames, s, "kind");
}

struct Layer {
    std::string name;
    LayerKind kind = LayerKind::Continuous;
    int channels = 1;
    std::string description;
    std::vector<std::string> legend;  // Categorical: legend[i] names value i
    std::vector<vec3> palette;        // Categorical: colour of value i (empty: Tableau-10)
    // Values only at the pixels that hold a sample (0 elsewhere, e.g. method A's radiance
    // points): viewers draw those pixels as points so that zooming out never hides them.
    bool sparse = false;
    std::vector<float> data;  // interleaved, row-major from the top row

    float& at(int width, int x, int y, int c = 0) {
        return data[(size_t(y) * width + x) * channels + c];
    }
    float at(int width, int x, int y, int c = 0) const {
        return data[(size_t(y) * width + x) * channels + c];
    }
    // EXR channel names: the main `color` layer is R,G,B; others `name.R/G/B` for colours,
    // `name.X/Y/Z` for vectors and `name.Y` for scalars.
    std::vector<std::string> channel_names() const;
    // Texel i's luminance (math/types.h's weights) of an RGB layer.
    float luminance_at(size_t i) const {
        return luminance(vec3(data[3 * i], data[3 * i + 1], data[3 * i + 2]));
    }
};

class LayerSet {
  public:
    LayerSet() = default;
    LayerSet(int width, int height) : width_(width), height_(height) {}

    int width() const { return width_; }
    int height() const { return height_; }
    size_t pixel_count() const { return size_t(width_) * height_; }

    // Adds a zero-filled layer; replaces a layer of the same name.
    Layer& add(const std::string& name, LayerKind kind, int channels,
               const std::string& description = "");
    const Layer* find(const std::string& name) const;
    Layer* find(const std::string& name);
    const Layer& get(const std::string& name) const;  // throws Error listing the layer names
    const std::deque<Layer>& layers() const { return layers_; }
    std::deque<Layer>& layers() { return layers_; }
    std::string names() const;  // "a, b, c" for messages

  private:
    int width_ = 0, height_ = 0;
    std::deque<Layer> layers_;  // deque: references stay valid as layers are added
};

}  // namespace freqlab
