#include "image/image_io.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "base/error.h"
#include "base/file_io.h"
#include "image/image_file_check.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;
OIIO_NAMESPACE_USING

namespace {

json layer_table(const LayerSet& set) {
    json table = json::array();
    for (const Layer& l : set.layers()) {
        json e = {{"name", l.name}, {"kind", to_string(l.kind)}, {"channels", l.channels}};
        if (!l.description.empty()) e["description"] = l.description;
        if (!l.legend.empty()) e["legend"] = l.legend;
        // A categorical layer's own colours travel with it, so that `freqlab figure` and the
        // workbench colour a layer read back exactly as the one that was written.
        if (!l.palette.empty()) {
            json colours = json::array();
            for (const vec3& c : l.palette) colours.push_back({c.x, c.y, c.z});
            e["palette"] = colours;
        }
        table.push_back(e);
    }
    return table;
}

// A layer's palette from its header entry: RGB triples in [0, 1].
std::vector<vec3> read_palette(const json& colours, const fs::path& path,
                               const std::string& field) {
    if (!colours.is_array() || colours.size() > 4096)
        throw Error(path.string(), field + ".palette", "expected an array of at most 4096 colours");
    std::vector<vec3> palette;
    for (size_t k = 0; k < colours.size(); ++k) {
        const json& c = colours[k];
        const std::string where = field + ".palette[" + std::to_string(k) + "]";
        if (!c.is_array() || c.size() != 3) throw Error(path.string(), where, "expected [r, g, b]");
        vec3 v;
        for (int i = 0; i < 3; ++i) {
            if (!c[size_t(i)].is_number() || !(c[size_t(i)].get<double>() >= 0.0) ||
                !(c[size_t(i)].get<double>() <= 1.0))
                throw Error(path.string(), where, "expected components in [0, 1]");
            v[i] = c[size_t(i)].get<float>();
        }
        palette.push_back(v);
    }
    return palette;
}

float srgb_to_linear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// The reader of the file's extension only: on a file that reader refuses, OIIO would by
// default try every format it knows (its global "try_all_readers"), LibRaw's among them, which
// clears 64 MB per attempt (profiled: 80 % of fuzz_env_hdr's time, 51 inputs a second under
// ASan) and exposes every plugin to any file; the error is then another format's complaint.
std::unique_ptr<ImageInput> open_image(const fs::path& path, const std::string& expectation) {
    static const bool by_extension_only = OIIO::attribute("try_all_readers", 0);
    (void)by_extension_only;
    check_exr_attributes(path);
    auto in = ImageInput::create(path.string(), /*do_open=*/false);
    if (!in)
        throw Error(path.string(), "",
                    "cannot read image: " + OIIO::geterror() +
                        " (read by its extension's format only)" + expectation);
    ImageSpec spec;
    if (!in->open(path.string(), spec)) {
        std::string why = in->geterror();
        if (why.empty()) why = OIIO::geterror();
        throw Error(path.string(), "", "cannot read image: " + why + expectation);
    }
    return in;
}

// Not zero-filled: a header that promises a large image and a file that ends early cost no
// page of memory (fuzz_env_exr spent most of its time zeroing such buffers).
std::unique_ptr<float[]> pixel_buffer(const ImageSpec& spec) {
    return std::unique_ptr<float[]>(new float[size_t(spec.width) * spec.height * spec.nchannels]);
}

// Every pixel as floats. OpenImageIO 2.4's read_image and read_scanlines convert through a
// buffer of 64 MB of scanlines whatever the image's size (page-faulting it cost ~20 ms a read:
// 80 % of fuzz_env_hdr's time, 32 inputs a second); a scanline image in one pixel format is
// read here with read_native_scanlines into a buffer of its own size (converted after).
std::unique_ptr<float[]> read_float_pixels(ImageInput& in, const ImageSpec& spec,
                                           const fs::path& path) {
    std::unique_ptr<float[]> pixels = pixel_buffer(spec);
    const size_t values = size_t(spec.width) * spec.height * spec.nchannels;
    const bool one_format = spec.channelformats.empty() && spec.format.size() <= sizeof(float);
    bool ok = false;
    if (spec.tile_width == 0 && one_format && spec.format == TypeDesc::FLOAT) {
        ok = in.read_native_scanlines(0, 0, spec.y, spec.y + spec.height, 0, pixels.get());
    } else if (spec.tile_width == 0 && one_format) {
        std::unique_ptr<char[]> native(new char[values * spec.format.size()]);
        ok = in.read_native_scanlines(0, 0, spec.y, spec.y + spec.height, 0, native.get()) &&
             OIIO::convert_pixel_values(spec.format, native.get(), TypeDesc::FLOAT, pixels.get(),
                                        int(values));
    } else {
        ok = in.read_image(0, 0, 0, spec.nchannels, TypeDesc::FLOAT, pixels.get());
    }
    if (!ok) throw Error(path.string(), "", "cannot read pixels: " + in.geterror());
    return pixels;
}

// Why a write failed: the writer's own error (OIIO keeps it per ImageOutput), else the global
// one, with what the file system says (a full disk gave "could not write EXR:" and no reason).
std::string write_failure(const fs::path& path, ImageOutput* out) {
    std::string why = out ? out->geterror() : std::string();
    if (why.empty()) why = OIIO::geterror();
    return describe_write_failure(path, why);
}

}  // namespace

