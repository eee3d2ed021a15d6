// The table file: a save/load round trip answers the same queries (to float precision), and a
// damaged, truncated or foreign file is an error naming the field.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "base/error.h"
#include "shared_tables.h"
#include "volume/impulse_tables.h"

using namespace freqlab;
namespace fs = std::filesystem;

TEST(ImpulseTables, SaveLoadRoundTripAndDamage) {
    const test_support::SharedTables& shared = test_support::shared_tables();
    const ImpulseTables& built = shared.built;
    const ImpulseTables& loaded = shared.loaded;
    const HomogeneousMedium m{0.8, 0.2, 0.25};
    for (double d : {0.05, 0.6, 3.0}) {
        const ZhVector a = built.point_single().single(m, d),
                       b = loaded.point_single().single(m, d);
        const ZhVector c = built.directional_single().single(m, d),
                       e = loaded.directional_single().single(m, d);
        const ZhVector f = built.point_multiple().bounces_in(m, d, 1, 2),
                       g = loaded.point_multiple().bounces_in(m, d, 1, 2);
        const ZhVector h = built.directional_multiple().bounces_in(m, d, 2, 4),
                       i = loaded.directional_multiple().bounces_in(m, d, 2, 4);
        const TiltedZh j = built.area_single().single(m, d, 0.4),
                       k = loaded.area_single().single(m, d, 0.4);
        EXPECT_NEAR(j.tilt, k.tilt, 1e-6);
        for (int l = 0; l < kImpulseOrder; ++l) {
            EXPECT_NEAR(a[size_t(l)], b[size_t(l)], 1e-6 * std::fabs(a[0]));
            EXPECT_NEAR(c[size_t(l)], e[size_t(l)], 1e-6 * std::fabs(c[0]));
            EXPECT_NEAR(f[size_t(l)], g[size_t(l)], 1e-6 * std::fabs(f[0]));
            EXPECT_NEAR(h[size_t(l)], i[size_t(l)], 1e-6 * std::fabs(h[0]));
            // Half floats: 2^-12 relative rounding per stored value.
            EXPECT_NEAR(j.zh[size_t(l)], k.zh[size_t(l)], 5e-4 * std::fabs(j.zh[0]));
        }
        EXPECT_GT(std::fabs(j.zh[0]), 0.0);
        EXPECT_GT(std::fabs(h[0]), 0.0);
    }
    const fs::path path = fs::temp_directory_path() / "freqlab_tables_damage_test.bin";
    fs::copy_file(shared.path, path, fs::copy_options::overwrite_existing);
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

// The check `freqlab tables` runs on every file it writes (ImpulseTables::verify): point and
// directional single scattering against direct quadrature, within 0.5 % per ZH coefficient.
TEST(ImpulseTables, VerifyAgainstDirectQuadrature) {
    const ImpulseTables& tables = test_support::shared_impulse_tables();
    const ImpulseTables::Verification v = tables.verify();
    std::printf("verify: point %.2e, directional %.2e over %d queries\n", v.worst_point,
                v.worst_directional, v.queries);
    EXPECT_EQ(v.queries, 144);  // 3 sigma_s x 8 g (every g panel) x 3 d x 2 emitters
    EXPECT_LT(v.worst_point, ImpulseTables::kVerifyTolerance);
    EXPECT_LT(v.worst_directional, ImpulseTables::kVerifyTolerance);
    EXPECT_GT(v.worst(), 0.0) << "a table equal to the quadrature to the last bit is suspicious";
}
