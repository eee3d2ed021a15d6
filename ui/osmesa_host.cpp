#include "osmesa_host.h"

#include <glad/gl.h>
#include <imgui.h>

#include "base/error.h"
#include "osmesa_context.h"

namespace freqlab::ui {

struct OsMesaHost::Context {
    OsMesaContextHandle* handle = nullptr;
    ~Context() { osmesa_destroy(handle); }
};

OsMesaHost::OsMesaHost(int width, int height)
    : context_(std::make_unique<Context>()), width_(width), height_(height) {
    context_->handle = osmesa_create(width, height);
    if (!context_->handle)
        throw Error("OSMesa", "OSMesaCreateContextAttribs",
                    "cannot create an offscreen GL 3.3 core context (is libosmesa6 installed?)");
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(osmesa_proc_address)))
        throw Error("OSMesa", "gladLoadGL", "cannot load OpenGL 3.3 core functions");
}

OsMesaHost::~OsMesaHost() = default;

void OsMesaHost::begin_frame() {
    ImGuiIO& io = ImGui::GetIO();
    io.DisplaySize = ImVec2(float(width_), float(height_));
    io.DisplayFramebufferScale = ImVec2(1, 1);
    io.DeltaTime = 1.0f / 60.0f;  // time comes from frames, never the wall clock
    io.MousePos = ImVec2(mouse_x_, mouse_y_);
    io.MouseDown[0] = mouse_down_;
    io.MouseWheel = wheel_;
    wheel_ = 0;
}

void OsMesaHost::end_frame() {
    glFinish();
}

void OsMesaHost::framebuffer_size(int* w, int* h) const {
    *w = width_;
    *h = height_;
}

void OsMesaHost::set_mouse(float x, float y, bool left_down) {
    mouse_x_ = x;
    mouse_y_ = y;
    mouse_down_ = left_down;
}

}  // namespace freqlab::ui
