#include "gl_host.h"

#include <glad/gl.h>

namespace freqlab::ui {

std::vector<unsigned char> GlHost::read_rgb() const {
    int w, h;
    framebuffer_size(&w, &h);
    std::vector<unsigned char> rgba(size_t(w) * h * 4), rgb(size_t(w) * h * 3);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glFinish();
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    for (int y = 0; y < h; ++y)  // GL rows start at the bottom
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                rgb[(size_t(h - 1 - y) * w + x) * 3 + c] = rgba[(size_t(y) * w + x) * 4 + c];
    return rgb;
}

}  // namespace freqlab::ui
