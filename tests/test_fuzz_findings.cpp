// Regression tests of what the fuzzers found (issue "Reliability", tests/fuzz): each input
// once crashed, hung, leaked an exception that named no file, or let a non-finite value
// through; each must now end in a freqlab::Error naming the file and the field.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "base/error.h"
#include "image/image_file_check.h"
#include "image/image_io.h"
#include "render/frame_renderer.h"
#include "scene/json_reader.h"
#include "scene/light.h"
#include "session/session_file.h"
#include "volume/impulse_tables.h"
#include "volume/vdb_file_check.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include "volume/vdb_reader.h"

using namespace freqlab;
namespace fs = std::filesystem;

namespace {

template <class F>
Error expect_error(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e;
    }
    ADD_FAILURE() << "no Error";
    return Error("", "", "");
}

fs::path temp_file(const std::string& name) {
    return fs::temp_directory_path() / ("freqlab_fuzz_findings_" + name);
}

std::string read_bytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_bytes(const fs::path& p, const std::string& bytes) {
    std::ofstream(p, std::ios::binary) << bytes;
}

// A valid 4 x 2 colour EXR written at p, as bytes to damage.
std::string small_exr_bytes(const fs::path& p) {
    LayerSet layers(4, 2);
    layers.add("color", LayerKind::Color, 3);
    write_exr(p, layers);
    return read_bytes(p);
}

}  // namespace

// nlohmann's const operator[] past an array's end is undefined (fuzz_session: "range": []).
TEST(FuzzFindings, JsonArrayIndexPastTheEndNamesTheField) {
    const nlohmann::json doc = nlohmann::json::parse(R"({"range": [1]})");
    const JsonReader r(doc, "s.json", "");
    const Error e = expect_error([&] { r.get("range").at(1); });
    EXPECT_EQ(e.file(), "s.json");
    EXPECT_EQ(e.field(), "range");
    EXPECT_NE(std::string(e.what()).find("at least 2 elements"), std::string::npos) << e.what();
    const Error n = expect_error([&] { r.get("range").at(0).at(0); });
    EXPECT_EQ(n.field(), "range[0]");
}

SessionFile valid_session() {
    RenderConfig config;
    SessionFile s;
    s.scene = "builtin:default";
    s.method = "mis";
    s.layer = "color";
    s.settings = config.settings_group().to_json();
    return s;
}

TEST(FuzzFindings, SessionFileRoundTripsAndRefusesBadFieldsByName) {
    SessionFile s = valid_session();
    s.zoom = 3.0f;
    s.insets = {{1, 2, 30, 40}};
    const SessionFile back = read_session_file(session_json(s).dump(), "s.json");
    EXPECT_EQ(back.zoom, 3.0f);
    ASSERT_EQ(back.insets.size(), 1u);
    EXPECT_EQ(back.insets[0].height, 40);
    struct Case {
        const char* key;
        nlohmann::json value;
        const char* field;
    };
    const Case cases[] = {{"range", nlohmann::json::array(), "range"},
                          {"range", 5, "range"},
                          {"centre", {0.5}, "centre"},
                          {"zoom", 0, "zoom"},
                          {"insets", {{1, 2}}, "insets[0]"},
                          {"method", "nonsense", "method"},
                          {"bake", nlohmann::json::object(), "bake"}};
    for (const Case& c : cases) {
        nlohmann::json j = session_json(s);
        j[c.key] = c.value;
        const Error e = expect_error([&] { read_session_file(j.dump(), "s.json"); });
        EXPECT_EQ(e.file(), "s.json") << c.key;
        EXPECT_EQ(e.field(), c.field) << e.what();
    }
}

// An EXR attribute declaring 1.8 GB in a 600-byte file: OpenEXR allocated it (fuzz_env_exr).
TEST(FuzzFindings, ExrAttributeLargerThanTheFileIsRefused) {
    const fs::path p = temp_file("attribute.exr");
    std::string bytes = small_exr_bytes(p);
    const size_t at = bytes.find("channels");
    ASSERT_NE(at, std::string::npos);
    const size_t size_at = at + std::strlen("channels") + 1 + std::strlen("chlist") + 1;
    const int32_t huge = 1845493779;
    std::memcpy(&bytes[size_at], &huge, 4);
    write_bytes(p, bytes);
    const Error e = expect_error([&] { read_rgb_image(p); });
    EXPECT_EQ(e.file(), p.string());
    EXPECT_EQ(e.field(), "header.channels");
    EXPECT_NE(std::string(e.what()).find("1845493779"), std::string::npos) << e.what();
    const Error x = expect_error([&] { read_exr(p); });
    EXPECT_EQ(x.field(), "header.channels");
    fs::remove(p);
}

