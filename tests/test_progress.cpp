// A job's progress (base/job.h; issue "The timeline as a recorded run": "progress moves within a
// stage, the ETA falls monotonically"): planned from the stages a frame like it took, fractions
// weigh stages by their time and the ETA never rises, whatever the stages do (overrun, one
// unit, run faster); without a plan the old mean-of-stages fraction stands.
#include <gtest/gtest.h>

#include <chrono>
#include <random>

#include "base/job.h"

using namespace freqlab;

namespace {

// A clock the test moves.
struct TestClock {
    Progress::Clock::time_point now{};
    void advance(double seconds) {
        now += std::chrono::duration_cast<Progress::Clock::duration>(
            std::chrono::duration<double>(seconds));
    }
};

}  // namespace

TEST(Progress, PlannedFractionsWeighStagesByTimeAndTheEtaCountsDown) {
    TestClock clock;
    Progress p([&] { return clock.now; });
    p.set_expected_stages({{"a", 1.0}, {"b", 3.0}});
    EXPECT_DOUBLE_EQ(p.snapshot().eta_s, 4.0);
    EXPECT_DOUBLE_EQ(p.snapshot().fraction, 0.0);
    p.begin_stage("a", 1);  // one unit: counts down by time
    clock.advance(0.5);
    EXPECT_DOUBLE_EQ(p.snapshot().eta_s, 3.5);
    EXPECT_DOUBLE_EQ(p.snapshot().fraction, 0.125);
    clock.advance(1.0);  // a overran its second: waits at the stages after it
    EXPECT_DOUBLE_EQ(p.snapshot().eta_s, 3.0);
    p.begin_stage("b", 4);
    clock.advance(0.5);
    p.advance(2);  // half its units in a sixth of its time: units say 1.5 s left, time 2.5
    EXPECT_DOUBLE_EQ(p.snapshot().eta_s, 1.5);
    EXPECT_DOUBLE_EQ(p.snapshot().fraction, 0.625);
    const std::vector<StageTime> took = p.stage_times();
    ASSERT_EQ(took.size(), 2u);
    EXPECT_EQ(took[0].name, "a");
    EXPECT_DOUBLE_EQ(took[0].seconds, 1.5);
    EXPECT_DOUBLE_EQ(took[1].seconds, 0.5);
}

TEST(Progress, PlannedEtaNeverRises) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int trial = 0; trial < 50; ++trial) {
        TestClock clock;
        Progress p([&] { return clock.now; });
        std::vector<StageTime> plan;
        for (int i = 0; i < 5; ++i) plan.push_back({"s" + std::to_string(i), 0.1 + u(rng)});
        p.set_expected_stages(plan);
        double last = p.snapshot().eta_s, last_fraction = 0.0;
        for (int stage = 0; stage < 5; ++stage) {
            const long units = 1 + long(u(rng) * 20);
            p.begin_stage(plan[size_t(stage)].name, units);
            const double pace = 0.2 + 3.0 * u(rng);  // stages run slower or faster than planned
            for (long k = 0; k < units; ++k) {
                clock.advance(pace * plan[size_t(stage)].seconds / double(units) * 2.0 * u(rng));
                if (u(rng) < 0.7) p.advance();
                const ProgressSnapshot s = p.snapshot();
                EXPECT_LE(s.eta_s, last + 1e-12) << "trial " << trial << " stage " << stage;
                EXPECT_GE(s.fraction, last_fraction - 1e-12);
                last = s.eta_s;
                last_fraction = s.fraction;
            }
        }
    }
}

TEST(Progress, WithoutAPlanStagesWeighTheSame) {
    TestClock clock;
    Progress p([&] { return clock.now; });
    p.set_stage_count(2);
    p.begin_stage("a", 4);
    p.advance(2);
    clock.advance(1.0);
    EXPECT_DOUBLE_EQ(p.snapshot().fraction, 0.25);
    EXPECT_DOUBLE_EQ(p.snapshot().eta_s, 3.0);  // elapsed (1 - f) / f
}
