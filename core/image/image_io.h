// Image files: multi-layer EXR (every layer, kinds and provenance in the header) and PNG
// previews, through OpenImageIO. All writes are atomic (base/file_io.h).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "image/layers.h"
#include "math/types.h"

namespace freqlab {

struct RgbImage {
    int width = 0, height = 0;
    std::vector<vec3> pixels;  // linear RGB, row-major from the top row
    const vec3& at(int x, int y) const { return pixels[size_t(y) * width + x]; }
};

// Writes every layer as float channels (ZIP compressed). `provenance` lands in the header as
// the string attribute "freqlab:provenance"; layer kinds and legends as "freqlab:layers".
void write_exr(const std::filesystem::path& path, const LayerSet& layers,
               const nlohmann::json& provenance = nlohmann::json::object());

struct ExrFile {
    LayerSet layers;
    nlohmann::json provenance;  // empty object when the file was not written by freqlab
};
// Reads any float EXR; channels are grouped into layers by their "layer." prefix. Files
// written by freqlab get their kinds and legends back exactly.
ExrFile read_exr(const std::filesystem::path& path);

// An image file's size as its header declares it, read with the same checks as the readers
// below (throws Error naming the file): what a caller may look at before reading the pixels.
struct ImageHeader {
    int width = 0, height = 0, channels = 0;
};
ImageHeader read_image_header(const std::filesystem::path& path);

// Reads an RGB(A) image of any format OpenImageIO knows as linear RGB (8-bit sRGB files are
// linearised). With `require_finite`, a NaN/Inf pixel is an error naming the pixel.
RgbImage read_rgb_image(const std::filesystem::path& path, bool require_finite = true);

// 8-bit sRGB PNG (RGB), rows from the top.
// `provenance`, when not empty, goes into a tEXt chunk named freqlab:provenance.
void write_png(const std::filesystem::path& path, int width, int height,
               const std::vector<unsigned char>& rgb8,
               const nlohmann::json& provenance = nlohmann::json::object());

}  // namespace freqlab