// OpenEXR 3.1 reads a channel list until its empty name and a known type by its own size,
// whatever the declared size says; where they disagree it reads on from another offset
// (fuzz_env_exr: a 206-byte file, an attribute size read out of "\0com", 1.8 GB allocated).
// The walk refuses such a header by name; a file OpenEXR wrote still reads.
TEST(FuzzFindings, ExrValueSizesMustBeTheTypesOwn) {
    const fs::path p = temp_file("chlist.exr");
    const std::string valid = small_exr_bytes(p);
    EXPECT_EQ(read_rgb_image(p).width, 4);
    const size_t at = valid.find("channels");
    ASSERT_NE(at, std::string::npos);
    const size_t size_at = at + std::strlen("channels") + 1 + std::strlen("chlist") + 1;
    int32_t declared = 0;
    std::memcpy(&declared, &valid[size_at], 4);
    // The list's structure is its entries and the empty name; declaring 18 bytes fewer leaves
    // OpenEXR reading the rest as the next attribute.
    std::string bytes = valid;
    const int32_t shorter = declared - 18;
    std::memcpy(&bytes[size_at], &shorter, 4);
    write_bytes(p, bytes);
    Error e = expect_error([&] { read_rgb_image(p); });
    EXPECT_EQ(e.field(), "header.channels") << e.what();
    // A compression attribute declaring 4 bytes (OpenEXR reads 1).
    bytes = valid;
    const size_t c = bytes.find("compression");
    ASSERT_NE(c, std::string::npos);
    const int32_t four = 4;
    std::memcpy(&bytes[c + 2 * (std::strlen("compression") + 1)], &four, 4);
    write_bytes(p, bytes);
    e = expect_error([&] { read_rgb_image(p); });
    EXPECT_EQ(e.field(), "header.compression") << e.what();
    EXPECT_NE(e.message().find("which is 1"), std::string::npos) << e.what();
    // The fuzzer's own input.
    const Error f = expect_error([&] {
        read_rgb_image(std::string(FREQLAB_SOURCE_DIR) +
                       "/tests/fuzz/corpus/env_exr/chlist-past-its-size.exr");
    });
    EXPECT_EQ(f.field(), "header.channels") << f.what();
    fs::remove(p);
}

// OpenImageIO buffers a whole compression chunk (DWAB: 256 rows) of a 2 x 1e6 image: 2.3 GB.
TEST(FuzzFindings, ImageSizeLimitsNameTheResolution) {
    EXPECT_NO_THROW(check_image_size("a.exr", 8192, 4096, 4));
    const Error wide = expect_error([] { check_image_size("a.exr", 2162692, 2, 1); });
    EXPECT_EQ(wide.field(), "resolution");
    EXPECT_EQ(wide.file(), "a.exr");
    const Error big = expect_error([] { check_image_size("a.exr", 16384, 8192, 3); });
    EXPECT_NE(std::string(big.what()).find("2^28"), std::string::npos) << big.what();
    EXPECT_EQ(expect_error([] { check_image_size("a.exr", 0, 8, 3); }).field(), "resolution");
}

// A finite 1.7e38 texel in an HDR file made every estimate Inf (fuzz_env_hdr).
TEST(FuzzFindings, EnvironmentTexelBeyondTheLimitIsRefused) {
    auto image = std::make_shared<RgbImage>(*constant_latlong(vec3(1.0f), 8, 4));
    EXPECT_NO_THROW(EnvironmentMap("ok.hdr", image, 0.0f, 1e19f));
    const Error scaled = expect_error([&] { EnvironmentMap("ok.hdr", image, 0.0f, 1e21f); });
    EXPECT_EQ(scaled.file(), "ok.hdr");
    EXPECT_EQ(scaled.field(), "pixel (0, 0)");
    image->pixels[8 * 2 + 5] = vec3(0.0f, 1.7e38f, 0.0f);
    const Error e = expect_error([&] { EnvironmentMap("map.hdr", image, 0.0f, 1.0f); });
    EXPECT_EQ(e.field(), "pixel (5, 2)");
    EXPECT_NE(std::string(e.what()).find("1.7e+38"), std::string::npos) << e.what();
}

