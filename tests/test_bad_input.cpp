// Bad input: each case must throw freqlab::Error whose message names the file and the field.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "base/error.h"
#include "image/image_io.h"
#include "scene/scene_loader.h"

using namespace freqlab;
namespace fs = std::filesystem;

namespace {

const char* kCamera = R"("camera": {"position": [0, -5, 1], "look_at": [0, 0, 0]})";

std::string scene_with(const std::string& objects, const std::string& extra = "") {
    return std::string("{") + kCamera + ", \"objects\": " + objects + extra + "}";
}

// Parses `text` expecting an Error whose field contains `field` and message contains `expect`.
void expect_error(const std::string& text, const std::string& field, const std::string& expect) {
    try {
        parse_scene(text, "bad.json", "");
        FAIL() << "no error for: " << text;
    } catch (const Error& e) {
        EXPECT_EQ(e.file(), "bad.json");
        EXPECT_NE(e.field().find(field), std::string::npos) << "field was: " << e.field();
        EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << e.what();
    }
}

const std::string kPlane = R"({"shape": {"type": "plane"}, "material": {"type": "lambert"}})";

}  // namespace

TEST(BadInput, MalformedJsonNamesLineAndColumn) {
    expect_error("{\n  \"camera\": {,\n}", "line 2, column", "malformed JSON");
}

TEST(BadInput, UnknownTopLevelKey) {
    expect_error(scene_with("[" + kPlane + "]", ", \"objcts\": []"), "objcts", "unknown field");
}

TEST(BadInput, RoughnessWrongType) {
    expect_error(
        scene_with(
            "[" + kPlane +
            R"(, {"shape": {"type": "sphere"}, "material": {"type": "ggx", "roughness": "abc"}}])"),
        "objects[1].material.roughness", "expected a number in (0, 1]");
}

TEST(BadInput, RoughnessOutOfRange) {
    expect_error(
        scene_with(
            R"([{"shape": {"type": "sphere"}, "material": {"type": "beckmann", "roughness": 0}}])"),
        "objects[0].material.roughness", "(0, 1]");
}

TEST(BadInput, UnknownMaterialType) {
    expect_error(scene_with(R"([{"shape": {"type": "sphere"}, "material": {"type": "velvet"}}])"),
                 "objects[0].material.type", "expected one of lambert, phong");
}

TEST(BadInput, UnknownMaterialName) {
    expect_error(scene_with(R"([{"shape": {"type": "sphere"}, "material": "gold"}])"),
                 "objects[0].material", "unknown material \"gold\"");
}

TEST(BadInput, ZeroLengthLookAt) {
    expect_error(
        R"({"camera": {"position": [1, 2, 3], "look_at": [1, 2, 3]}, "objects": [)" + kPlane + "]}",
        "camera.look_at", "zero-length view direction");
}

TEST(BadInput, UpParallelToView) {
    expect_error(
        R"({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0]}, "objects": [)" + kPlane + "]}",
        "camera.up", "parallel");
}

TEST(BadInput, MissingCamera) {
    expect_error("{\"objects\": [" + kPlane + "]}", "camera", "missing required field");
}

TEST(BadInput, ObjectsNotAnArray) {
    expect_error(scene_with("{}"), "objects", "array");
}

TEST(BadInput, Vector3WrongLength) {
    expect_error(
        scene_with(
            R"([{"shape": {"type": "box"}, "material": {"type": "lambert"}, "transform": {"translate": [1, 2]}}])"),
        "objects[0].transform.translate", "3 numbers");
}

TEST(BadInput, NegativeColour) {
    expect_error(
        scene_with(
            R"([{"shape": {"type": "box"}, "material": {"type": "lambert", "albedo": [0.5, -1, 0]}}])"),
        "objects[0].material.albedo", "non-negative");
}

TEST(BadInput, ZeroRotationAxis) {
    expect_error(
        scene_with(
            R"([{"shape": {"type": "box"}, "material": {"type": "lambert"}, "transform": {"rotate": {"axis": [0, 0, 0], "deg": 10}}}])"),
        "objects[0].transform.rotate.axis", "non-zero direction");
}

TEST(BadInput, KeyframesOutOfOrder) {
    expect_error(scene_with(R"([{"shape": {"type": "box"}, "material": {"type": "lambert"},
        "animation": {"keyframes": [{"t": 1}, {"t": 0.5}]}}])"),
                 "objects[0].animation.keyframes[1].t", "increasing order");
}

TEST(BadInput, MissingMeshFileNamesThePackage) {
    expect_error(
        scene_with(R"([{"mesh": "PLY/NoSuchModel.ply", "material": {"type": "lambert"}}])"),
        "objects[0].mesh", "assimp-testmodels");
}

TEST(BadInput, MissingEnvMapNamesThePackage) {
    expect_error(
        scene_with("[" + kPlane + "]",
                   R"(, "lights": [{"type": "envmap", "file": "studiolights/world/nowhere.exr"}])"),
        "lights[0].file", "blender-data");
}

TEST(BadInput, ShapeAndMeshBoth) {
    expect_error(
        scene_with(
            R"([{"shape": {"type": "box"}, "mesh": "x.obj", "material": {"type": "lambert"}}])"),
        "objects[0]", "exactly one of");
}

TEST(BadInput, DegenerateOnlyProceduralMesh) {
    expect_error(
        scene_with(
            R"([{"shape": {"type": "box", "size": [1, 0, 1]}, "material": {"type": "lambert"}}])"),
        "objects[0].shape.size", "positive");
}

