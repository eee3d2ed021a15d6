// A set of (schema, object) bindings addressed by "prefix.key": what `--set`, the stats
// output and the session JSON see as one namespace of settings.
#pragma once

#include <string>
#include <vector>

#include "settings/schema.h"

namespace freqlab {

class SettingsGroup {
  public:
    void bind(const SettingsSchema& schema, void* object) {
        bindings_.push_back({&schema, object});
    }

    // "prefix.key=value" (the CLI form). Returns the field's invalidation flags.
    uint32_t apply_assignment(const std::string& assignment, const std::string& origin = "--set");
    nlohmann::json to_json() const;  // {"prefix": {"key": value, ...}, ...}
    // `settings` (to_json's shape) without the fields that change no result: those whose
    // invalidation flags are nothing or display only (frame.exposure, cache.checkpoint_every,
    // reference.use_cache, ...). A recorded run is keyed by what is left: changing the
    // exposure must not make its frames another run's.
    nlohmann::json affecting_results(nlohmann::json settings) const;
    // Reads {"prefix": {...}} objects; unknown prefixes are errors listing the valid ones.
    void from_json(const nlohmann::json& j, const std::string& file, const std::string& path);
    std::string keys_list() const;

    struct Binding {
        const SettingsSchema* schema;
        void* object;
    };
    const std::vector<Binding>& bindings() const { return bindings_; }

  private:
    std::vector<Binding> bindings_;
};

}  // namespace freqlab