// A header field of another type threw nlohmann's type_error, naming no file.
TEST(FuzzFindings, ImpulseTableHeaderFieldsOfAnotherTypeNameTheField) {
    const fs::path p = temp_file("tables.bin");
    // Every parameter field as this version writes it, the closing brace left off.
    std::string good = nlohmann::json{{"bins", ZhDistanceTable::kBins},
                                      {"g_nodes", kGNodes},
                                      {"g_range", kGRange},
                                      {"g_inner", kGInner},
                                      {"g_panel_edges", kGPanelEdges},
                                      {"max_d", ZhDistanceTable::kMaxD},
                                      {"min_d", ZhDistanceTable::kMinD},
                                      {"order", kImpulseOrder},
                                      {"phase_terms", kPhaseTerms},
                                      {"shift_bins", kShiftBins},
                                      {"version", ImpulseTables::kFormatVersion}}
                           .dump();
    good.pop_back();
    const std::pair<std::string, std::string> cases[] = {
        {"[1, 2]", "header"},
        {good + R"(,"bounces":"30"})", "bounces"},
        {good + R"(,"bounces":30,"payload_floats":"x","payload_halves":1})", "payload_floats"}};
    for (const auto& [header, field] : cases) {
        write_bytes(p, "freqlab-impulse-tables\n" + header + "\n" + std::string(64, '\0'));
        const Error e = expect_error([&] { ImpulseTables::load(p); });
        EXPECT_EQ(e.file(), p.string());
        EXPECT_EQ(e.field(), field) << e.what();
    }
    fs::remove(p);
}

// A number beyond double threw nlohmann's out_of_range through every JSON reader
// (fuzz_scene_json, fuzz_session).
TEST(FuzzFindings, JsonNumberBeyondDoubleIsAnError) {
    const Error e = expect_error([] { JsonReader::parse(R"({"zoom": 1e99999})", "s.json"); });
    EXPECT_EQ(e.file(), "s.json");
    EXPECT_NE(std::string(e.what()).find("number overflow"), std::string::npos) << e.what();
}

// OpenVDB does not check its stream: a file cut short left a string length uninitialised and
// the reader allocated gigabytes, or not, from run to run (fuzz_vdb). Every prefix of a valid
// file must now be refused by name, and the whole file still read.
TEST(FuzzFindings, EveryTruncatedVdbFileIsRefusedByName) {
    VdbDensity g;
    g.box_min = vec3(0.0f);
    g.box_max = vec3(1.0f, 0.5f, 0.25f);
    g.resolution = ivec3(8, 4, 2);
    g.voxels.assign(64, 0.5f);
    const fs::path whole = temp_file("whole.vdb");
    write_vdb_density(whole.string(), "density", g);
    const std::string bytes = read_bytes(whole);
    ASSERT_GT(bytes.size(), 64u);
    EXPECT_EQ(
        read_vdb_density(whole.string(), "density", "s.json", "media[0].density").voxels.size(),
        64u);
    const fs::path cut = temp_file("cut.vdb");
    int refused = 0;
    for (size_t n = 0; n < bytes.size(); ++n) {
        write_bytes(cut, bytes.substr(0, n));
        const Error e = expect_error(
            [&] { read_vdb_density(cut.string(), "density", "s.json", "media[0].density"); });
        EXPECT_EQ(e.file(), "s.json") << n;
        EXPECT_EQ(e.field().rfind("media[0].density.", 0), 0u) << n << ": " << e.what();
        refused += e.message().find(cut.string()) != std::string::npos;
    }
    EXPECT_EQ(refused, int(bytes.size()));  // every message names the VDB file itself
}

