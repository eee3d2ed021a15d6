// One set of impulse-response tables per test binary (the area tables take seconds to build):
// built in memory, and the same saved and loaded back, so that tests exercise the stored
// precision (half floats for the area responses) too.
#pragma once

#include <filesystem>

#include "volume/impulse_tables.h"

namespace freqlab::test_support {

struct SharedTables {
    ImpulseTables built, loaded;
    std::filesystem::path path;
};

inline const SharedTables& shared_tables() {
    static const SharedTables tables = [] {
        const std::filesystem::path path =
            std::filesystem::temp_directory_path() / "freqlab_shared_tables_test.bin";
        ImpulseTables built = ImpulseTables::build(4);
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
