#include "session/session_file.h"

#include <algorithm>

#include "base/error.h"
#include "render/frame_renderer.h"
#include "render/method.h"
#include "scene/json_reader.h"
#include "scene/scene.h"
#include "settings/settings_group.h"
#include "volume/bake_estimators.h"

namespace freqlab {

namespace {

BakeSessionFile read_bake_part(const JsonReader& r) {
    r.only_keys({"settings", "media", "camera", "probe_lobes"});
    BakeSessionFile f;
    SettingsGroup group;
    group.bind(BakeSettings::schema(), &f.settings);
    if (r.has("settings"))
        group.from_json(r.get("settings").raw(), r.file(), r.path() + ".settings");
    if (r.has("media")) {
        const JsonReader media = r.get("media");
        for (size_t i = 0; i < media.array_size(); ++i) {
            const JsonReader m = media.at(i);
            m.only_keys({"name", "sigma_s", "sigma_a", "g", "density_scale"});
            // The scene format's ranges (medium_desc.cpp).
            f.media.push_back({m.get("name").string(), m.get("sigma_s").number_in(0.0, 1e6),
                               m.get("sigma_a").number_in(0.0, 1e6),
                               m.get("g").number_in(-1.0, 1.0, true, true),
                               m.get("density_scale").number_in(0.0, 1e6)});
        }
    }
    if (r.has("camera")) {
        const JsonReader c = r.get("camera");
        c.only_keys({"yaw", "pitch", "zoom"});
        f.yaw = float(c.get("yaw").number_in(-180.0, 180.0));
        f.pitch = float(c.get("pitch").number_in(-60.0, 60.0));
        f.zoom = float(c.get("zoom").number_in(0.3, 4.0));
    }
    if (r.has("probe_lobes")) f.show_lobes = r.get("probe_lobes").boolean();
    return f;
}

void check_method(const JsonReader& method, const std::string& name) {
    const std::vector<std::string> names = render_method_names();
    if (is_bake_method(name) || std::find(names.begin(), names.end(), name) != names.end()) return;
    std::string list;
    for (const std::string& m : names) list += m + ", ";
    method.fail("expected one of " + list + bake_method_list(", "));
}

}  // namespace

SessionFile read_session_file(const std::string& text, const std::string& file) {
    const nlohmann::json doc = JsonReader::parse(text, file);
    const JsonReader r(doc, file, "");
    r.only_keys({"freqlab_session", "scene", "method", "frame", "layer", "overlay_on_color",
                 "overlay_opacity", "fixed_range", "range", "zoom", "centre", "inspect", "insets",
                 "settings", "bake"});
    if (r.get("freqlab_session").integer_in(1, 1) != 1) r.fail("unsupported session version");
    SessionFile s;
    s.file = file;
    s.scene = r.get("scene").string();
    const JsonReader method = r.get("method");
    s.method = method.string();
    check_method(method, s.method);
    s.bake_method = is_bake_method(s.method);
    s.frame = r.get("frame").integer_in(0, 1 << 30);
    s.layer = r.get("layer").string();
    s.settings = r.get("settings").raw();
    RenderConfig probe;  // checks every setting; the workbench applies them to its own
    probe.settings_group().from_json(s.settings, file, "settings");
    s.overlay_on_color = r.get("overlay_on_color").boolean();
    s.overlay_opacity = float(r.get("overlay_opacity").number_in(0, 1));
    s.fixed_range = r.get("fixed_range").boolean();
    const JsonReader range = r.get("range");
    if (range.array_size() != 2) range.fail("expected [lo, hi]");
    s.range_lo = float(range.at(0).number_in(-1e30, 1e30));
    s.range_hi = float(range.at(1).number_in(-1e30, 1e30));
    s.zoom = float(r.get("zoom").number_in(1, 64));
    const JsonReader centre = r.get("centre");
    if (centre.array_size() != 2) centre.fail("expected [x, y] in [0, 1]");
    s.centre_x = float(centre.at(0).number_in(0, 1));
    s.centre_y = float(centre.at(1).number_in(0, 1));
    const JsonReader inspect = r.get("inspect");
    if (inspect.array_size() != 2) inspect.fail("expected [x, y] (-1: none)");
    s.pick_x = inspect.at(0).integer_in(-1, 1 << 20);
    s.pick_y = inspect.at(1).integer_in(-1, 1 << 20);
    const JsonReader insets = r.get("insets");
    if (insets.array_size() > 4) insets.fail("expected at most 4 insets");
    for (size_t i = 0; i < insets.array_size(); ++i) {
        const JsonReader in = insets.at(i);
        if (in.array_size() != 4) in.fail("expected [x, y, width, height]");
        s.insets.push_back({in.at(0).integer_in(0, 1 << 20), in.at(1).integer_in(0, 1 << 20),
                            in.at(2).integer_in(2, 1 << 20), in.at(3).integer_in(2, 1 << 20)});
    }
    if (r.has("bake")) {
        if (!s.bake_method) r.get("bake").fail("a bake part needs a bake method");
        s.bake = read_bake_part(r.get("bake"));
    }
    return s;
}

void check_session_media(const SessionFile& session, const Scene& scene) {
    if (!session.bake || session.bake->media.empty()) return;
    const auto& media = session.bake->media;
    if (media.size() != scene.media.size())
        throw Error(session.file, "bake.media",
                    "expected " + std::to_string(scene.media.size()) +
                        " media (the scene's), in the scene's order; got " +
                        std::to_string(media.size()));
    for (size_t i = 0; i < media.size(); ++i)
        if (media[i].name != scene.media[i].name)
            throw Error(session.file, "bake.media[" + std::to_string(i) + "].name",
                        "expected \"" + scene.media[i].name + "\", the scene's medium " +
                            std::to_string(i) + "; got \"" + media[i].name + "\"");
}

namespace {

nlohmann::json bake_session_json(const BakeSessionFile& bake) {
    BakeSettings settings = bake.settings;
    SettingsGroup group;
    group.bind(BakeSettings::schema(), &settings);
    nlohmann::json media = nlohmann::json::array();
    for (const BakeSessionFile::Coefficients& m : bake.media)
        media.push_back({{"name", m.name},
                         {"sigma_s", m.sigma_s},
                         {"sigma_a", m.sigma_a},
                         {"g", m.g},
                         {"density_scale", m.density_scale}});
    return {{"settings", group.to_json()},
            {"media", media},
            {"camera", {{"yaw", bake.yaw}, {"pitch", bake.pitch}, {"zoom", bake.zoom}}},
            {"probe_lobes", bake.show_lobes}};
}

}  // namespace

nlohmann::json session_json(const SessionFile& s) {
    nlohmann::json insets = nlohmann::json::array();
    for (const SessionFile::Inset& in : s.insets)
        insets.push_back({in.x, in.y, in.width, in.height});
    nlohmann::json j = {{"freqlab_session", 1},
                        {"scene", s.scene},
                        {"method", s.method},
                        {"frame", s.frame},
                        {"layer", s.layer},
                        {"overlay_on_color", s.overlay_on_color},
                        {"overlay_opacity", s.overlay_opacity},
                        {"fixed_range", s.fixed_range},
                        {"range", {s.range_lo, s.range_hi}},
                        {"zoom", s.zoom},
                        {"centre", {s.centre_x, s.centre_y}},
                        {"inspect", {s.pick_x, s.pick_y}},
                        {"insets", insets},
                        {"settings", s.settings}};
    if (s.bake) j["bake"] = bake_session_json(*s.bake);
    return j;
}

}  // namespace freqlab
