#include "layer_texture.h"

#include <glad/gl.h>

namespace freqlab::ui {

LayerTexture::LayerTexture() {
    glGenTextures(1, &texture_);
    glBindTexture(GL_TEXTURE_2D, texture_);
    // Nearest magnification: a researcher zooms in to see pixels, not a blur.
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

LayerTexture::~LayerTexture() {
    glDeleteTextures(1, &texture_);
}

void LayerTexture::upload(const LayerSet& set, const Layer& layer, const DisplayParams& params) {
    const std::vector<unsigned char> rgb = layer_to_rgb8(set, layer, params);
    width_ = set.width();
    height_ = set.height();
    glBindTexture(GL_TEXTURE_2D, texture_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, width_, height_, 0, GL_RGB, GL_UNSIGNED_BYTE,
                 rgb.data());
}

}  // namespace freqlab::ui