// OpenVDB allocates and fills every string at the size the file declares before reading it: a
// damaged 10 kB file (tests/fuzz/corpus/vdb/regression_string_size.vdb, fuzz_vdb) cost 2 GB
// and 3 s before failing. The layout walk refuses it first, naming the field and the offset;
// a valid file passes it (and every prefix of one is refused: the test above).
TEST(FuzzFindings, VdbDeclaringMoreThanItHoldsIsRefusedBeforeAllocating) {
    const std::string bad =
        std::string(FREQLAB_SOURCE_DIR) + "/tests/fuzz/corpus/vdb/regression_string_size.vdb";
    const Error e = expect_error([&] { read_vdb_density(bad, "density", "s.json", "media[0]"); });
    EXPECT_EQ(e.field(), "media[0].file");
    EXPECT_NE(e.message().find("declares 1853189987 bytes but the file has"), std::string::npos)
        << e.what();
    EXPECT_NE(check_vdb_layout(bad).find("instance parent name declares"), std::string::npos)
        << check_vdb_layout(bad);

    VdbDensity g;
    g.box_min = vec3(0.0f);
    g.box_max = vec3(1.0f);
    g.resolution = ivec3(4, 4, 4);
    g.voxels.assign(64, 0.25f);
    const fs::path valid = temp_file("valid.vdb");
    write_vdb_density(valid.string(), "smoke", g);
    EXPECT_EQ(check_vdb_layout(valid.string()), "");
}

// OpenEXR sizes its line buffers from the data window when the file is opened: an inverted or
// vast window (fuzz_env_exr: corpus/env_exr/regression_inverted_window.exr) cost seconds of
// allocation before any check of ours ran. The header walk now refuses it, naming the field.
TEST(FuzzFindings, ExrDataWindowIsCheckedBeforeOpenExrSizesBuffers) {
    const fs::path p = temp_file("window.exr");
    const std::string valid = small_exr_bytes(p);
    const size_t at = valid.find("dataWindow");
    ASSERT_NE(at, std::string::npos);
    const size_t value_at = at + std::strlen("dataWindow") + 1 + std::strlen("box2i") + 1 + 4;
    auto with_window = [&](int32_t x0, int32_t y0, int32_t x1, int32_t y1) {
        std::string bytes = valid;
        const int32_t v[4] = {x0, y0, x1, y1};
        std::memcpy(&bytes[value_at], v, 16);
        write_bytes(p, bytes);
    };
    with_window(0, 0, -5, 1);
    Error e = expect_error([&] { read_rgb_image(p); });
    EXPECT_EQ(e.field(), "header.dataWindow");
    EXPECT_NE(e.message().find("(0, 0) to (-5, 1)"), std::string::npos) << e.what();
    with_window(-2000000000, 0, 2000000000, 1);
    e = expect_error([&] { read_rgb_image(p); });
    EXPECT_EQ(e.field(), "resolution");
    with_window(0, 0, 3, 1);  // the file's own window reads
    EXPECT_EQ(read_rgb_image(p).width, 4);
}

// A header naming dataWindow twice: OpenEXR keeps the last (983041 x 8 pixels, 1.8 s of line
// buffers under ASan), where the header walk checked the first (fuzz_env_exr timeout,
// corpus/env_exr/regression_duplicate_window.exr). Any attribute named twice is refused.
TEST(FuzzFindings, ExrAttributeNamedTwiceIsRefused) {
    const Error e = expect_error([] {
        read_rgb_image(std::string(FREQLAB_SOURCE_DIR) +
                       "/tests/fuzz/corpus/env_exr/regression_duplicate_window.exr");
    });
    EXPECT_EQ(e.field(), "header.compression");  // the first name seen twice
    EXPECT_NE(e.message().find("appears twice"), std::string::npos) << e.what();
    // Built by hand too: a valid file with its dataWindow attribute repeated.
    const fs::path p = temp_file("twice.exr");
    std::string bytes = small_exr_bytes(p);
    const size_t at = bytes.find("dataWindow");
    ASSERT_NE(at, std::string::npos);
    const size_t length = std::strlen("dataWindow") + 1 + std::strlen("box2i") + 1 + 4 + 16;
    bytes.insert(at, bytes.substr(at, length));
    write_bytes(p, bytes);
    EXPECT_EQ(expect_error([&] { read_rgb_image(p); }).field(), "header.dataWindow");
}

