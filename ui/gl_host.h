// Where GL frames come from. One small interface so the workbench does not care whether it
// draws into a GLFW window (GLX) or, later, an offscreen OSMesa / EGL context.
#pragma once

#include <string>

namespace freqlab::ui {

class GlHost {
  public:
    virtual ~GlHost() = default;
    virtual bool should_close() const = 0;
    virtual void begin_frame() = 0;  // poll events, start the ImGui platform frame
    virtual void end_frame() = 0;    // present
    virtual void framebuffer_size(int* w, int* h) const = 0;
    virtual void set_title(const std::string& title) = 0;
};

}  // namespace freqlab::ui
