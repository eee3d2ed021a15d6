// A scene parsed from JSON text with its media and rays at t = 0: what method B's baker tests
// start from.
#pragma once

#include <memory>
#include <string>

#include "accel/ray_scene.h"
#include "scene/scene_loader.h"
#include "volume/media.h"

namespace freqlab::test_support {

struct BakeFixture {
    Scene scene;
    Media media;
    EmbreeDevice device{2};
    std::unique_ptr<RayScene> rays;
    explicit BakeFixture(const std::string& text) : scene(parse_scene(text, "test.json", "")) {
        media = Media(scene.media);
        rays = std::make_unique<RayScene>(scene, device);
        rays->update(0.0f);
    }
};

}  // namespace freqlab::test_support
