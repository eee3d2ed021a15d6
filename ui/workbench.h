// The workbench window: settings panels generated from core's declarations, the viewport
// showing the colour or any layer, a pixel inspector, and the timeline with a stats strip.
// Rendering runs as a cancellable background job; the UI thread never waits for it.
#pragma once

#include <string>

namespace freqlab::ui {

struct WorkbenchOptions {
    std::string scene = "builtin:default";  // a file or builtin:default
    int frame = 0;
    std::string layer;  // initial layer shown ("" = color)
    std::string
        screenshot;  // when set: once the frame is rendered, write the window as PNG and exit
    int width = 1280, height = 760;
};

// Opens a window; returns the exit code.
int run_workbench(const WorkbenchOptions& options);

}  // namespace freqlab::ui
