#include "settings/settings_group.h"

#include "base/error.h"

namespace freqlab {

uint32_t SettingsGroup::apply_assignment(const std::string& assignment, const std::string& origin) {
    const size_t eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0)
        throw Error(origin, assignment, "expected key=value, e.g. frame.spp=4");
    const std::string full = assignment.substr(0, eq), value = assignment.substr(eq + 1);
    const size_t dot = full.find('.');
    if (dot != std::string::npos) {
        const std::string prefix = full.substr(0, dot);
        for (const Binding& b : bindings_)
            if (b.schema->prefix() == prefix && b.schema->find(full.substr(dot + 1)))
                return b.schema->set_from_string(b.object, full.substr(dot + 1), value, origin);
    }
    throw Error(origin, full, "unknown setting; valid keys are: " + keys_list());
}

nlohmann::json SettingsGroup::to_json() const {
    nlohmann::json j = nlohmann::json::object();
    for (const Binding& b : bindings_) j[b.schema->prefix()] = b.schema->to_json(b.object);
    return j;
}

nlohmann::json SettingsGroup::affecting_results(nlohmann::json settings) const {
    for (const Binding& b : bindings_) {
        const auto group = settings.find(b.schema->prefix());
        if (group == settings.end() || !group->is_object()) continue;
        for (const SettingField& f : b.schema->fields())
            if ((f.invalidates & ~uint32_t(kInvalidatesDisplay)) == 0) group->erase(f.key);
    }
    return settings;
}

void SettingsGroup::from_json(const nlohmann::json& j, const std::string& file,
                              const std::string& path) {
    if (!j.is_object()) throw Error(file, path, "expected an object of settings groups");
    for (const auto& [prefix, value] : j.items()) {
        const Binding* found = nullptr;
        for (const Binding& b : bindings_)
            if (b.schema->prefix() == prefix) found = &b;
        const std::string where = path.empty() ? prefix : path + "." + prefix;
        if (!found) {
            std::string valid;
            for (const Binding& b : bindings_)
                valid += (valid.empty() ? "" : ", ") + b.schema->prefix();
            throw Error(file, where, "unknown settings group; valid groups are: " + valid);
        }
        found->schema->from_json(found->object, value, file, where);
    }
}

std::string SettingsGroup::keys_list() const {
    std::string s;
    for (const Binding& b : bindings_) s += (s.empty() ? "" : ", ") + b.schema->keys_list();
    return s;
}

}  // namespace freqlab
