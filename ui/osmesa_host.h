// An offscreen GL 3.3 core context through OSMesa (llvmpipe): the workbench without a display,
// for `freqlab gui --headless` and the `gl` tests. Mouse input is injected by the caller.
#pragma once

#include <memory>

#include "gl_host.h"

namespace freqlab::ui {

class OsMesaHost : public GlHost {
  public:
    OsMesaHost(int width, int height);  // throws Error when no context can be made
    ~OsMesaHost() override;
    bool should_close() const override { return false; }
    void begin_frame() override;
    void end_frame() override;
    void framebuffer_size(int* w, int* h) const override;

    // Input for the next frame (pixels from the top-left, as ImGui counts them).
    void set_mouse(float x, float y, bool left_down);
    void scroll(float wheel) { wheel_ = wheel; }

  private:
    struct Context;
    std::unique_ptr<Context> context_;
    int width_, height_;
    float mouse_x_ = -1, mouse_y_ = -1, wheel_ = 0;
    bool mouse_down_ = false;
};

}  // namespace freqlab::ui
