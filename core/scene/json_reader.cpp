#include "scene/json_reader.h"

#include <cmath>
#include <sstream>

#include "base/error.h"

namespace freqlab {

using nlohmann::json;

json JsonReader::parse(const std::string& text, const std::string& file) {
    try {
        return json::parse(text);
    } catch (const json::parse_error& e) {
        // Convert the byte offset to line:column, which is what an editor shows.
        size_t line = 1, col = 1;
        for (size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
            if (text[i] == '\n')
                ++line, col = 1;
            else
                ++col;
        }
        std::string what = e.what();
        const size_t pos = what.find("syntax error");
        throw Error(
            file, "line " + std::to_string(line) + ", column " + std::to_string(col),
            "malformed JSON (" + (pos == std::string::npos ? what : what.substr(pos)) + ")");
    } catch (const json::exception& e) {
        // out_of_range.406: a number beyond double (fuzz_scene_json: 1111...e1111...).
        throw Error(file, "", std::string("malformed JSON (") + e.what() + ")");
    }
}

void JsonReader::fail(const std::string& expectation) const {
    throw Error(file_, path_.empty() ? "(top level)" : path_, expectation);
}

std::string JsonReader::got() const {
    std::string s = value_->dump();
    if (s.size() > 40) s = s.substr(0, 37) + "...";
    return s;
}

bool JsonReader::has(const std::string& key) const {
    return value_->is_object() && value_->contains(key);
}

JsonReader JsonReader::get(const std::string& key) const {
    if (!value_->is_object()) fail("expected an object, got " + got());
    const std::string sub = path_.empty() ? key : path_ + "." + key;
    auto it = value_->find(key);
    if (it == value_->end()) throw Error(file_, sub, "missing required field");
    return JsonReader(*it, file_, sub);
}

JsonReader JsonReader::at(size_t index) const {
    // nlohmann's const operator[] is undefined past the end: every caller gets a located error.
    if (!value_->is_array()) fail("expected an array, got " + got());
    if (index >= value_->size())
        fail("expected at least " + std::to_string(index + 1) + " elements, got " +
             std::to_string(value_->size()));
    return JsonReader((*value_)[index], file_, path_ + "[" + std::to_string(index) + "]");
}

size_t JsonReader::array_size() const {
    if (!value_->is_array()) fail("expected an array, got " + got());
    return value_->size();
}

void JsonReader::only_keys(std::initializer_list<const char*> allowed) const {
    if (!value_->is_object()) fail("expected an object, got " + got());
    for (const auto& [key, v] : value_->items()) {
        bool ok = false;
        for (const char* a : allowed) ok = ok || key == a;
        if (!ok) {
            std::string list;
            for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
            throw Error(file_, path_.empty() ? key : path_ + "." + key,
                        "unknown field; expected one of: " + list);
        }
    }
}

double JsonReader::number() const {
    if (!value_->is_number()) fail("expected a number, got " + got());
    const double v = value_->get<double>();
    if (!std::isfinite(v)) fail("expected a finite number");
    return v;
}

double JsonReader::number_in(double lo, double hi, bool lo_open, bool hi_open) const {
    if (!value_->is_number() || !std::isfinite(value_->get<double>()) ||
        (lo_open ? value_->get<double>() <= lo : value_->get<double>() < lo) ||
        (hi_open ? value_->get<double>() >= hi : value_->get<double>() > hi)) {
        std::ostringstream ss;
        ss << "expected a number in " << (lo_open ? "(" : "[") << lo << ", " << hi
           << (hi_open ? ")" : "]") << ", got " << got();
        fail(ss.str());
    }
    return value_->get<double>();
}

int JsonReader::integer_in(int lo, int hi) const {
    if (!value_->is_number_integer() || value_->get<long long>() < lo ||
        value_->get<long long>() > hi)
        fail("expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
             "], got " + got());
    return value_->get<int>();
}

bool JsonReader::boolean() const {
    if (!value_->is_boolean()) fail("expected true or false, got " + got());
    return value_->get<bool>();
}

std::string JsonReader::string() const {
    if (!value_->is_string()) fail("expected a string, got " + got());
    return value_->get<std::string>();
}

std::string JsonReader::one_of(const std::vector<const char*>& names) const {
    std::string list;
    for (const char* n : names) list += (list.empty() ? "" : ", ") + std::string(n);
    if (!value_->is_string()) fail("expected one of " + list + ", got " + got());
    const std::string s = value_->get<std::string>();
    for (const char* n : names)
        if (s == n) return s;
    fail("expected one of " + list + ", got " + got());
}

vec3 JsonReader::vector3() const {
    if (!value_->is_array() || value_->size() != 3)
        fail("expected an array of 3 numbers [x, y, z], got " + got());
    vec3 v;
    for (int i = 0; i < 3; ++i) {
        const json& e = (*value_)[i];
        if (!e.is_number() || !std::isfinite(e.get<double>()))
            fail("expected an array of 3 finite numbers, got " + got());
        v[i] = e.get<float>();
    }
    return v;
}

vec3 JsonReader::direction() const {
    const vec3 v = vector3();
    if (glm::length(v) < 1e-12f) fail("expected a non-zero direction, got " + got());
    return glm::normalize(v);
}

vec3 JsonReader::color() const {
    if (value_->is_number()) {
        const double g = number_in(0, 1e30);
        return vec3(float(g));
    }
    if (!value_->is_array() || value_->size() != 3)
        fail("expected a colour: [r, g, b] or a single number, each >= 0, got " + got());
    const vec3 c = vector3();
    if (c.r < 0 || c.g < 0 || c.b < 0)
        fail("expected non-negative colour components, got " + got());
    return c;
}

double JsonReader::number_or(const std::string& key, double fallback, double lo, double hi) const {
    return has(key) ? get(key).number_in(lo, hi) : fallback;
}

vec3 JsonReader::vector3_or(const std::string& key, vec3 fallback) const {
    return has(key) ? get(key).vector3() : fallback;
}

vec3 JsonReader::color_or(const std::string& key, vec3 fallback) const {
    return has(key) ? get(key).color() : fallback;
}

}  // namespace freqlab
