// Writes the binary seeds of the fuzz corpora and the stub assets the scene fuzzer resolves
// against (tests/fuzz/assets: small stand-ins for the Debian packages' maps, meshes and
// textures, so that one input loads in milliseconds). Run by hand when a seed changes:
//   build-sanitize/tests/fuzz/fuzz_make_seeds tests/fuzz
// The outputs are committed; nothing runs this in CI.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "base/byte_stream.h"
#include "cache/radiance_cache.h"
#include "fuzz_support.h"
#include "render/frame_renderer.h"
#include "render/frame_store.h"
#include "session/session_file.h"
#include "volume/vdb_reader.h"

namespace fs = std::filesystem;

namespace {

std::vector<float> gradient(int w, int h, int channels) {
    std::vector<float> px(size_t(w) * h * channels);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < channels; ++c)
                px[(size_t(y) * w + x) * channels + c] =
                    c == 3 ? 1.0f : 0.2f + 4.0f * float(x + c) / w * float(h - y) / h;
    return px;
}

void write_image(const fs::path& path, int w, int h, int channels, OIIO::TypeDesc format,
                 const std::vector<float>& px) {
    fs::create_directories(path.parent_path());
    OIIO::ImageSpec spec(w, h, channels, format);
    auto out = OIIO::ImageOutput::create(path.string());
    if (!out || !out->open(path.string(), spec) ||
        !out->write_image(OIIO::TypeDesc::FLOAT, px.data()) || !out->close()) {
        std::fprintf(stderr, "%s: %s\n", path.c_str(), OIIO::geterror().c_str());
        std::exit(1);
    }
}

void write_vdb(const fs::path& path, const std::string& grid, int n, float voxel) {
    fs::create_directories(path.parent_path());
    freqlab::VdbDensity d;
    d.resolution = freqlab::ivec3(n);
    d.box_min = freqlab::vec3(-0.5f * n * voxel);
    d.box_max = freqlab::vec3(0.5f * n * voxel);
    d.voxels.resize(size_t(n) * n * n);
    for (size_t i = 0; i < d.voxels.size(); ++i) d.voxels[i] = float(i % 7) * 0.25f;
    freqlab::write_vdb_density(path.string(), grid, d);
}

void write_text(const fs::path& path, const std::string& text) {
    fs::create_directories(path.parent_path());
    std::ofstream(path) << text;
}

void write_sessions(const fs::path& dir) {
    freqlab::RenderConfig config;
    freqlab::SessionFile s;
    s.scene = "scenes/rotor.json";
    s.method = "cache";
    s.frame = 12;
    s.layer = "cache_decisions";
    s.insets = {{10, 20, 64, 48}};
    s.pick_x = 40, s.pick_y = 30;
    s.settings = config.settings_group().to_json();
    write_text(dir / "render.json", freqlab::session_json(s).dump(2));
    s.scene = "scenes/cornell_fog.json";
    s.method = "impulse";
    s.layer = "lm_total";
    s.insets.clear();
    freqlab::BakeSessionFile bake;
    bake.media = {{"fog", 0.8, 0.05, 0.3, 1.0}};
    bake.yaw = 20.0f;
    s.bake = bake;
    write_text(dir / "bake.json", freqlab::session_json(s).dump(2));
}

}  // namespace

// A recorded frame (prefix byte 0) and an encoded cache (prefix 1), tiny but with every part.
void write_run_store_seeds(const fs::path& dir) {
    fs::create_directories(dir);
    const fs::path tmp = fs::temp_directory_path() / "freqlab-seed-run";
    freqlab::FrameResult r;
    r.frame = 3;
    r.layers = freqlab::LayerSet(4, 3);
    r.layers.add("color", freqlab::LayerKind::Color, 3).data.assign(36, 0.5f);
    freqlab::Layer& d = r.layers.add("decision", freqlab::LayerKind::Categorical, 1);
    d.legend = {"reused", "new"};
    d.palette = {freqlab::vec3(1, 0, 0), freqlab::vec3(0, 1, 0)};
    r.stats = {{"frame", 3}, {"time_ms", 1.5}};
    freqlab::CacheRecord rec;
    rec.pixel = 5;
    r.cache_records = std::make_shared<const std::vector<freqlab::CacheRecord>>(1, rec);
    r.sample_positions = std::make_shared<const std::vector<std::pair<int, freqlab::vec3>>>(
        1, std::make_pair(5, freqlab::vec3(1, 2, 3)));
    freqlab::write_recorded_frame(tmp, fuzz_run_key(), r);
    std::ifstream in(freqlab::recorded_frame_path(tmp, 3), std::ios::binary);
    const std::string frame((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(dir / "frame.bin", std::ios::binary) << '\0' << frame;
    freqlab::RadianceCache cache;
    cache.reset(2);
    for (int k = 0; k < 3; ++k) {
        freqlab::CacheEntry e;
        e.position = freqlab::vec3(float(k), 0.0f, 1.0f);
        cache.object(k % 2).insert(e);
    }
    freqlab::ByteWriter w;
    cache.encode(w);
    std::ofstream(dir / "cache.bin", std::ios::binary) << '\1' << w.bytes();
    fs::remove_all(tmp);
}

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: fuzz_make_seeds tests/fuzz\n");
        return 2;
    }
    const fs::path root = argv[1];
    const fs::path assets = root / "assets", corpus = root / "corpus";
    const auto half = OIIO::TypeDesc::HALF, flt = OIIO::TypeDesc::FLOAT;
    for (const char* name : {"city", "forest"})
        write_image(assets / "studiolights/world" / (std::string(name) + ".exr"), 16, 8, 3, half,
                    gradient(16, 8, 3));
    write_image(assets / "OBJ/SpiderTex.jpg", 8, 8, 3, OIIO::TypeDesc::UINT8, gradient(8, 8, 3));
    write_image(assets / "glTF/CesiumMilkTruck/CesiumMilkTruck.png", 8, 8, 3, OIIO::TypeDesc::UINT8,
                gradient(8, 8, 3));
    write_image(corpus / "env_exr/rgb_half.exr", 16, 8, 3, half, gradient(16, 8, 3));
    write_image(corpus / "env_exr/rgba_float.exr", 8, 4, 4, flt, gradient(8, 4, 4));
    write_image(corpus / "env_exr/grey.exr", 4, 2, 1, flt, gradient(4, 2, 1));
    write_image(corpus / "env_hdr/rgb.hdr", 16, 8, 3, flt, gradient(16, 8, 3));
    write_image(corpus / "env_hdr/wide.hdr", 64, 2, 3, flt, gradient(64, 2, 3));
    write_vdb(corpus / "vdb/density.vdb", "density", 4, 0.5f);
    write_vdb(corpus / "vdb/smoke.vdb", "smoke", 3, 1.0f);
    write_sessions(corpus / "session");
    write_run_store_seeds(corpus / "run_store");
    return 0;
}
