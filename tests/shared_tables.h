// One set of impulse-response tables per test binary (the area tables take seconds to build):
// built in memory, and the same saved and loaded back, so that tests exercise the stored
// precision (half floats for the area responses) too.
//
// FREQLAB_SHARED_TABLES (set by tests/CMakeLists.txt) names a file that keeps the built set
// between runs: absent or unreadable, the set is built and saved there; present, it is loaded
// instead. scripts/sanitize.sh hands the release suite's file to the sanitized suite, where
// building took 290 s of its 570 (see there for what that leaves unsanitized).
#pragma once

#include <cstdlib>
#include <filesystem>

#include "base/error.h"
#include "volume/impulse_tables.h"

namespace freqlab::test_support {

struct SharedTables {
    ImpulseTables built, loaded;
    std::filesystem::path path;
};

inline ImpulseTables built_or_kept_tables() {
    const char* kept = std::getenv("FREQLAB_SHARED_TABLES");
    if (kept && *kept && std::filesystem::exists(kept)) {
        try {
            return ImpulseTables::load(kept);
        } catch (const Error&) {
            // An older table layout: built again below.
        }
    }
    ImpulseTables built = ImpulseTables::build(4);
    if (kept && *kept) {
        std::filesystem::create_directories(std::filesystem::path(kept).parent_path());
        built.save(kept);
    }
    return built;
}

inline const SharedTables& shared_tables() {
    static const SharedTables tables = [] {
        const std::filesystem::path path =
            std::filesystem::temp_directory_path() / "freqlab_shared_tables_test.bin";
        ImpulseTables built = built_or_kept_tables();
        built.save(path);
        return SharedTables{built, ImpulseTables::load(path), path};
    }();
    return tables;
}

// What the query path reads: the tables as stored.
inline const ImpulseTables& shared_impulse_tables() {
    return shared_tables().loaded;
}

}  // namespace freqlab::test_support
