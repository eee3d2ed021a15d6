// A real window: GLFW 3.3 with a GL 3.3 core context (needs an X display; see
// shared/PLATFORM.md — GLFW 3.3 has no null platform).
#pragma once

#include "gl_host.h"

struct GLFWwindow;

namespace freqlab::ui {

class GlfwHost : public GlHost {
  public:
    GlfwHost(int width, int height, const std::string& title);  // throws Error on failure
    ~GlfwHost() override;
    bool should_close() const override;
    void begin_frame() override;
    void end_frame() override;
    void framebuffer_size(int* w, int* h) const override;
    float content_scale() const override;
    void set_idle(bool idle) override { idle_ = idle; }

  private:
    GLFWwindow* window_ = nullptr;
    bool idle_ = false;
};

}  // namespace freqlab::ui
