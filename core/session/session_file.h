// The workbench's session file (File > Save / Load session, `freqlab gui --session F`): scene,
// method, frame, view and every setting, read and checked here in core so that a bad file is
// refused before anything in the workbench changes (the UI only applies a SessionFile), and
// so that the fuzzers reach the reader without a GL context (issue "Reliability").
//
// | field            | meaning                                       | accepted                  |
// |------------------|-----------------------------------------------|---------------------------|
// | freqlab_session  | format version                                | 1                         |
// | scene, method    | scene file, render or bake method name        | method: a registered name |
// | frame, layer     | the viewed frame and layer                    | frame in [0, 2^30]        |
// | overlay_*, range, zoom, centre, inspect, insets | the viewport | finite, in the UI's ranges |
// | settings         | every render setting (settings/schema.h)      | the schemas' ranges       |
// | bake             | bake settings, media coefficients, preview    | scene format's ranges     |
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "settings/bake_settings.h"

namespace freqlab {

struct Scene;

// A bake's part of a session file: bake settings, every medium's coefficients (by the
// scene's order and name), the preview camera and the probe-lobes toggle.
struct BakeSessionFile {
    BakeSettings settings;
    struct Coefficients {
        std::string name;
        double sigma_s, sigma_a, g, density_scale;
    };
    std::vector<Coefficients> media;  // empty: the scene's own
    float yaw = 0.0f, pitch = 0.0f, zoom = 1.0f;
    bool show_lobes = true;
};

struct SessionFile {
    std::string file;  // where it was read from (for messages)
    std::string scene, method;
    bool bake_method = false;
    int frame = 0;
    std::string layer;
    bool overlay_on_color = false, fixed_range = false;
    float overlay_opacity = 1.0f;
    float range_lo = 0.0f, range_hi = 1.0f;
    float zoom = 1.0f, centre_x = 0.5f, centre_y = 0.5f;
    int pick_x = -1, pick_y = -1;
    struct Inset {
        int x, y, width, height;
    };
    std::vector<Inset> insets;  // at most 4
    nlohmann::json settings;    // checked against every render schema; apply with from_json
    std::optional<BakeSessionFile> bake;  // only for a bake method
};

// Parses and checks all of `text`; throws Error naming `file` and the field.
SessionFile read_session_file(const std::string& text, const std::string& file);
// The bake part's media against the scene's (count, order, names); throws Error naming the
// session file and field.
void check_session_media(const SessionFile& session, const Scene& scene);
// The file as the workbench writes it (read_session_file reads it back).
nlohmann::json session_json(const SessionFile& session);

}  // namespace freqlab