void write_exr(const fs::path& path, const LayerSet& layers, const json& provenance) {
    if (layers.layers().empty()) throw Error(path.string(), "", "no layers to write");
    std::vector<std::string> names;
    for (const Layer& l : layers.layers())
        for (const std::string& n : l.channel_names()) names.push_back(n);
    const int nch = int(names.size());
    const size_t npix = layers.pixel_count();
    std::vector<float> interleaved(npix * nch);
    int base = 0;
    for (const Layer& l : layers.layers()) {
        for (size_t p = 0; p < npix; ++p)
            for (int c = 0; c < l.channels; ++c)
                interleaved[p * nch + base + c] = l.data[p * l.channels + c];
        base += l.channels;
    }
    ImageSpec spec(layers.width(), layers.height(), nch, TypeDesc::FLOAT);
    spec.channelnames = names;
    spec.attribute("compression", "zip");
    spec.attribute("freqlab:layers", layer_table(layers).dump());
    spec.attribute("freqlab:provenance", provenance.dump());
    // A fixed capture date keeps files byte-identical across runs (determinism tests compare
    // bytes); the real wall-clock times live in stats.json.
    spec.attribute("DateTime", "1970:01:01 00:00:00");
    write_atomically(path, [&](const fs::path& tmp) {
        auto out = ImageOutput::create(tmp.string());
        if (!out || !out->open(tmp.string(), spec) ||
            !out->write_image(TypeDesc::FLOAT, interleaved.data()) || !out->close())
            throw Error(path.string(), "",
                        "could not write EXR: " + write_failure(path, out.get()));
    });
}

