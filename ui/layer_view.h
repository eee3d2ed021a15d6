// A layer on the GPU: the float data as a texture, mapped to display colours by the layer
// shader (shaders/layer.frag) into an RGBA8 texture that the viewport draws. Colormap LUTs
// are built from core's colormap functions, so CPU exports and the screen agree.
#pragma once

#include <vector>

#include "image/colormap.h"
#include "image/layers.h"

namespace freqlab::ui {

class LayerView {
  public:
    LayerView();
    ~LayerView();
    LayerView(const LayerView&) = delete;
    LayerView& operator=(const LayerView&) = delete;

    // Uploads `layer` and renders its display colours; returns the range that was used.
    // The output is the layer's size unless out_width/out_height ask for another (nearest).
    DisplayRange render(const LayerSet& set, const Layer& layer, const DisplayParams& params,
                        int out_width = 0, int out_height = 0);
    unsigned texture() const { return output_; }
    int width() const { return width_; }
    int height() const { return height_; }
    // The rendered colours, RGBA8, top row first (tests compare them with the CPU colormaps).
    std::vector<unsigned char> read_rgba() const;

  private:
    unsigned program_ = 0, vao_ = 0, data_ = 0, ramp_lut_ = 0, diverging_lut_ = 0, palette_lut_ = 0,
             fbo_ = 0, output_ = 0;
    int width_ = 0, height_ = 0;
};

}  // namespace freqlab::ui