// OpenVDB 10's bloscFromStream reads a value chunk marked uncompressed at the length the file
// declares into a buffer sized for its node, then compares (an ASan-confirmed heap-buffer
// overflow; fuzz_vdb: "double free or corruption" later). The walk follows the tree's topology
// and buffers and refuses such a chunk before OpenVDB reads it.
// A root child at x = 2147483647: OpenVDB offsets it by its node's 4095 in int arithmetic
// (fuzz_vdb, UBSan in openvdb/math/Coord.h). The walk refuses such origins by byte.
TEST(FuzzFindings, VdbRootOriginPastTheInt32RangeIsRefused) {
    const std::string bad = std::string(FREQLAB_SOURCE_DIR) +
                            "/tests/fuzz/corpus/vdb/regression_root_origin_overflow.vdb";
    EXPECT_NE(check_vdb_layout(bad).find("origin at coordinate 2147483647"), std::string::npos)
        << check_vdb_layout(bad);
    const Error e = expect_error([&] { read_vdb_density(bad, "density", "s.json", "media[0]"); });
    EXPECT_EQ(e.field(), "media[0].file");
}

TEST(FuzzFindings, VdbValueChunkLargerThanItsNodeIsRefused) {
    const std::string bad = std::string(FREQLAB_SOURCE_DIR) +
                            "/tests/fuzz/corpus/vdb/regression_uncompressed_chunk.vdb";
    EXPECT_NE(check_vdb_layout(bad).find(
                  "an uncompressed value chunk declares 4294967296 bytes where its node holds 24"),
              std::string::npos)
        << check_vdb_layout(bad);
    const Error e = expect_error([&] { read_vdb_density(bad, "density", "s.json", "media[0]"); });
    EXPECT_EQ(e.field(), "media[0].file");
}

// The walk's model of the format against what OpenVDB writes: every compression (none, zip,
// blosc, with and without the active mask), half floats, tiles, several grids and a vec3s
// grid beside the density. The walk ends each grid's topology exactly at its block offset and
// its buffers exactly at its end offset, or refuses the file.
TEST(FuzzFindings, VdbLayoutWalkAcceptsWhatOpenVdbWrites) {
    openvdb::initialize();
    int files = 0;
    for (uint32_t compression : {0u, 1u, 2u, 3u, 4u, 6u})
        for (bool half : {false, true}) {
            auto density = openvdb::FloatGrid::create(0.0f);
            density->setName("density");
            density->setSaveFloatAsHalf(half);
            auto acc = density->getAccessor();
            for (int z = 0; z < 20; ++z)
                for (int y = 0; y < 12; ++y)
                    for (int x = 0; x < 9; ++x) acc.setValue(openvdb::Coord(x, y, z), 0.1f * x);
            density->fill(openvdb::CoordBBox(openvdb::Coord(64), openvdb::Coord(255)), 2.0f);
            // 600 leaves apart: the delayed-load metadata's per-leaf arrays get long enough for
            // OpenVDB to compress them.
            for (int i = 0; i < 600; ++i)
                acc.setValue(openvdb::Coord(300 + (i % 20) * 8, (i / 20 % 10) * 8, (i / 200) * 8),
                             0.01f * float(i % 7));
            acc.setValueOff(openvdb::Coord(3, 3, 3), 0.5f);  // an inactive non-background value
            auto velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
            velocity->setName("velocity");
            velocity->getAccessor().setValue(openvdb::Coord(1, 2, 3), openvdb::Vec3s(1, 2, 3));
            const fs::path p = temp_file("variant.vdb");
            openvdb::io::File out(p.string());
            out.setCompression(compression);
            openvdb::MetaMap file_metadata;  // file-level metadata too
            file_metadata.insertMeta("creator", openvdb::StringMetadata("freqlab test"));
            file_metadata.insertMeta("frame", openvdb::Int32Metadata(7));
            out.write({velocity, density}, file_metadata);
            out.close();
            EXPECT_EQ(check_vdb_layout(p.string()), "")
                << "compression " << compression << " half " << half;
            ++files;
        }
    EXPECT_EQ(files, 12);
}

// c-blosc decodes a damaged chunk's internal block offsets unchecked (fuzz_vdb: a SEGV inside
// libblosc); the walk asks blosc_cbuffer_validate first.
TEST(FuzzFindings, DamagedBloscChunkIsRefusedBeforeDecoding) {
    const std::string bad =
        std::string(FREQLAB_SOURCE_DIR) + "/tests/fuzz/corpus/vdb/regression_blosc_damaged.vdb";
    EXPECT_NE(check_vdb_layout(bad).find("a blosc value chunk is damaged"), std::string::npos)
        << check_vdb_layout(bad);
    const Error e = expect_error([&] { read_vdb_density(bad, "density", "s.json", "media[0]"); });
    EXPECT_EQ(e.field(), "media[0].file");
}
