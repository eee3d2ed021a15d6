// The query path shared by the CLI, the Tables panel and the bakers: components add up, the
// surface variant is the infinite response at the shifted receiver, the similarity rule feeds
// multiple scattering, and out-of-domain inputs are errors naming the flag.
#include <gtest/gtest.h>

#include <cmath>

#include "base/error.h"
#include "shared_tables.h"
#include "volume/impulse_query.h"

using namespace freqlab;

TEST(ImpulseQuery, TotalIsTheSumAndBouncesAddMultipleScattering) {
    const ImpulseTables& t = test_support::shared_impulse_tables();
    for (EmitterKind e : {EmitterKind::Point, EmitterKind::Directional, EmitterKind::Area}) {
        ImpulseQuery q;
        q.emitter = e;
        q.distance = 0.8;
        q.shift = 0.3;
        q.medium = {1.5, 0.2, 0.25};
        q.last_bounce = 1;
        const ImpulseResponse single = query_impulse(t, q);
        q.last_bounce = 4;
        const ImpulseResponse all = query_impulse(t, q);
        EXPECT_EQ(single.multiple[0], 0.0);
        EXPECT_GT(all.multiple[0], 0.0) << to_string(e);
        for (int l = 0; l < kImpulseOrder; ++l) {
            EXPECT_DOUBLE_EQ(all.single[size_t(l)], single.single[size_t(l)]);
            EXPECT_NEAR(all.total[size_t(l)],
                        all.direct[size_t(l)] + all.single[size_t(l)] + all.multiple[size_t(l)],
                        1e-15 * std::fabs(all.total[0]));
        }
        // Similarity: multiple scattering at g equals the isotropic medium with sigma_s (1 - g).
        ImpulseQuery iso = q;
        iso.medium = {1.5 * 0.75, 0.2, 0.0};
        const ImpulseResponse similar = query_impulse(t, iso);
        for (int l = 0; l < kImpulseOrder; ++l)
            EXPECT_NEAR(all.multiple[size_t(l)], similar.multiple[size_t(l)],
                        1e-12 * all.multiple[0]);
    }
}

TEST(ImpulseQuery, SurfaceVariantIsTheShiftedReceiver) {
    const ImpulseTables& t = test_support::shared_impulse_tables();
    const HomogeneousMedium m{2.0, 0.5, 0.3};  // sigma_t = 2.5: the shift is 0.05 scene units
    for (EmitterKind e : {EmitterKind::Point, EmitterKind::Directional, EmitterKind::Area}) {
        ImpulseQuery q;
        q.emitter = e;
        q.distance = 0.6;
        q.shift = 0.5;
        q.medium = m;
        q.last_bounce = 3;
        q.variant = TableVariant::Surface;
        const ImpulseResponse surface = query_impulse(t, q);
        q.variant = TableVariant::Infinite;
        const ImpulseResponse infinite = query_impulse(t, q);
        q.distance = 0.6 - kBackScatterShift / m.sigma_t();
        const ImpulseResponse shifted = query_impulse(t, q);
        for (int l = 0; l < kImpulseOrder; ++l) {
            EXPECT_DOUBLE_EQ(surface.direct[size_t(l)], infinite.direct[size_t(l)]);
            EXPECT_DOUBLE_EQ(surface.single[size_t(l)], shifted.single[size_t(l)]);
            EXPECT_DOUBLE_EQ(surface.multiple[size_t(l)], shifted.multiple[size_t(l)]);
        }
        // Closer to the emitter (or to the boundary): more in-scattered light.
        EXPECT_GT(surface.single[0], infinite.single[0]) << to_string(e);
    }
}

TEST(ImpulseQuery, OutOfDomainInputsNameTheFlag) {
    auto field_of = [](const ImpulseQuery& q) {
        try {
            validate(q, 30);
        } catch (const Error& e) {
            return e.file();
        }
        return std::string("none");
    };
    ImpulseQuery q;
    EXPECT_EQ(field_of(q), "none");
    q.distance = -1;
    EXPECT_EQ(field_of(q), "--distance");
    q = {};
    q.distance = std::nan("");
    EXPECT_EQ(field_of(q), "--distance");
    q = {};
    q.medium.g = 0.9;  // within the tables' range since they carry HG beyond |g| = 0.6
    EXPECT_EQ(field_of(q), "none");
    q.medium.g = 0.96;
    EXPECT_EQ(field_of(q), "--g");
    q = {};
    q.shift = 1.5;
    EXPECT_EQ(field_of(q), "--shift");
    q = {};
    q.last_bounce = 31;
    EXPECT_EQ(field_of(q), "--bounces");
    q = {};
    q.medium.sigma_s = 0;
    EXPECT_EQ(field_of(q), "--sigma-s/--sigma-a");
    EXPECT_THROW(parse_emitter("spot"), Error);
    EXPECT_THROW(parse_variant("slab"), Error);
}
