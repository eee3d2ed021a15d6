// A GL texture holding one layer as displayed (core's colormap/tonemap decides the colours;
// the GPU colormap shaders arrive with the workbench issue).
#pragma once

#include "image/colormap.h"
#include "image/layers.h"

namespace freqlab::ui {

class LayerTexture {
  public:
    LayerTexture();
    ~LayerTexture();
    LayerTexture(const LayerTexture&) = delete;
    LayerTexture& operator=(const LayerTexture&) = delete;

    void upload(const LayerSet& set, const Layer& layer, const DisplayParams& params);
    unsigned id() const { return texture_; }
    int width() const { return width_; }
    int height() const { return height_; }

  private:
    unsigned texture_ = 0;
    int width_ = 0, height_ = 0;
};

}  // namespace freqlab::ui
