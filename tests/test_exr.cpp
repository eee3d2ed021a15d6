// Multi-layer EXR: every layer, kind and legend survives a write/read bit-exactly.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cstring>
#include <filesystem>

#include "image/image_io.h"
#include "math/rng.h"

using namespace freqlab;
namespace fs = std::filesystem;

TEST(Exr, MultiLayerRoundTripIsBitExact) {
    LayerSet set(37, 19);
    CounterRng rng(1, 2, 3, 4);
    Layer& color = set.add("color", LayerKind::Color, 3);
    Layer& normal = set.add("normal", LayerKind::Signed, 3, "unit normals");
    Layer& depth = set.add("depth", LayerKind::Continuous, 1);
    Layer& decision = set.add("decision", LayerKind::Categorical, 1);
    decision.legend = {"reused", "discard: angular", "discard: occlusion"};
    for (Layer* l : {&color, &normal, &depth, &decision})
        for (float& v : l->data) v = (rng.next_float() - 0.25f) * 1e3f;
    depth.data[5] = 1e-38f;  // denormal-adjacent values must survive too
    depth.data[6] = -0.0f;
    const fs::path path = fs::temp_directory_path() / "freqlab_roundtrip.exr";
    const nlohmann::json prov = {{"method", "gbuffer"}, {"seed", 7}};
    write_exr(path, set, prov);

    const ExrFile back = read_exr(path);
    EXPECT_EQ(back.provenance, prov);
    ASSERT_EQ(back.layers.width(), 37);
    ASSERT_EQ(back.layers.height(), 19);
    ASSERT_EQ(back.layers.layers().size(), 4u);
    for (const Layer& l : set.layers()) {
        const Layer* b = back.layers.find(l.name);
        ASSERT_NE(b, nullptr) << l.name;
        EXPECT_EQ(b->kind, l.kind);
        EXPECT_EQ(b->channels, l.channels);
        EXPECT_EQ(b->legend, l.legend);
        ASSERT_EQ(b->data.size(), l.data.size());
        EXPECT_EQ(std::memcmp(b->data.data(), l.data.data(), l.data.size() * sizeof(float)), 0)
            << l.name;
    }
    EXPECT_EQ(back.layers.find("normal")->description, "unit normals");
}

TEST(Exr, ChannelNamesFollowTheConvention) {
    LayerSet set(1, 1);
    set.add("color", LayerKind::Color, 3);
    set.add("albedo", LayerKind::Color, 3);
    set.add("normal", LayerKind::Signed, 3);
    set.add("depth", LayerKind::Continuous, 1);
    EXPECT_EQ(set.get("color").channel_names(), (std::vector<std::string>{"R", "G", "B"}));
    EXPECT_EQ(set.get("albedo").channel_names(),
              (std::vector<std::string>{"albedo.R", "albedo.G", "albedo.B"}));
    EXPECT_EQ(set.get("normal").channel_names(),
              (std::vector<std::string>{"normal.X", "normal.Y", "normal.Z"}));
    EXPECT_EQ(set.get("depth").channel_names(), (std::vector<std::string>{"depth.Y"}));
}

TEST(Exr, NoTemporaryFileIsLeftBehind) {
    const fs::path dir = fs::temp_directory_path() / "freqlab_atomic";
    fs::remove_all(dir);
    fs::create_directories(dir);
    LayerSet set(2, 2);
    set.add("color", LayerKind::Color, 3);
    write_exr(dir / "a.exr", set);
    int files = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
        EXPECT_EQ(e.path().filename(), "a.exr");
        ++files;
    }
    EXPECT_EQ(files, 1);
}

// A PNG carries the provenance in a text chunk, as an EXR does in its header.
TEST(Exr, PngCarriesTheProvenanceInATextChunk) {
    const std::filesystem::path file =
        std::filesystem::temp_directory_path() / "freqlab_test_provenance.png";
    const nlohmann::json prov = {{"method", "mis"}, {"seed", 7}, {"media", {{{"g", 0.9}}}}};
    write_png(file, 2, 1, {255, 0, 0, 0, 255, 0}, prov);
    auto in = OIIO::ImageInput::open(file.string());
    ASSERT_TRUE(in);
    const std::string text = in->spec().get_string_attribute("freqlab:provenance");
    in->close();
    std::filesystem::remove(file);
    EXPECT_EQ(nlohmann::json::parse(text), prov);
}
