#include "glfw_host.h"

#include <glad/gl.h>
// glad first: GLFW must not pull in the system GL header.
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>

#include "base/error.h"

namespace freqlab::ui {

namespace {
std::string g_glfw_error;
void on_glfw_error(int code, const char* message) {
    g_glfw_error = "GLFW error " + std::to_string(code) + ": " + (message ? message : "");
}
}  // namespace

GlfwHost::GlfwHost(int width, int height, const std::string& title) {
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) throw Error("display", "glfwInit", "cannot open a window: " + g_glfw_error);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (!window_) {
        glfwTerminate();
        throw Error("display", "glfwCreateWindow",
                    "cannot create a GL 3.3 core window: " + g_glfw_error);
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(1);
    if (!gladLoadGL(reinterpret_cast<GLADloadfunc>(glfwGetProcAddress)))
        throw Error("display", "gladLoadGL", "cannot load OpenGL 3.3 core functions");
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
}

GlfwHost::~GlfwHost() {
    ImGui_ImplGlfw_Shutdown();
    glfwDestroyWindow(window_);
    glfwTerminate();
}

bool GlfwHost::should_close() const {
    return glfwWindowShouldClose(window_);
}

void GlfwHost::begin_frame() {
    // Idle: sleep until an input event, waking twice a second for what changes without one
    // (a background table build); busy (a job's progress, playback): one frame per vsync.
    if (idle_)
        glfwWaitEventsTimeout(0.5);
    else
        glfwPollEvents();
    ImGui_ImplGlfw_NewFrame();
}

void GlfwHost::end_frame() {
    glfwSwapBuffers(window_);
}

float GlfwHost::content_scale() const {
    float x = 1.0f, y = 1.0f;
    glfwGetWindowContentScale(window_, &x, &y);
    return x > 0.0f ? x : 1.0f;
}

void GlfwHost::framebuffer_size(int* w, int* h) const {
    glfwGetFramebufferSize(window_, w, h);
}

}  // namespace freqlab::ui
