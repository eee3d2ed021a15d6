// A real window (GLFW on X, under xvfb-run): drives 40 frames of the workbench including a
// timeline scrub and a settings change, reads back the framebuffer, and compares it with the
// OSMesa (headless) render of the same state. Label `window`.
#include <gtest/gtest.h>
#include <imgui.h>
#include <imgui_impl_opengl3.h>

#include <cstdlib>

#include "glfw_host.h"
#include "osmesa_host.h"
#include "workbench.h"

using namespace freqlab;
using namespace freqlab::ui;

namespace {

constexpr int kW = 1000, kH = 640;

WorkbenchOptions options() {
    WorkbenchOptions o;
    o.settings = {"frame.width=200", "frame.height=112", "gbuffer.aa_samples=2"};
    o.show_timings = false;
    return o;
}

// The scripted session: 40 frames, scrubbing 0 -> 5 -> 2, then an exposure change.
std::vector<unsigned char> drive(GlHost& host, int* frames_drawn) {
    ImGui_ImplOpenGL3_Init("#version 330");
    std::vector<unsigned char> pixels;
    {
        Workbench wb(options());
        int drawn = 0;
        auto step = [&](int n) {
            for (int i = 0; i < n; ++i, ++drawn) {
                wb.wait_for_render();
                render_ui_frame(host, wb);
                host.end_frame();
            }
        };
        step(10);
        wb.set_frame(5);
        step(10);
        wb.set_frame(2);
        step(10);
        wb.apply_setting("frame.exposure=1.5");
        wb.set_layer("albedo");
        step(8);
        for (int i = 0; i < 50 && !wb.frame_shown(); ++i) step(1);
        EXPECT_TRUE(wb.frame_shown()) << wb.error();
        EXPECT_EQ(wb.frame(), 2);
        step(1);
        wb.wait_for_render();
        render_ui_frame(host, wb);  // the frame compared: read before presenting
        pixels = host.read_rgb();
        host.end_frame();
        *frames_drawn = drawn + 1;
    }
    ImGui_ImplOpenGL3_Shutdown();
    return pixels;
}

}  // namespace

TEST(Window, RealWindowMatchesTheHeadlessRender) {
    std::vector<unsigned char> window_pixels, headless_pixels;
    int frames = 0;
    {
        ImGui::CreateContext();
        ImGui::GetIO().IniFilename = nullptr;
        GlfwHost host(kW, kH, "freqlab window test");
        int w, h;
        host.framebuffer_size(&w, &h);
        ASSERT_EQ(w, kW);
        ASSERT_EQ(h, kH);
        window_pixels = drive(host, &frames);
    }
    ImGui::DestroyContext();
    EXPECT_GE(frames, 30);
    {
        ImGui::CreateContext();
        ImGui::GetIO().IniFilename = nullptr;
        OsMesaHost host(kW, kH);
        int unused;
        headless_pixels = drive(host, &unused);
        ImGui::DestroyContext();
    }
    ASSERT_EQ(window_pixels.size(), headless_pixels.size());
    std::vector<int> seen(256, 0);
    for (unsigned char v : window_pixels) seen[v] = 1;
    int distinct = 0;
    for (int v : seen) distinct += v;
    EXPECT_GT(distinct, 64) << "the window shows the workbench, not a blank frame";
    long differing = 0;
    double total = 0;
    for (size_t i = 0; i < window_pixels.size(); ++i) {
        const int d = std::abs(int(window_pixels[i]) - int(headless_pixels[i]));
        total += d;
        differing += d > 2;
    }
    // Both are Mesa llvmpipe: the same state must give the same picture.
    std::printf("window vs headless: mean |diff| %.4f, %ld of %zu values differ by > 2\n",
                total / double(window_pixels.size()), differing, window_pixels.size());
    EXPECT_LE(total / double(window_pixels.size()), 0.5);
    EXPECT_LE(double(differing) / double(window_pixels.size()), 0.001);
}
