// A JSON value together with where it came from (file and JSON path), so that every
// complaint about it names the field: `scene.json: objects[2].material.roughness: expected a
// number in (0, 1], got "abc"`.
#pragma once

#include <initializer_list>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/enum_names.h"
#include "math/types.h"

namespace freqlab {

class JsonReader {
  public:
    JsonReader(const nlohmann::json& value, std::string file, std::string path)
        : value_(&value), file_(std::move(file)), path_(std::move(path)) {}

    // Parses text; a syntax error names the file, line and column.
    static nlohmann::json parse(const std::string& text, const std::string& file);

    const nlohmann::json& raw() const { return *value_; }
    const std::string& file() const { return file_; }
    const std::string& path() const { return path_; }

    bool has(const std::string& key) const;
    JsonReader get(const std::string& key) const;  // required member of an object
    JsonReader at(size_t index) const;             // element of an array
    size_t array_size() const;                     // throws unless an array
    bool is_string() const { return value_->is_string(); }
    bool is_object() const { return value_->is_object(); }
    bool is_array() const { return value_->is_array(); }
    // Throws on members not in `allowed`, listing the allowed ones.
    void only_keys(std::initializer_list<const char*> allowed) const;

    double number() const;
    double number_in(double lo, double hi, bool lo_open = false, bool hi_open = false) const;
    int integer_in(int lo, int hi) const;
    bool boolean() const;
    std::string string() const;
    std::string one_of(const std::vector<const char*>& names) const;
    // The value an enum's name table gives this string (base/enum_names.h).
    template <class E, std::size_t N>
    E one_of(const EnumName<E> (&table)[N]) const {
        const std::string name = one_of(enum_names(table));
        for (const EnumName<E>& e : table)
            if (name == e.name) return e.value;
        return table[0].value;  // one_of() threw already
    }
    vec3 vector3() const;    // [x, y, z], finite
    vec3 direction() const;  // non-zero vector3, normalised
    vec3 color() const;      // [r, g, b] >= 0, or a single number for grey

    // Optional members with defaults.
    double number_or(const std::string& key, double fallback, double lo, double hi) const;
    vec3 vector3_or(const std::string& key, vec3 fallback) const;
    vec3 color_or(const std::string& key, vec3 fallback) const;

    [[noreturn]] void fail(const std::string& expectation) const;

  private:
    std::string got() const;  // short rendering of the value for messages
    const nlohmann::json* value_;
    std::string file_, path_;
};

}  // namespace freqlab
