// The settings mechanism: defaults, JSON round trip, --set parsing and its errors.
#include <gtest/gtest.h>

#include "base/error.h"
#include "render/frame_renderer.h"
#include "settings/bake_settings.h"
#include "settings/render_settings.h"
#include "settings/settings_group.h"

using namespace freqlab;

TEST(Settings, SchemaDefaultsAreTheStructInitialisers) {
    FrameSettings f;
    f.width = 3;
    FrameSettings::schema().reset(&f);
    EXPECT_EQ(f.width, FrameSettings{}.width);
    for (const SettingField& field : FrameSettings::schema().fields()) {
        EXPECT_GE(field.default_value, field.min) << field.key;
        EXPECT_LE(field.default_value, field.max) << field.key;
        EXPECT_FALSE(field.tooltip.empty()) << field.key;
    }
}

TEST(Settings, JsonRoundTrip) {
    RenderConfig a;
    a.frame.width = 123;
    a.frame.exposure = -1.5f;
    a.gbuffer.aa_samples = 9;
    const nlohmann::json j = a.settings_group().to_json();
    RenderConfig b;
    b.settings_group().from_json(j, "session.json", "settings");
    EXPECT_EQ(b.frame.width, 123);
    EXPECT_FLOAT_EQ(b.frame.exposure, -1.5f);
    EXPECT_EQ(b.gbuffer.aa_samples, 9);
    EXPECT_EQ(b.settings_group().to_json(), j);  // JSON -> struct -> JSON is the identity
}

TEST(Settings, SetParsesAndReportsInvalidation) {
    RenderConfig c;
    SettingsGroup g = c.settings_group();
    EXPECT_EQ(g.apply_assignment("frame.width=320"), uint32_t(kInvalidatesGBuffer));
    EXPECT_EQ(g.apply_assignment("frame.exposure=2.5"), uint32_t(kInvalidatesDisplay));
    g.apply_assignment("gbuffer.aa_samples=16");
    EXPECT_EQ(c.frame.width, 320);
    EXPECT_FLOAT_EQ(c.frame.exposure, 2.5f);
    EXPECT_EQ(c.gbuffer.aa_samples, 16);
}

TEST(Settings, UnknownKeyListsValidKeys) {
    RenderConfig c;
    SettingsGroup g = c.settings_group();
    try {
        g.apply_assignment("frame.widht=3");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "frame.widht");
        EXPECT_NE(std::string(e.what()).find("frame.width, frame.height"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("gbuffer.aa_samples"), std::string::npos);
    }
}

TEST(Settings, RejectsBadValues) {
    RenderConfig c;
    SettingsGroup g = c.settings_group();
    EXPECT_THROW(g.apply_assignment("frame.width=0"), Error);       // below range
    EXPECT_THROW(g.apply_assignment("frame.width=12.5"), Error);    // not integral
    EXPECT_THROW(g.apply_assignment("frame.width=12px"), Error);    // trailing junk
    EXPECT_THROW(g.apply_assignment("frame.exposure=nan"), Error);  // not finite
    EXPECT_THROW(g.apply_assignment("frame.width"), Error);         // no '='
    EXPECT_EQ(c.frame.width, FrameSettings{}.width);                // untouched by failures
}

TEST(Settings, JsonErrorsNameThePath) {
    RenderConfig c;
    try {
        c.settings_group().from_json({{"frame", {{"width", "wide"}}}}, "session.json", "settings");
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.file(), "session.json");
        EXPECT_EQ(e.field(), "settings.frame.width");
    }
    EXPECT_THROW(c.settings_group().from_json({{"nosuch", {}}}, "s.json", "settings"), Error);
}

// bake.quality is a preset: choosing it writes spp, bounces and texel_density; a later --set of
// one of them wins, and in a JSON object the preset is applied before the fields beside it
// whatever the key order.
TEST(Settings, QualityPresetWritesItsFieldsAndExplicitValuesWin) {
    const SettingsSchema& schema = BakeSettings::schema();
    BakeSettings b;
    schema.set_from_string(&b, "quality", "high", "test");
    EXPECT_EQ(b.quality, BakeQuality::High);
    EXPECT_EQ(b.spp, 128);
    EXPECT_EQ(b.bounces, 4);
    EXPECT_FLOAT_EQ(b.texel_density, 8.0f);
    schema.set_from_string(&b, "spp", "20", "test");
    EXPECT_EQ(b.spp, 20);
    schema.set_from_string(&b, "quality", "low", "test");
    EXPECT_EQ(b.spp, 16);
    EXPECT_EQ(b.bounces, 2);
    EXPECT_FLOAT_EQ(b.texel_density, 4.0f);
    // "spp" sorts before "quality": the preset still goes first.
    BakeSettings j;
    schema.from_json(&j, nlohmann::json{{"spp", 20}, {"quality", "high"}}, "s.json", "bake");
    EXPECT_EQ(j.spp, 20);
    EXPECT_EQ(j.bounces, 4);
    // custom writes nothing; the saved JSON reloads to the same values.
    BakeSettings c = j;
    schema.set_from_string(&c, "quality", "custom", "test");
    EXPECT_EQ(c.spp, 20);
    EXPECT_EQ(c.bounces, 4);
    BakeSettings reloaded;
    schema.from_json(&reloaded, schema.to_json(&j), "s.json", "bake");
    EXPECT_EQ(schema.to_json(&reloaded), schema.to_json(&j));
}
