// What the GL tests share: an ImGui + OSMesa session per test, a small scene's options, and
// the UI loop until the workbench shows a frame.
#pragma once

#include <gtest/gtest.h>
#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "osmesa_host.h"
#include "workbench.h"

namespace freqlab::ui::test {

// $FREQLAB_RUN_STORE_DIR pointing at an empty temporary folder for this scope; the previous
// value comes back and the folder goes at the end, also when an assertion returns early.
class ScopedRunStore {
  public:
    explicit ScopedRunStore(const std::string& name)
        : dir_(std::filesystem::temp_directory_path() / name) {
        std::filesystem::remove_all(dir_);
        if (const char* old = std::getenv("FREQLAB_RUN_STORE_DIR")) previous_ = old;
        setenv("FREQLAB_RUN_STORE_DIR", dir_.c_str(), 1);
    }
    ScopedRunStore(const ScopedRunStore&) = delete;
    ScopedRunStore& operator=(const ScopedRunStore&) = delete;
    ~ScopedRunStore() {
        if (previous_)
            setenv("FREQLAB_RUN_STORE_DIR", previous_->c_str(), 1);
        else
            unsetenv("FREQLAB_RUN_STORE_DIR");
        std::error_code ec;
        std::filesystem::remove_all(dir_, ec);
    }
    const std::filesystem::path& dir() const { return dir_; }

  private:
    std::filesystem::path dir_;
    std::optional<std::string> previous_;
};

// An ImGui context plus an OSMesa context with the OpenGL3 backend, per test.
struct GlSession {
    explicit GlSession(int w = 960, int h = 600) {
        ImGui::CreateContext();
        ImGui::GetIO().IniFilename = nullptr;
        host = std::make_unique<OsMesaHost>(w, h);
        ImGui_ImplOpenGL3_Init("#version 330");
    }
    ~GlSession() {
        ImGui_ImplOpenGL3_Shutdown();
        host.reset();
        ImGui::DestroyContext();
    }
    std::unique_ptr<OsMesaHost> host;
};

inline void run_until_shown(GlSession& gl, Workbench& wb) {
    for (int i = 0; i < 400 && !wb.frame_shown(); ++i) {
        wb.wait_for_render();
        render_ui_frame(*gl.host, wb);
    }
    ASSERT_TRUE(wb.frame_shown()) << wb.error();
    render_ui_frame(*gl.host, wb);  // one more frame: the layout uses the shown result
}

inline WorkbenchOptions small_scene(const std::string& layer) {
    WorkbenchOptions o;
    o.layer = layer;
    o.settings = {"frame.width=160", "frame.height=90", "gbuffer.aa_samples=1"};
    return o;
}

}  // namespace freqlab::ui::test
