#include "layer_view.h"

#include <glad/gl.h>

#include <cmath>
#include <string>

#include "base/error.h"
#include "shaders.h"

namespace freqlab::ui {

namespace {

unsigned compile(GLenum type, const char* source, const char* name) {
    const unsigned s = glCreateShader(type);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    int ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[2048];
        glGetShaderInfoLog(s, sizeof log, nullptr, log);
        throw Error(std::string("shaders/") + name, "compile", log);
    }
    return s;
}

unsigned make_lut(const std::vector<vec3>& colours) {
    unsigned tex;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, int(colours.size()), 1, 0, GL_RGB, GL_FLOAT,
                 colours.data());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return tex;
}

}  // namespace

LayerView::LayerView() {
    const unsigned vs = compile(GL_VERTEX_SHADER, kShader_layer_vert, "layer.vert");
    const unsigned fs = compile(GL_FRAGMENT_SHADER, kShader_layer_frag, "layer.frag");
    program_ = glCreateProgram();
    glAttachShader(program_, vs);
    glAttachShader(program_, fs);
    glLinkProgram(program_);
    glDeleteShader(vs);
    glDeleteShader(fs);
    int ok = 0;
    glGetProgramiv(program_, GL_LINK_STATUS, &ok);
    if (!ok) throw Error("shaders/layer", "link", "the layer shader program did not link");
    glGenVertexArrays(1, &vao_);

    std::vector<vec3> ramp(256), div(256), palette(10);
    for (int i = 0; i < 256; ++i) {
        ramp[size_t(i)] = viridis(i / 255.0f);
        div[size_t(i)] = diverging(2.0f * i / 255.0f - 1.0f);
    }
    for (int i = 0; i < 10; ++i) palette[size_t(i)] = categorical(i);
    ramp_lut_ = make_lut(ramp);
    diverging_lut_ = make_lut(div);
    palette_lut_ = make_lut(palette);

    glGenTextures(1, &data_);
    glGenTextures(1, &output_);
    glGenFramebuffers(1, &fbo_);
}

LayerView::~LayerView() {
    glDeleteFramebuffers(1, &fbo_);
    const unsigned textures[] = {data_, output_, ramp_lut_, diverging_lut_, palette_lut_};
    glDeleteTextures(5, textures);
    glDeleteVertexArrays(1, &vao_);
    glDeleteProgram(program_);
}

DisplayRange LayerView::render(const LayerSet& set, const Layer& layer, const DisplayParams& params,
                               int out_width, int out_height) {
    const int lw = set.width(), lh = set.height();
    const int w = out_width > 0 ? out_width : lw, h = out_height > 0 ? out_height : lh;
    const bool vector = layer.channels >= 3 && layer.kind != LayerKind::Color;
    const int mode = layer.kind == LayerKind::Color        ? 0
                     : vector                              ? 4
                     : layer.kind == LayerKind::Continuous ? 1
                     : layer.kind == LayerKind::Signed     ? 2
                                                           : 3;
    const DisplayRange range = params.auto_range ? auto_range(layer) : params.range;

    glBindTexture(GL_TEXTURE_2D, data_);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    if (layer.channels >= 3) {
        // Pack to RGB (ignoring a 4th channel) for one upload path.
        std::vector<float> rgb(size_t(lw) * lh * 3);
        for (size_t p = 0; p < size_t(lw) * lh; ++p)
            for (int c = 0; c < 3; ++c) rgb[3 * p + c] = layer.data[p * layer.channels + c];
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, lw, lh, 0, GL_RGB, GL_FLOAT, rgb.data());
    } else {
        glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, lw, lh, 0, GL_RED, GL_FLOAT, layer.data.data());
    }
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);

    if (w != width_ || h != height_) {
        glBindTexture(GL_TEXTURE_2D, output_);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
        // Nearest magnification: zooming in shows pixels, not a blur.
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, output_, 0);
        width_ = w;
        height_ = h;
    }

    GLint previous_fbo, previous_viewport[4];
    glGetIntegerv(GL_FRAMEBUFFER_BINDING, &previous_fbo);
    glGetIntegerv(GL_VIEWPORT, previous_viewport);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, w, h);
    glDisable(GL_BLEND);
    glDisable(GL_SCISSOR_TEST);
    glUseProgram(program_);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, data_);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, mode == 3 ? palette_lut_ : mode == 2 ? diverging_lut_ : ramp_lut_);
    if (mode == 3) {  // the layer's own palette (or the default one)
        const std::vector<vec3> palette = layer_palette(layer);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, int(palette.size()), 1, 0, GL_RGB, GL_FLOAT,
                     palette.data());
    }
    glUniform1i(glGetUniformLocation(program_, "u_layer"), 0);
    glUniform1i(glGetUniformLocation(program_, "u_lut"), 1);
    glUniform1i(glGetUniformLocation(program_, "u_mode"), mode);
    glUniform1f(glGetUniformLocation(program_, "u_lo"), range.lo);
    glUniform1f(glGetUniformLocation(program_, "u_hi"), range.hi);
    glUniform1f(glGetUniformLocation(program_, "u_exposure"), std::exp2(params.exposure_ev));
    glUniform1i(glGetUniformLocation(program_, "u_channels"), std::min(layer.channels, 3));
    glUniform1i(glGetUniformLocation(program_, "u_sparse"), layer.sparse ? 1 : 0);
    glBindVertexArray(vao_);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glActiveTexture(GL_TEXTURE0);
    glUseProgram(0);
    glBindFramebuffer(GL_FRAMEBUFFER, GLuint(previous_fbo));
    glViewport(previous_viewport[0], previous_viewport[1], previous_viewport[2],
               previous_viewport[3]);
    return range;
}

std::vector<unsigned char> LayerView::read_rgba() const {
    std::vector<unsigned char> pixels(size_t(width_) * height_ * 4);
    GLint previous_fbo;
    glGetIntegerv(GL_FRAMEBUFFER_BINDING, &previous_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glFinish();
    glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    glBindFramebuffer(GL_FRAMEBUFFER, GLuint(previous_fbo));
    // The shader wrote v_uv.y = 0 (the layer's top row) at GL row 0: GL rows are layer rows.
    return pixels;
}

}  // namespace freqlab::ui
