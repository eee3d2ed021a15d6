// One table names an enum's values once: to_string, parsing (scene files, the command line,
// EXR headers) and the lists an error message offers all read it.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "base/error.h"

namespace freqlab {

template <class E>
struct EnumName {
    E value;
    const char* name;
};

template <class E, std::size_t N>
const char* enum_name(const EnumName<E> (&table)[N], E value) {
    for (const EnumName<E>& e : table)
        if (e.value == value) return e.name;
    return "?";
}

template <class E, std::size_t N>
std::vector<const char*> enum_names(const EnumName<E> (&table)[N]) {
    std::vector<const char*> names;
    for (const EnumName<E>& e : table) names.push_back(e.name);
    return names;
}

// `separator` may hold NULs (ImGui's combo lists): a std::string, not a C string.
template <class E, std::size_t N>
std::string enum_name_list(const EnumName<E> (&table)[N], const std::string& separator = ", ") {
    std::string list;
    for (const EnumName<E>& e : table)
        list += (list.empty() ? "" : separator) + std::string(e.name);
    return list;
}

// The value named `name`, or an Error naming `where` (a flag, a file or a field), the name
// and every name the table holds.
template <class E, std::size_t N>
E enum_from_name(const EnumName<E> (&table)[N], const std::string& name, const std::string& where) {
    for (const EnumName<E>& e : table)
        if (name == e.name) return e.value;
    throw Error(where, name, "expected one of " + enum_name_list(table));
}

}  // namespace freqlab