TEST(BadInput, QuadWithoutArea) {
    expect_error(
        scene_with(
            "[" + kPlane + "]",
            R"(, "lights": [{"type": "quad", "corner": [0,0,2], "edge_u": [1,0,0], "edge_v": [2,0,0], "radiance": 5}])"),
        "lights[0].edge_v", "no area");
}

TEST(BadInput, TwoEnvironments) {
    expect_error(
        scene_with("[" + kPlane + "]", R"(, "lights": [{"type": "sky"}, {"type": "sky"}])"),
        "lights[1]", "only one environment");
}

TEST(BadInput, MediaCoefficients) {
    expect_error(scene_with("[" + kPlane + "]", R"(, "media": [{"sigma_s": -1}])"),
                 "media[0].sigma_s", "expected");
    expect_error(scene_with("[" + kPlane + "]", R"(, "media": [{"sigma_s": 1, "g": 1}])"),
                 "media[0].g", "expected");
    expect_error(scene_with("[" + kPlane + "]",
                            R"(, "media": [{"sigma_s": 1, "density": {"source": "vdb",
                                "file": "absent.vdb"}}])"),
                 "media[0].density.file", "does not exist");
}

TEST(BadInput, PhongWithoutExponent) {
    expect_error(scene_with(R"([{"shape": {"type": "box"}, "material": {"type": "phong"}}])"),
                 "objects[0].material.exponent", "missing required field");
}

TEST(BadInput, MissingSceneFile) {
    try {
        load_scene("/nonexistent/scene.json");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.file(), "/nonexistent/scene.json");
        EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
    }
}

TEST(BadInput, EmptyMeshFile) {
    const fs::path dir = fs::temp_directory_path() / "freqlab_bad_mesh";
    fs::create_directories(dir);
    std::ofstream(dir / "empty.obj") << "# nothing\nv 0 0 0\nv 1 0 0\n";
    std::ofstream(dir / "scene.json")
        << scene_with(R"([{"mesh": "empty.obj", "material": {"type": "lambert"}}])");
    try {
        load_scene((dir / "scene.json").string());
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "objects[0].mesh");
        EXPECT_NE(std::string(e.what()).find("expected a mesh file with at least one triangle"),
                  std::string::npos)
            << e.what();
    }
}

TEST(BadInput, DegenerateOnlyMeshFile) {
    const fs::path dir = fs::temp_directory_path() / "freqlab_bad_mesh";
    fs::create_directories(dir);
    std::ofstream(dir / "flat.obj") << "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";
    std::ofstream(dir / "scene2.json")
        << scene_with(R"([{"mesh": "flat.obj", "material": {"type": "lambert"}}])");
    try {
        load_scene((dir / "scene2.json").string());
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "objects[0].mesh");
        EXPECT_NE(std::string(e.what()).find("no usable triangles"), std::string::npos) << e.what();
    }
}

TEST(BadInput, NanFilledEnvMap) {
    const fs::path dir = fs::temp_directory_path() / "freqlab_bad_env";
    fs::create_directories(dir);
    LayerSet set(4, 2);
    Layer& c = set.add("color", LayerKind::Color, 3);
    c.data[7] = NAN;  // pixel (2, 0), channel G
    write_exr(dir / "nan.exr", set);
    std::ofstream(dir / "scene.json")
        << scene_with("[" + kPlane + "]", R"(, "lights": [{"type": "envmap", "file": "nan.exr"}])");
    try {
        load_scene((dir / "scene.json").string());
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "lights[0].file");
        EXPECT_NE(std::string(e.what()).find("pixel (2, 0)"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("non-finite"), std::string::npos) << e.what();
    }
}

TEST(BadInput, UnreadableExr) {
    const fs::path p = fs::temp_directory_path() / "freqlab_not_an.exr";
    std::ofstream(p) << "this is not an EXR";
    try {
        read_exr(p);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.file(), p.string());
        EXPECT_NE(std::string(e.what()).find("cannot read image"), std::string::npos) << e.what();
    }
}

// A full disk (issue "Reliability": "could not write EXR:" with no reason): the error names the
// file and says why, and no temporary file is left. Needs a 48 kB tmpfs (root); skipped without.
TEST(BadInput, FullDiskNamesTheFileAndTheReason) {
    const fs::path dir = fs::temp_directory_path() / "freqlab_full_disk";
    fs::create_directories(dir);
    if (std::system(("mount -t tmpfs -o size=48k tmpfs " + dir.string() + " 2>/dev/null").c_str()))
        GTEST_SKIP() << "cannot mount a small tmpfs here (not root?)";
    LayerSet layers(160, 90);
    Layer& color = layers.add("color", LayerKind::Color, 3);
    uint32_t state = 12345;  // noise: 170 kB of floats that zip cannot shrink below 48 kB
    for (float& v : color.data) v = float(state = state * 1664525u + 1013904223u) * 2.3e-10f;
    std::string what;
    try {
        write_exr(dir / "frame.exr", layers);
    } catch (const Error& e) {
        what = e.what();
        EXPECT_EQ(e.file(), (dir / "frame.exr").string());
    }
    size_t left = 0;
    for (const auto& entry : fs::directory_iterator(dir)) left += entry.is_regular_file();
    EXPECT_EQ(std::system(("umount " + dir.string()).c_str()), 0);
    EXPECT_NE(what.find("no space left on the device"), std::string::npos) << what;
    EXPECT_EQ(left, 0u);  // neither the file nor its temporary sibling
}