ExrFile read_exr(const fs::path& path) {
    auto in = open_image(path, " (expected a readable OpenEXR file)");
    const ImageSpec spec = in->spec();
    check_image_size(path, spec.width, spec.height, spec.nchannels);
    const std::unique_ptr<float[]> pixels = pixel_buffer(spec);
    if (!in->read_image(0, 0, 0, spec.nchannels, TypeDesc::FLOAT, pixels.get()))
        throw Error(path.string(), "", "cannot read pixels: " + in->geterror());
    in->close();

    ExrFile file;
    file.layers = LayerSet(spec.width, spec.height);
    file.provenance = json::object();
    const std::string prov = spec.get_string_attribute("freqlab:provenance");
    if (!prov.empty()) file.provenance = json::parse(prov, nullptr, false);
    if (file.provenance.is_discarded()) file.provenance = json::object();

    std::map<std::string, int> channel_index;
    for (int c = 0; c < spec.nchannels; ++c) channel_index[spec.channelnames[c]] = c;
    auto copy_channels = [&](Layer& layer) {
        const std::vector<std::string> names = layer.channel_names();
        for (int c = 0; c < layer.channels; ++c) {
            auto it = channel_index.find(names[c]);
            if (it == channel_index.end())
                throw Error(path.string(), "channel " + names[c],
                            "missing although the freqlab:layers header lists it");
            for (size_t p = 0; p < file.layers.pixel_count(); ++p)
                layer.data[p * layer.channels + c] = pixels[p * spec.nchannels + it->second];
        }
    };

    const json table =
        json::parse(spec.get_string_attribute("freqlab:layers", "null"), nullptr, false);
    if (table.is_array()) {
        for (size_t i = 0; i < table.size(); ++i) {
            const json& e = table[i];
            const std::string field = "freqlab:layers[" + std::to_string(i) + "]";
            try {
                const int channels = e.value("channels", 1);
                if (channels < 1 || channels > 4)
                    throw Error(path.string(), field + ".channels", "expected 1 to 4");
                Layer& l = file.layers.add(e.value("name", ""),
                                           layer_kind_from_string(e.value("kind", "continuous")),
                                           channels, e.value("description", ""));
                if (e.contains("legend")) l.legend = e["legend"].get<std::vector<std::string>>();
                if (e.contains("palette")) l.palette = read_palette(e["palette"], path, field);
                copy_channels(l);
            } catch (const json::exception& x) {  // a field of another type
                throw Error(path.string(), field,
                            std::string("malformed layer entry: ") + x.what());
            }
        }
        return file;
    }
    // A foreign EXR: group channels by the text before the last '.', unprefixed ones = color.
    std::vector<std::pair<std::string, std::vector<int>>> groups;
    for (int c = 0; c < spec.nchannels; ++c) {
        const std::string& n = spec.channelnames[c];
        const size_t dot = n.rfind('.');
        const std::string layer = dot == std::string::npos ? "color" : n.substr(0, dot);
        auto it = std::find_if(groups.begin(), groups.end(),
                               [&](const auto& g) { return g.first == layer; });
        if (it == groups.end())
            groups.push_back({layer, {c}});
        else
            it->second.push_back(c);
    }
    for (const auto& [name, chans] : groups) {
        Layer& l = file.layers.add(
            name, chans.size() >= 3 ? LayerKind::Color : LayerKind::Continuous, int(chans.size()));
        for (size_t p = 0; p < file.layers.pixel_count(); ++p)
            for (size_t c = 0; c < chans.size(); ++c)
                l.data[p * l.channels + c] = pixels[p * spec.nchannels + chans[c]];
    }
    return file;
}

ImageHeader read_image_header(const fs::path& path) {
    const ImageSpec spec = open_image(path, "")->spec();
    return ImageHeader{spec.width, spec.height, spec.nchannels};
}

RgbImage read_rgb_image(const fs::path& path, bool require_finite) {
    auto in = open_image(path, "");
    const ImageSpec spec = in->spec();
    check_image_size(path, spec.width, spec.height, spec.nchannels);
    const std::unique_ptr<float[]> pixels = read_float_pixels(*in, spec, path);
    const bool srgb = spec.format.basetype == TypeDesc::UINT8 ||
                      spec.get_string_attribute("oiio:ColorSpace") == "sRGB";
    RgbImage img;
    img.width = spec.width;
    img.height = spec.height;
    img.pixels.resize(size_t(spec.width) * spec.height);
    for (size_t p = 0; p < img.pixels.size(); ++p) {
        vec3 v;
        for (int c = 0; c < 3; ++c) {
            float x = pixels[p * spec.nchannels + std::min(c, spec.nchannels - 1)];
            if (require_finite && !std::isfinite(x))
                throw Error(path.string(),
                            "pixel (" + std::to_string(p % spec.width) + ", " +
                                std::to_string(p / spec.width) + ")",
                            "non-finite value (NaN or Inf); expected finite radiance");
            v[c] = srgb ? srgb_to_linear(x) : x;
        }
        img.pixels[p] = v;
    }
    return img;
}

void write_png(const fs::path& path, int width, int height, const std::vector<unsigned char>& rgb8,
               const json& provenance) {
    ImageSpec spec(width, height, 3, TypeDesc::UINT8);
    // A tEXt chunk "freqlab:provenance" (scene/provenance.h), like the EXR header's.
    if (!provenance.empty()) spec.attribute("freqlab:provenance", provenance.dump());
    write_atomically(path, [&](const fs::path& tmp) {
        auto out = ImageOutput::create(tmp.string());
        if (!out || !out->open(tmp.string(), spec) ||
            !out->write_image(TypeDesc::UINT8, rgb8.data()) || !out->close())
            throw Error(path.string(), "",
                        "could not write PNG: " + write_failure(path, out.get()));
    });
}

}  // namespace freqlab
