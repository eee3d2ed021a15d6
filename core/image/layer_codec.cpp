#include "image/layer_codec.h"

#include <algorithm>
#include <cstring>

#include "base/error.h"

namespace freqlab {

namespace {
constexpr uint32_t kMagic = 0x464c4c53;  // "FLLS"
}

std::string encode_layers(const LayerSet& layers) {
    ByteWriter w;
    encode_layers(layers, w);
    return std::move(w.bytes());
}

void encode_layers(const LayerSet& layers, ByteSink& w) {
    w.put(kMagic);
    w.put<int32_t>(layers.width());
    w.put<int32_t>(layers.height());
    w.put<uint32_t>(uint32_t(layers.layers().size()));
    for (const Layer& l : layers.layers()) {
        w.put_string(l.name);
        w.put<int32_t>(int32_t(l.kind));
        w.put<int32_t>(l.channels);
        w.put_string(l.description);
        w.put<uint32_t>(uint32_t(l.legend.size()));
        for (const std::string& s : l.legend) w.put_string(s);
        w.put<uint32_t>(uint32_t(l.palette.size()));
        w.put_bytes(l.palette.data(), l.palette.size() * sizeof(vec3));
        w.put<uint8_t>(l.sparse ? 1 : 0);
        w.put<uint64_t>(l.data.size());
        w.put_bytes(l.data.data(), l.data.size() * sizeof(float));
    }
}

namespace {

// Every layer when `only` is null.
LayerSet decode(std::string_view bytes, const std::string& source,
                const std::vector<std::string>* only, std::vector<std::string>* left_out) {
    ByteReader r(bytes, source);
    if (r.get<uint32_t>() != kMagic) throw Error(source, "layers", "not an encoded LayerSet");
    const int width = r.get<int32_t>(), height = r.get<int32_t>();
    if (width < 0 || height < 0) throw Error(source, "layers", "negative size");
    LayerSet set(width, height);
    const uint32_t count = r.get<uint32_t>();
    for (uint32_t i = 0; i < count; ++i) {
        const std::string name = r.get_string();
        const int kind = r.get<int32_t>();
        if (kind < 0 || kind > int(LayerKind::Categorical))
            throw Error(source, "layers." + name, "unknown kind " + std::to_string(kind));
        const int channels = r.get<int32_t>();
        if (channels < 1 || channels > 4)
            throw Error(source, "layers." + name, "expected 1 to 4 channels");
        // The values must be in what is left before a layer of the declared size is allocated.
        if (uint64_t(width) * uint64_t(height) * uint64_t(channels) > r.remaining() / sizeof(float))
            throw Error(source, "layers." + name,
                        std::to_string(width) + " x " + std::to_string(height) + " x " +
                            std::to_string(channels) + " values past the end");
        const bool wanted = !only || std::find(only->begin(), only->end(), name) != only->end();
        Layer scratch;  // a layer left out is checked like the others, then dropped
        Layer& l = wanted ? set.add(name, LayerKind(kind), channels, r.get_string()) : scratch;
        if (!wanted) r.get_view();  // its description
        const uint32_t entries = r.get<uint32_t>();
        if (entries > r.remaining() / sizeof(uint64_t))  // each at least its length
            throw Error(source, "layers." + name,
                        "a legend of " + std::to_string(entries) + " entries past the end");
        l.legend.resize(entries);
        for (std::string& s : l.legend) s = r.get_string();
        const uint32_t colours = r.get<uint32_t>();
        if (size_t(colours) * sizeof(vec3) > r.remaining())
            throw Error(source, "layers." + name, "palette past the end");
        l.palette.resize(colours);
        r.get_bytes(l.palette.data(), l.palette.size() * sizeof(vec3));
        l.sparse = r.get<uint8_t>() != 0;
        const uint64_t values = r.get<uint64_t>();
        if (values != uint64_t(set.pixel_count()) * uint64_t(channels))
            throw Error(source, "layers." + name,
                        "expected " + std::to_string(set.pixel_count() * size_t(channels)) +
                            " values, got " + std::to_string(values));
        if (wanted) {
            r.get_bytes(l.data.data(), size_t(values) * sizeof(float));
        } else {
            r.skip(size_t(values) * sizeof(float));
            left_out->push_back(name);
        }
    }
    if (r.remaining() != 0)
        throw Error(source, "layers", std::to_string(r.remaining()) + " bytes past the end");
    return set;
}

}  // namespace

LayerSet decode_layers(std::string_view bytes, const std::string& source) {
    return decode(bytes, source, nullptr, nullptr);
}

LayerSet decode_layers(std::string_view bytes, const std::string& source,
                       const std::vector<std::string>& only, std::vector<std::string>& left_out) {
    left_out.clear();
    return decode(bytes, source, &only, &left_out);
}

}  // namespace freqlab
