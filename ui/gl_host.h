// Where GL frames come from. One small interface so the workbench does not care whether it
// draws into a GLFW window (GLX) or an offscreen OSMesa context (an EGL-surfaceless host can
// be added behind the same interface when Mesa drops OSMesa; see shared/PLATFORM.md).
#pragma once

#include <string>
#include <vector>

namespace freqlab::ui {

class GlHost {
  public:
    virtual ~GlHost() = default;
    virtual bool should_close() const = 0;
    virtual void begin_frame() = 0;  // events / ImGui platform frame
    // Nothing on screen will change until an input event: a window host may sleep in
    // begin_frame() until one comes (or a short timeout), instead of redrawing at full rate.
    virtual void set_idle(bool) {}
    virtual void end_frame() = 0;  // present
    virtual void framebuffer_size(int* w, int* h) const = 0;
    // The monitor's content scale (DPI / 96): what --ui-scale 0 (auto) scales the UI by.
    virtual float content_scale() const { return 1.0f; }
    // The default framebuffer as RGB8, top row first (after drawing, before end_frame()).
    std::vector<unsigned char> read_rgb() const;
};

}  // namespace freqlab::ui
