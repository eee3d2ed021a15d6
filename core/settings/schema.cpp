#include "settings/schema.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "base/error.h"

namespace freqlab {

using nlohmann::json;

std::string invalidates_to_string(uint32_t flags) {
    static const std::pair<uint32_t, const char*> names[] = {
        {kInvalidatesDisplay, "display"}, {kInvalidatesGBuffer, "gbuffer"},
        {kInvalidatesShading, "shading"}, {kInvalidatesCache, "cache"},
        {kInvalidatesTables, "tables"},   {kInvalidatesBake, "bake"}};
    std::string s;
    for (const auto& [bit, name] : names)
        if (flags & bit) s += (s.empty() ? "" : "|") + std::string(name);
    return s.empty() ? "nothing" : s;
}

const SettingField* SettingsSchema::find(const std::string& key) const {
    for (const SettingField& f : fields_)
        if (f.key == key) return &f;
    return nullptr;
}

std::string SettingsSchema::keys_list() const {
    std::string s;
    for (const SettingField& f : fields_) s += (s.empty() ? "" : ", ") + prefix_ + "." + f.key;
    return s;
}

std::string SettingsSchema::describe_range(const SettingField& f) const {
    std::ostringstream ss;
    switch (f.type) {
        case SettingType::Bool:
            return "true or false";
        case SettingType::Choice: {
            ss << "one of";
            for (size_t i = 0; i < f.choices.size(); ++i) ss << (i ? ", " : " ") << f.choices[i];
            return ss.str();
        }
        case SettingType::Int:
            ss << "an integer in [" << (long long)f.min << ", " << (long long)f.max << "]";
            break;
        case SettingType::Float:
            ss << "a number in [" << f.min << ", " << f.max << "]";
            break;
    }
    if (!f.unit.empty()) ss << " " << f.unit;
    return ss.str();
}

json SettingsSchema::to_json(const void* object) const {
    json j = json::object();
    for (const SettingField& f : fields_) {
        const double v = f.get(object);
        switch (f.type) {
            case SettingType::Bool:
                j[f.key] = v != 0;
                break;
            case SettingType::Int:
                j[f.key] = (long long)v;
                break;
            case SettingType::Float:
                j[f.key] = v;
                break;
            case SettingType::Choice:
                j[f.key] = f.choices.at(size_t(v));
                break;
        }
    }
    return j;
}

void SettingsSchema::set_value(void* object, const SettingField& f, double v,
                               const std::string& origin, const std::string& where) const {
    const bool integral = f.type != SettingType::Float;
    if (!std::isfinite(v) || v < f.min || v > f.max || (integral && v != std::floor(v))) {
        std::ostringstream got;
        if (integral && std::isfinite(v) && std::fabs(v) < 9e18)
            got << std::setprecision(17) << v;  // an integer past 1e6 keeps all its digits
        else
            got << v;
        throw Error(origin, where, "expected " + describe_range(f) + ", got " + got.str());
    }
    f.set(object, v);
}

void SettingsSchema::from_json(void* object, const json& j, const std::string& file,
                               const std::string& path) const {
    const std::string base = path.empty() ? prefix_ : path;
    if (!j.is_object())
        throw Error(file, base, "expected an object of settings (" + keys_list() + ")");
    // Presets first: the fields they write take their own values from the object after them.
    std::vector<std::pair<std::string, const json*>> ordered;
    for (const auto& [key, value] : j.items()) {
        const SettingField* f = find(key);
        ordered.emplace(f && f->is_preset ? ordered.begin() : ordered.end(), key, &value);
    }
    for (const auto& [key, value_ptr] : ordered) {
        const json& value = *value_ptr;
        const std::string where = base + "." + key;
        const SettingField* f = find(key);
        if (!f) throw Error(file, where, "unknown setting; valid keys are: " + keys_list());
        double v = 0;
        if (f->type == SettingType::Bool) {
            if (!value.is_boolean()) throw Error(file, where, "expected true or false");
            v = value.get<bool>() ? 1 : 0;
        } else if (f->type == SettingType::Choice) {
            if (!value.is_string()) throw Error(file, where, "expected " + describe_range(*f));
            auto it = std::find(f->choices.begin(), f->choices.end(), value.get<std::string>());
            if (it == f->choices.end())
                throw Error(file, where,
                            "expected " + describe_range(*f) + ", got \"" +
                                value.get<std::string>() + "\"");
            v = double(it - f->choices.begin());
        } else {
            if (!value.is_number())
                throw Error(file, where,
                            "expected " + describe_range(*f) + ", got " + value.dump());
            v = value.get<double>();
        }
        set_value(object, *f, v, file, where);
    }
}

uint32_t SettingsSchema::set_from_string(void* object, const std::string& key,
                                         const std::string& text, const std::string& origin) const {
    const SettingField* f = find(key);
    const std::string where = prefix_ + "." + key;
    if (!f) throw Error(origin, where, "unknown setting; valid keys are: " + keys_list());
    double v = 0;
    if (f->type == SettingType::Bool) {
        if (text == "true" || text == "on" || text == "1")
            v = 1;
        else if (text == "false" || text == "off" || text == "0")
            v = 0;
        else
            throw Error(origin, where, "expected true or false, got \"" + text + "\"");
    } else if (f->type == SettingType::Choice) {
        auto it = std::find(f->choices.begin(), f->choices.end(), text);
        if (it == f->choices.end())
            throw Error(origin, where, "expected " + describe_range(*f) + ", got \"" + text + "\"");
        v = double(it - f->choices.begin());
    } else {
        size_t used = 0;
        try {
            v = std::stod(text, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != text.size())
            throw Error(origin, where, "expected " + describe_range(*f) + ", got \"" + text + "\"");
    }
    set_value(object, *f, v, origin, where);
    return f->invalidates;
}

void SettingsSchema::reset(void* object) const {
    for (const SettingField& f : fields_) f.set(object, f.default_value);
}

}  // namespace freqlab
