// The table file: a save/load round trip answers the same queries (to float precision), and a
// damaged, truncated or foreign file is an error naming the field.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "base/error.h"
#include "volume/impulse_tables.h"

using namespace freqlab;
namespace fs = std::filesystem;

TEST(ImpulseTables, SaveLoadRoundTripAndDamage) {
    const fs::path path = fs::temp_directory_path() / "freqlab_tables_test.bin";
    const ImpulseTables built = ImpulseTables::build(2);
    built.save(path);
    const ImpulseTables loaded = ImpulseTables::load(path);
    const HomogeneousMedium m{0.8, 0.2, 0.25};
    for (double d : {0.05, 0.6, 3.0}) {
        const ZhVector a = built.point_single().single(m, d),
                       b = loaded.point_single().single(m, d);
        const ZhVector c = built.directional_single().single(m, d),
                       e = loaded.directional_single().single(m, d);
        const ZhVector f = built.point_multiple().bounces_in(m, d, 1, 2),
                       g = loaded.point_multiple().bounces_in(m, d, 1, 2);
        for (int l = 0; l < kImpulseOrder; ++l) {
            EXPECT_NEAR(a[size_t(l)], b[size_t(l)], 1e-6 * std::fabs(a[0]));
            EXPECT_NEAR(c[size_t(l)], e[size_t(l)], 1e-6 * std::fabs(c[0]));
            EXPECT_NEAR(f[size_t(l)], g[size_t(l)], 1e-6 * std::fabs(f[0]));
        }
    }
    // One flipped byte in the payload.
    {
        std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
        file.seekp(-100, std::ios::end);
        file.put('\x7f');
    }
    try {
        ImpulseTables::load(path);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "checksum");
    }
    // Truncated.
    fs::resize_file(path, fs::file_size(path) - 64);
    try {
        ImpulseTables::load(path);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "payload");
    }
    // Not a table file at all.
    std::ofstream(path) << "hello\n";
    try {
        ImpulseTables::load(path);
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.field(), "header");
    }
}
