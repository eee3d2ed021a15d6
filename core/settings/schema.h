// The one description of a settings struct (DESIGN.md "Settings"): each field's key,
// default, range, unit, tooltip and what a change invalidates. JSON load/save, the CLI's
// `--set key=value`, the stats output and (later) the GUI's panels all read this table, so a
// parameter is declared exactly once (compare Mitsuba's traverse()).
//
// Values are carried as double for every field type; ints, bools and choices are checked to be
// integral and in range when set.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace freqlab {

// What has to be recomputed after a change (bit flags).
enum Invalidates : uint32_t {
    kInvalidatesNothing = 0,
    kInvalidatesDisplay = 1u << 0,  // only the colormap / tonemap of what is shown
    kInvalidatesGBuffer = 1u << 1,  // primary rays
    kInvalidatesShading = 1u << 2,  // radiance estimates of the current frame
    kInvalidatesCache = 1u << 3,    // method A's cache across frames
    kInvalidatesTables = 1u << 4,   // method B's impulse-response tables
    kInvalidatesBake = 1u << 5,     // method B's lightmaps / probes
};
std::string invalidates_to_string(uint32_t flags);

enum class SettingType { Bool, Int, Float, Choice };

struct SettingField {
    std::string key;  // e.g. "spp"; the schema's prefix makes it "frame.spp"
    SettingType type = SettingType::Float;
    double default_value = 0;
    double min = 0, max = 0;  // inclusive range (Bool/Choice: implied)
    std::string unit;         // "", "px", "samples", "EV", "deg", ...
    std::string tooltip;
    uint32_t invalidates = kInvalidatesNothing;
    std::vector<std::string> choices;  // Choice: the names of values 0..n-1
    std::function<double(const void*)> get;
    std::function<void(void*, double)> set;
    // A preset (SchemaBuilder::preset): setting it writes other fields, so a JSON object
    // applies it before them and their own values there win.
    bool is_preset = false;
};

class SettingsSchema {
  public:
    SettingsSchema(std::string prefix, std::string title) : prefix_(prefix), title_(title) {}

    const std::string& prefix() const { return prefix_; }
    const std::string& title() const { return title_; }
    const std::vector<SettingField>& fields() const { return fields_; }
    const SettingField* find(const std::string& key) const;  // key without the prefix

    nlohmann::json to_json(const void* object) const;
    // Reads the keys present in `j`; unknown keys, wrong types and out-of-range values throw
    // Error(file, json_path + "." + key, expectation).
    void from_json(void* object, const nlohmann::json& j, const std::string& file,
                   const std::string& json_path) const;
    // `value` as typed on a command line: numbers, true/false/on/off, or a choice name.
    // Returns the invalidation flags of the field.
    uint32_t set_from_string(void* object, const std::string& key, const std::string& value,
                             const std::string& origin) const;
    void reset(void* object) const;
    // Validates and stores `v` (throws Error naming origin and key when out of range).
    void set_value(void* object, const SettingField& f, double v, const std::string& origin,
                   const std::string& where) const;
    std::string keys_list() const;  // "prefix.a, prefix.b" for error messages
    std::string describe_range(const SettingField& f) const;

  protected:
    std::string prefix_, title_;
    std::vector<SettingField> fields_;
};

// Builds a schema for struct S from member pointers.
template <class S>
class SchemaBuilder {
  public:
    SchemaBuilder(std::string prefix, std::string title) : schema_(prefix, title) {}

    template <class T>
    SchemaBuilder& field(T S::*member, const std::string& key, double min, double max,
                         const std::string& unit, uint32_t invalidates,
                         const std::string& tooltip) {
        const T default_value = S{}.*member;  // the struct's initialiser is the default
        SettingField f;
        f.key = key;
        f.type = std::is_same<T, bool>::value       ? SettingType::Bool
                 : std::is_floating_point<T>::value ? SettingType::Float
                                                    : SettingType::Int;
        f.default_value = double(default_value);
        f.min = f.type == SettingType::Bool ? 0 : min;
        f.max = f.type == SettingType::Bool ? 1 : max;
        f.unit = unit;
        f.invalidates = invalidates;
        f.tooltip = tooltip;
        f.get = [member](const void* o) { return double(static_cast<const S*>(o)->*member); };
        f.set = [member](void* o, double v) { static_cast<S*>(o)->*member = static_cast<T>(v); };
        add(std::move(f));
        return *this;
    }

    // An enum (or int) field whose values are named.
    template <class E>
    SchemaBuilder& choice(E S::*member, const std::string& key, std::vector<std::string> names,
                          uint32_t invalidates, const std::string& tooltip) {
        const E default_value = S{}.*member;
        SettingField f;
        f.key = key;
        f.type = SettingType::Choice;
        f.default_value = double(int(default_value));
        f.min = 0;
        f.max = double(names.size() - 1);
        f.choices = std::move(names);
        f.invalidates = invalidates;
        f.tooltip = tooltip;
        f.get = [member](const void* o) { return double(int(static_cast<const S*>(o)->*member)); };
        f.set = [member](void* o, double v) { static_cast<S*>(o)->*member = E(int(v)); };
        add(std::move(f));
        return *this;
    }

    // A named preset of fields declared before it: choosing names[i] stores i in `member` and
    // writes values[i] ({key, value} of those fields; an empty list writes nothing). The
    // tooltip lists what each name sets.
    template <class E>
    SchemaBuilder& preset(E S::*member, const std::string& key, std::vector<std::string> names,
                          const std::vector<std::vector<std::pair<std::string, double>>>& values,
                          uint32_t invalidates, const std::string& tooltip) {
        std::vector<std::vector<std::function<void(void*)>>> writes(names.size());
        std::string listing;
        for (size_t i = 0; i < names.size() && i < values.size(); ++i) {
            std::string line;
            for (const auto& [k, v] : values[i]) {
                const SettingField* other = schema_.find(k);
                if (!other) throw std::logic_error("preset " + key + ": no field " + k);
                auto set = other->set;
                writes[i].push_back([set, v = v](void* o) { set(o, v); });
                char buf[64];
                // A choice's value by its name (its index is what the preset stores).
                const size_t index = size_t(std::max(0.0, v));
                if (other->type == SettingType::Choice && index < other->choices.size())
                    std::snprintf(buf, sizeof buf, "%s%s %s", line.empty() ? "" : ", ", k.c_str(),
                                  other->choices[index].c_str());
                else
                    std::snprintf(buf, sizeof buf, "%s%s %g", line.empty() ? "" : ", ", k.c_str(),
                                  v);
                line += buf;
            }
            if (!line.empty()) listing += "\n" + names[i] + ": " + line;
        }
        choice(member, key, std::move(names), invalidates, tooltip + listing);
        SettingField& f = static_cast<Access&>(schema_).fields_.back();
        f.is_preset = true;
        f.set = [member, writes](void* o, double v) {
            static_cast<S*>(o)->*member = E(int(v));
            for (const auto& w : writes[size_t(int(v))]) w(o);
        };
        return *this;
    }

    SettingsSchema build() { return std::move(schema_); }

  private:
    struct Access : SettingsSchema {
        using SettingsSchema::fields_;
    };
    void add(SettingField f) { static_cast<Access&>(schema_).fields_.push_back(std::move(f)); }
    SettingsSchema schema_;
};

}  // namespace freqlab
