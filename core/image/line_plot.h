// Line plots for benchmark reports (cumulative render time, error curves): axes with ticks,
// one polyline per series and a legend, drawn with OpenImageIO's render_line / render_text.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "math/types.h"

namespace freqlab {

struct PlotSeries {
    std::string name;
    vec3 colour{1.0f};
    std::vector<double> x, y;
};

struct LinePlot {
    std::string title, x_label, y_label;
    std::vector<PlotSeries> series;
    bool log_x = false, log_y = false;
    int width = 900, height = 520;
    std::string font = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
};

// Throws Error naming the field for empty or non-finite data and for an unusable font.
void write_line_plot(const std::filesystem::path& path, const LinePlot& plot);

}  // namespace freqlab
