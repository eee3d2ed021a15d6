#include "image/layers.h"

#include "base/error.h"

namespace freqlab {

std::vector<std::string> Layer::channel_names() const {
    static const char* rgb[] = {"R", "G", "B", "A"};
    static const char* xyz[] = {"X", "Y", "Z", "W"};
    std::vector<std::string> out;
    if (channels == 1) return {name + ".Y"};
    for (int c = 0; c < channels; ++c) {
        const std::string ch =
            c < 4 ? (kind == LayerKind::Color ? rgb[c] : xyz[c]) : std::to_string(c);
        out.push_back(name == "color" ? ch : name + "." + ch);
    }
    return out;
}

Layer& LayerSet::add(const std::string& name, LayerKind kind, int channels,
                     const std::string& description) {
    Layer layer;
    layer.name = name;
    layer.kind = kind;
    layer.channels = channels;
    layer.description = description;
    layer.data.assign(pixel_count() * channels, 0.0f);
    for (Layer& l : layers_)
        if (l.name == name) return l = std::move(layer);
    layers_.push_back(std::move(layer));
    return layers_.back();
}

const Layer* LayerSet::find(const std::string& name) const {
    for (const Layer& l : layers_)
        if (l.name == name) return &l;
    return nullptr;
}

Layer* LayerSet::find(const std::string& name) {
    for (Layer& l : layers_)
        if (l.name == name) return &l;
    return nullptr;
}

const Layer& LayerSet::get(const std::string& name) const {
    if (const Layer* l = find(name)) return *l;
    throw Error("", "layer", "no layer named \"" + name + "\"; layers are: " + names());
}

std::string LayerSet::names() const {
    std::string s;
    for (const Layer& l : layers_) s += (s.empty() ? "" : ", ") + l.name;
    return s;
}

}  // namespace freqlab
