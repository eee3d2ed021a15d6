// Paper figures from a layer: the image (nearest-neighbour upscaled), up to four zoomed
// insets framed in distinct colours on the image and repeated beside it, a colorbar with
// labelled ticks (or a legend for categorical layers) and a title. Text is rendered by
// OpenImageIO with a TrueType font (DejaVu Sans from fonts-dejavu-core by default).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "image/colormap.h"
#include "image/layers.h"

namespace freqlab {

struct FigureInset {
    int x = 0, y = 0, width = 32, height = 32;  // in layer pixels
};

struct FigureSpec {
    std::string layer = "color";
    DisplayParams display;
    std::vector<FigureInset> insets;  // at most 4
    int scale = 2;                    // main image magnification (nearest)
    std::string title;
    std::string font = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
};

struct FigureImage {
    int width = 0, height = 0;
    std::vector<unsigned char> rgb;  // top row first
    // Where things landed (for tests and captions), in figure pixels.
    struct Box {
        int x0, y0, x1, y1;
    };
    Box main;
    std::vector<Box> inset_panels;
    std::vector<Box> legend_swatches;  // categorical layers: the swatch of value i
};

// Composes the figure; throws Error naming the field for a bad layer, inset or font.
FigureImage compose_figure(const LayerSet& set, const FigureSpec& spec);
// `provenance` (scene/provenance.h) goes into the PNG's freqlab:provenance text chunk.
void write_figure(const std::filesystem::path& path, const LayerSet& set, const FigureSpec& spec,
                  const nlohmann::json& provenance = nlohmann::json::object());

}  // namespace freqlab
