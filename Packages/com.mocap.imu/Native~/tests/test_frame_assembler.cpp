// Frame assembler: resampling onto the output grid, holding, staleness, gaps and ordering.
//
// Every sensor follows a known smooth motion: a constant-rate rotation about its own fixed axis
// (so slerp between any two samples is exact) and specific force / angular rate that are linear
// in time (so linear interpolation is exact). Interpolated frames can then be compared with the
// truth at the frame time.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "frame_assembler.h"

namespace {

constexpr int kSensors = 6; // the default set; one test fills all MOCAP_MAX_SENSORS slots
constexpr double kRate = 60.0;
constexpr double kPeriod = 1.0 / kRate;
constexpr double kHold = 0.05;
constexpr double kStale = 0.25;
constexpr double kTick = 0.001;
constexpr uint32_t kAll = (1u << kSensors) - 1;

struct Truth {
    double axis[3];
    double omega;  // rad/s about axis
    double angle0; // rad at t = 0
    double f0[3], f1[3];
    double g0[3], g1[3];
};

Truth truth_for(int s)
{
    Truth tr{};
    const double ax[3] = {1.0 + s, -0.5 * s, 2.0 - 0.3 * s};
    const double n = std::sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
    for (int i = 0; i < 3; i++)
        tr.axis[i] = ax[i] / n;
    tr.omega = 0.7 + 0.3 * s * (s % 2 ? -1.0 : 1.0); // mixed signs, at most 2.2 rad/s
    tr.angle0 = 0.4 * s;
    for (int i = 0; i < 3; i++) {
        tr.f0[i] = 9.8 * (i == 2) + 0.1 * s - 0.2 * i;
        tr.f1[i] = 0.5 * (i + 1) - 0.3 * s;
        tr.g0[i] = 0.05 * s + 0.01 * i;
        tr.g1[i] = -0.02 * (i + 1) + 0.01 * s;
    }
    return tr;
}

void truth_quat(int s, double t, double q[4])
{
    const Truth tr = truth_for(s);
    const double half = 0.5 * (tr.angle0 + tr.omega * t);
    q[0] = std::cos(half);
    for (int i = 0; i < 3; i++)
        q[i + 1] = std::sin(half) * tr.axis[i];
}

imu_sample truth_sample(int s, double t)
{
    const Truth tr = truth_for(s);
    imu_sample x{};
    x.segment = s;
    x.node_id = 0x60u + (uint32_t)s;
    x.t = t;
    truth_quat(s, t, x.quat);
    for (int i = 0; i < 3; i++) {
        x.acc[i] = 0.0;
        x.force_world[i] = tr.f0[i] + tr.f1[i] * t;
        x.gyr[i] = tr.g0[i] + tr.g1[i] * t;
    }
    return x;
}

// Rotation angle between two unit quaternions, well conditioned for tiny angles.
double quat_diff_rad(const double a[4], const double b[4])
{
    const double w = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    const double x = a[0] * b[1] - a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
    const double y = a[0] * b[2] + a[1] * b[3] - a[2] * b[0] - a[3] * b[1];
    const double z = a[0] * b[3] - a[1] * b[2] + a[2] * b[1] - a[3] * b[0];
    return 2.0 * std::atan2(std::sqrt(x * x + y * y + z * z), std::fabs(w));
}

// Largest deviation of sensor s in frame f from the truth at frame time.
double truth_error(const raw_frame &f, int s)
{
    const imu_sample x = truth_sample(s, f.t);
    double e = quat_diff_rad(f.quat[s], x.quat);
    for (int i = 0; i < 3; i++) {
        e = std::max(e, std::fabs(f.force_world[s][i] - x.force_world[i]));
        e = std::max(e, std::fabs(f.gyr[s][i] - x.gyr[i]));
    }
    return e;
}

// Sensor s carries exactly the values of sample x (held, not interpolated).
void expect_holds(const raw_frame &f, int s, const imu_sample &x)
{
    for (int i = 0; i < 4; i++)
        EXPECT_EQ(f.quat[s][i], x.quat[i]) << "sensor " << s << " t " << f.t;
    for (int i = 0; i < 3; i++) {
        EXPECT_EQ(f.force_world[s][i], x.force_world[i]);
        EXPECT_EQ(f.gyr[s][i], x.gyr[i]);
    }
    EXPECT_EQ(f.node_id[s], x.node_id);
}

bool on_grid(double t)
{
    return std::fabs(t * kRate - std::round(t * kRate)) < 1e-6;
}

struct SensorPlan {
    bool present = true;
    double rate = 100.0;
    double phase = 0.0;          // first sample time offset (clock offset / phase)
    double gap_from = 1e9;       // no samples in [gap_from, gap_to)
    double gap_to = 1e9;
    double jitter = 0.0;         // +-jitter seconds, deterministic
};

struct Emitted {
    raw_frame f;
    double now; // session time at which assembler_next returned it
};

struct Sim {
    frame_assembler a{};
    std::vector<Emitted> frames;
    std::vector<std::vector<imu_sample>> pushed = std::vector<std::vector<imu_sample>>(kSensors);

    Sim() { assembler_init(&a, kRate, kHold, kStale); }

    void drain(double now)
    {
        Emitted e{};
        while (assembler_next(&a, now, &e.f)) {
            e.now = now;
            frames.push_back(e);
            ASSERT_LT(frames.size(), 1000000u) << "runaway emission";
        }
    }

    void push(const imu_sample &x)
    {
        assembler_push(&a, &x);
        pushed[x.segment].push_back(x);
    }

    // Samples arrive at their own time; a timer tick every kTick lets session time pass, as the
    // pipeline's advance() does. At equal times samples go first.
    void run(const std::vector<SensorPlan> &plans, double duration, bool ticks)
    {
        struct Ev { double t; int sensor; }; // sensor -1 = tick
        std::vector<Ev> ev;
        uint64_t lcg = 12345;
        for (int s = 0; s < kSensors; s++) {
            const SensorPlan &p = plans[s];
            if (!p.present)
                continue;
            for (int64_t k = 0;; k++) {
                double t = p.phase + (double)k / p.rate;
                if (t >= duration)
                    break;
                if (p.jitter > 0.0) {
                    lcg = lcg * 6364136223846793005ull + 1442695040888963407ull;
                    t += p.jitter * (2.0 * (double)(lcg >> 11) / 9007199254740992.0 - 1.0);
                }
                if (t >= p.gap_from && t < p.gap_to)
                    continue;
                ev.push_back({t, s});
            }
        }
        if (ticks)
            for (int64_t k = 0; k * kTick < duration; k++)
                ev.push_back({(double)k * kTick, -1});
        std::stable_sort(ev.begin(), ev.end(), [](const Ev &x, const Ev &y) {
            if (x.t != y.t)
                return x.t < y.t;
            return (x.sensor < 0 ? 1 : 0) < (y.sensor < 0 ? 1 : 0);
        });
        for (const Ev &e : ev) {
            if (e.sensor >= 0)
                push(truth_sample(e.sensor, e.t));
            drain(e.t);
        }
    }

    // Oldest pushed sample of sensor s after t.
    const imu_sample *first_after(int s, double t) const
    {
        for (const imu_sample &x : pushed[s])
            if (x.t > t)
                return &x;
        return nullptr;
    }

    // Newest pushed sample of sensor s at or before t.
    const imu_sample *last_before(int s, double t) const
    {
        const imu_sample *r = nullptr;
        for (const imu_sample &x : pushed[s])
            if (x.t <= t)
                r = &x;
        return r;
    }

    void expect_consecutive() const
    {
        for (size_t i = 0; i < frames.size(); i++)
            ASSERT_EQ(frames[i].f.sequence, (uint64_t)i);
    }
};

// A small phase keeps the first samples off a grid point: a sample exactly on the first grid
// point makes that frame due before the other sensors' first samples have arrived.
std::vector<SensorPlan> uniform_plans(double phase = 0.0002)
{
    return std::vector<SensorPlan>(kSensors, SensorPlan{true, 100.0, phase});
}

TEST(FrameAssembler, SixSensors100HzResampledTo60HzMatchTruth)
{
    Sim sim;
    sim.run(uniform_plans(0.1234), 3.0, false);
    ASSERT_GT(sim.frames.size(), 150u);
    sim.expect_consecutive();
    // First frame: first sample time rounded up onto the grid.
    EXPECT_NEAR(sim.frames[0].f.t, std::ceil(0.1234 * kRate) / kRate, 1e-12);
    for (size_t i = 0; i < sim.frames.size(); i++) {
        const raw_frame &f = sim.frames[i].f;
        ASSERT_TRUE(on_grid(f.t)) << f.t;
        if (i > 0) {
            EXPECT_NEAR(f.t - sim.frames[i - 1].f.t, kPeriod, 1e-9);
        }
        EXPECT_EQ(f.valid_mask, kAll);
        EXPECT_EQ(f.fresh_mask, kAll) << "t " << f.t;
        EXPECT_EQ(f.stale_mask, 0u);
        for (int s = 0; s < kSensors; s++) {
            EXPECT_LT(truth_error(f, s), 1e-6) << "sensor " << s << " t " << f.t;
            EXPECT_GE(f.age[s], 0.0);
            EXPECT_LE(f.age[s], 0.01 + 1e-9);
            EXPECT_EQ(f.node_id[s], 0x60u + (uint32_t)s);
        }
    }
}

TEST(FrameAssembler, MixedRatesPhasesAndClockOffset)
{
    std::vector<SensorPlan> plans = uniform_plans();
    plans[0].rate = 50.0;
    plans[1].rate = 200.0;
    plans[2].phase = 0.003; // 3 ms clock offset
    plans[3].phase = 0.0071;
    plans[4].rate = 120.0;
    plans[4].phase = 0.0015;
    plans[5].rate = 100.0;
    plans[5].jitter = 0.0012; // irregular arrival, still increasing at 100 Hz
    plans[5].phase = 0.002;
    Sim sim;
    sim.run(plans, 2.0, false);
    ASSERT_GT(sim.frames.size(), 100u);
    sim.expect_consecutive();
    size_t checked = 0;
    for (const Emitted &e : sim.frames) {
        const raw_frame &f = e.f;
        if (f.t < 0.02)
            continue; // the first frames may precede a sensor's first sample
        EXPECT_EQ(f.valid_mask, kAll);
        EXPECT_EQ(f.fresh_mask, kAll) << "t " << f.t;
        for (int s = 0; s < kSensors; s++)
            EXPECT_LT(truth_error(f, s), 1e-6) << "sensor " << s << " t " << f.t;
        checked++;
    }
    EXPECT_GT(checked, 100u);
}

TEST(FrameAssembler, FramesBeforeASensorStartsUseItsOldestSample)
{
    Sim sim;
    for (int k = 0; k <= 10; k++) {
        sim.push(truth_sample(0, k * 0.01));
        if (k >= 5)
            sim.push(truth_sample(4, k * 0.01 - 0.007)); // first sample at 0.043
    }
    sim.drain(0.1);
    ASSERT_GE(sim.frames.size(), 5u);
    sim.expect_consecutive();
    for (const Emitted &e : sim.frames) {
        const raw_frame &f = e.f;
        EXPECT_EQ(f.valid_mask, (1u << 0) | (1u << 4));
        EXPECT_EQ(f.stale_mask, 0u);
        EXPECT_LT(truth_error(f, 0), 1e-6);
        if (f.t < 0.043) {
            // Only later samples: the oldest is used, not fresh, and it is not old data.
            EXPECT_FALSE(f.fresh_mask & (1u << 4));
            EXPECT_EQ(f.age[4], 0.0);
            expect_holds(f, 4, sim.pushed[4][0]);
        } else {
            EXPECT_TRUE(f.fresh_mask & (1u << 4));
            EXPECT_LT(truth_error(f, 4), 1e-6);
        }
    }
    EXPECT_LT(sim.frames[2].f.t, 0.043); // 0, 1/60 and 2/60 precede sensor 4
}

TEST(FrameAssembler, SampleOnGridPointIsFreshAndExact)
{
    frame_assembler a;
    assembler_init(&a, kRate, kHold, kStale);
    const double t0 = 3.0 / kRate; // 0.05: first sample exactly on a grid point
    imu_sample x = truth_sample(0, t0);
    assembler_push(&a, &x);
    raw_frame f{};
    ASSERT_EQ(assembler_next(&a, t0, &f), 1);
    EXPECT_NEAR(f.t, t0, 1e-12);
    EXPECT_EQ(f.valid_mask, 1u);
    EXPECT_EQ(f.fresh_mask, 1u);
    EXPECT_EQ(f.age[0], 0.0);
    expect_holds(f, 0, x);
    EXPECT_EQ(assembler_next(&a, t0, &f), 0); // the next frame has no data after it yet
}

TEST(FrameAssembler, NeverSeenSensorIsInvalidAndFramesStillFlow)
{
    std::vector<SensorPlan> plans = uniform_plans();
    plans[5].present = false;
    Sim sim;
    sim.run(plans, 2.0, false); // no ticks: frames must come from data alone
    sim.expect_consecutive();
    EXPECT_NEAR((double)sim.frames.size(), 2.0 * kRate, 2.0);
    for (const Emitted &e : sim.frames) {
        EXPECT_EQ(e.f.valid_mask, kAll & ~(1u << 5));
        EXPECT_EQ(e.f.fresh_mask, kAll & ~(1u << 5));
        EXPECT_EQ(e.f.stale_mask, 0u);
        // Emitted as soon as the bracketing samples arrived, not after a hold timeout.
        EXPECT_LE(e.now, e.f.t + 0.01 + 1e-9);
        for (int s = 0; s < 5; s++)
            EXPECT_LT(truth_error(e.f, s), 1e-6);
    }
}

TEST(FrameAssembler, ShortDropoutHoldsAndWaitsAtMostHoldLatency)
{
    const int d = 3;
    std::vector<SensorPlan> plans = uniform_plans();
    plans[d].gap_from = 0.995; // samples 1.00 .. 1.09 missing: 0.1 s
    plans[d].gap_to = 1.095;
    Sim sim;
    sim.run(plans, 2.0, true);
    sim.expect_consecutive();
    const double last = sim.last_before(d, 0.995)->t, resume = sim.first_after(d, 0.995)->t;
    int held = 0, bridged = 0;
    for (const Emitted &e : sim.frames) {
        const raw_frame &f = e.f;
        EXPECT_EQ(f.valid_mask, kAll);
        EXPECT_EQ(f.stale_mask, 0u) << "0.1 s is shorter than stale_after";
        for (int s = 0; s < kSensors; s++)
            if (s != d) {
                EXPECT_LT(truth_error(f, s), 1e-6);
            }
        if (f.t > last + 1e-9 && f.t < resume - 1e-9) {
            EXPECT_EQ(f.fresh_mask & ~(1u << d), kAll & ~(1u << d));
            if (e.now < resume) {
                // Emitted before the sensor came back: it waited the hold latency, no longer.
                held++;
                EXPECT_FALSE(f.fresh_mask & (1u << d));
                EXPECT_GE(e.now, f.t + kHold - 1e-9);
                EXPECT_LE(e.now, f.t + kHold + kTick + 1e-9);
                expect_holds(f, d, *sim.last_before(d, f.t));
                EXPECT_NEAR(f.age[d], f.t - last, 1e-9);
            } else {
                // Still pending when the sensor resumed: bracketed across the short gap.
                bridged++;
                EXPECT_TRUE(f.fresh_mask & (1u << d));
                EXPECT_LT(truth_error(f, d), 1e-6);
            }
        } else {
            EXPECT_EQ(f.fresh_mask, kAll) << "t " << f.t;
            EXPECT_LT(truth_error(f, d), 1e-6);
        }
    }
    EXPECT_GE(held, 3);    // frames at 1.0, 1.0167, 1.0333 are due before the resume
    EXPECT_GE(bridged, 2); // 1.0667 and 1.0833 are not
    EXPECT_GE(held + bridged, 6);
}

TEST(FrameAssembler, LongDropoutIsStaleAndNotInterpolatedAcrossTheGap)
{
    const int d = 2;
    std::vector<SensorPlan> plans = uniform_plans();
    plans[d].gap_from = 0.995; // silent 1.00 .. 1.99
    plans[d].gap_to = 1.995;
    Sim sim;
    sim.run(plans, 3.0, true);
    sim.expect_consecutive();
    const double last = sim.last_before(d, 0.995)->t, resume = sim.first_after(d, 0.995)->t;
    int stale = 0;
    for (size_t i = 0; i < sim.frames.size(); i++) {
        const raw_frame &f = sim.frames[i].f;
        if (i > 0) {
            EXPECT_NEAR(f.t - sim.frames[i - 1].f.t, kPeriod, 1e-9) << "no gap: others flow";
        }
        EXPECT_EQ(f.fresh_mask & ~(1u << d), kAll & ~(1u << d));
        EXPECT_EQ(f.stale_mask & ~(1u << d), 0u);
        if (f.t > last + 1e-9 && f.t < resume - 1e-9) {
            EXPECT_FALSE(f.fresh_mask & (1u << d));
            expect_holds(f, d, *sim.last_before(d, f.t));
            EXPECT_NEAR(f.age[d], f.t - last, 1e-9);
            const bool is_stale = (f.stale_mask >> d) & 1u;
            EXPECT_EQ(is_stale, f.t - last > kStale) << "t " << f.t;
            stale += is_stale;
            // Waited for the missing sensor up to hold_latency (or until it came back), no
            // longer; a frame that was still pending at the resume is held, not bridged. Once
            // the sensor is stale it is gone: frames go out as soon as the others are in.
            if (sim.frames[i].now < resume) {
                if (is_stale) // frames go out in order: one may queue behind the last wait
                    EXPECT_LE(sim.frames[i].now,
                              std::max(f.t + 0.0101, sim.frames[i - 1].now + 1e-9))
                        << "no waiting for a gone sensor";
                else
                    EXPECT_GE(sim.frames[i].now, f.t + kHold - 1e-9);
            }
            EXPECT_LE(sim.frames[i].now, f.t + kHold + kTick + 1e-9);
        } else if (f.t >= resume) {
            EXPECT_TRUE(f.fresh_mask & (1u << d));
            EXPECT_LT(truth_error(f, d), 1e-6);
        }
    }
    EXPECT_GT(stale, 35); // about (1.0 - 0.25) s at 60 Hz
}

TEST(FrameAssembler, AllSilentThenResumeLeavesGapWithConsecutiveSequences)
{
    std::vector<SensorPlan> plans = uniform_plans(0.004);
    for (SensorPlan &p : plans) {
        p.gap_from = 1.0; // last sample 0.994, resume 3.004
        p.gap_to = 3.0;
    }
    Sim sim;
    sim.run(plans, 4.0, true);
    sim.expect_consecutive();
    const double last = 0.994, resume = 3.004;
    const double first_after = std::ceil(resume * kRate) / kRate;
    size_t gap_at = 0;
    for (size_t i = 0; i < sim.frames.size(); i++) {
        const raw_frame &f = sim.frames[i].f;
        ASSERT_TRUE(on_grid(f.t));
        // Nothing while every sensor is stale: only held frames until stale_after.
        EXPECT_FALSE(f.t > last + kStale && f.t < resume) << "frame in the silence at " << f.t;
        EXPECT_EQ(f.stale_mask, 0u);
        if (i > 0 && f.t - sim.frames[i - 1].f.t > 1.5 * kPeriod) {
            EXPECT_EQ(gap_at, 0u) << "one gap only";
            gap_at = i;
        }
    }
    ASSERT_GT(gap_at, 0u);
    EXPECT_NEAR(sim.frames[gap_at].f.t, first_after, 1e-9);
    EXPECT_LE(sim.frames[gap_at - 1].f.t, last + kStale);
    EXPECT_GT(sim.frames[gap_at - 1].f.t, last + kStale - kPeriod);
    for (size_t i = gap_at; i < sim.frames.size(); i++) {
        EXPECT_EQ(sim.frames[i].f.fresh_mask, kAll);
        for (int s = 0; s < kSensors; s++)
            EXPECT_LT(truth_error(sim.frames[i].f, s), 1e-6);
    }
    // After the gap frames continue for the remaining second.
    EXPECT_NEAR((double)(sim.frames.size() - gap_at), (4.0 - first_after) * kRate, 2.0);
}

TEST(FrameAssembler, SilenceWithoutTicksStillJumpsTheGap)
{
    // No timer at all: the grid must not crawl through the silence one held frame at a time
    // when data resumes.
    std::vector<SensorPlan> plans = uniform_plans();
    for (SensorPlan &p : plans) {
        p.gap_from = 0.5;
        p.gap_to = 2.5;
    }
    Sim sim;
    sim.run(plans, 3.0, false);
    sim.expect_consecutive();
    for (const Emitted &e : sim.frames)
        EXPECT_FALSE(e.f.t > 0.49 + kStale && e.f.t < 2.5) << e.f.t;
    ASSERT_FALSE(sim.frames.empty());
    EXPECT_GE(sim.frames.back().f.t, 2.9);
    for (const Emitted &e : sim.frames)
        if (e.f.t >= 2.5) {
            EXPECT_EQ(e.f.fresh_mask, kAll) << e.f.t;
        }
}

TEST(FrameAssembler, OutOfOrderAndDuplicateSamplesAreDroppedAndCounted)
{
    frame_assembler a;
    assembler_init(&a, kRate, kHold, kStale);
    const double times[] = {0.00, 0.01, 0.02, 0.03};
    for (double t : times) {
        imu_sample x = truth_sample(0, t);
        assembler_push(&a, &x);
        if (t == 0.01) {
            imu_sample bad = truth_sample(0, 0.01); // duplicate time, wrong content
            bad.quat[0] = 0.0;
            bad.quat[1] = 1.0;
            bad.quat[2] = bad.quat[3] = 0.0;
            bad.force_world[0] = 1e6;
            assembler_push(&a, &bad);
            bad.t = 0.005; // older than the newest
            assembler_push(&a, &bad);
        }
    }
    imu_sample older = truth_sample(0, -1.0);
    older.gyr[1] = -1e6;
    assembler_push(&a, &older);
    EXPECT_EQ(a.out_of_order, 3u);
    EXPECT_EQ(a.tracks[0].count, 4u);

    raw_frame f{};
    std::vector<raw_frame> out;
    while (assembler_next(&a, 0.03, &f))
        out.push_back(f);
    ASSERT_EQ(out.size(), 2u); // 0 and 1/60; 2/60 = 0.0333 has no later sample yet
    for (const raw_frame &g : out) {
        EXPECT_EQ(g.fresh_mask, 1u);
        EXPECT_LT(truth_error(g, 0), 1e-6);
    }
}

TEST(FrameAssembler, InvalidSegmentIsIgnored)
{
    frame_assembler a;
    assembler_init(&a, kRate, kHold, kStale);
    imu_sample x = truth_sample(0, 0.1);
    x.segment = MOCAP_MAX_SENSORS;
    assembler_push(&a, &x);
    x.segment = -1;
    assembler_push(&a, &x);
    raw_frame f{};
    EXPECT_EQ(assembler_next(&a, 100.0, &f), 0);
    EXPECT_EQ(a.started, 0);
}

// A full gateway: every one of the MOCAP_MAX_SENSORS slots is waited for and interpolated.
TEST(FrameAssembler, EverySlotUpToTheMaximumIsAssembled)
{
    frame_assembler a;
    assembler_init(&a, kRate, kHold, kStale);
    std::vector<raw_frame> out;
    for (int k = 0; k <= 100; k++) {
        const double t = 0.01 * k;
        for (int s = 0; s < MOCAP_MAX_SENSORS; s++) {
            imu_sample x = truth_sample(s, t);
            assembler_push(&a, &x);
        }
        raw_frame f{};
        while (assembler_next(&a, t, &f)) out.push_back(f);
    }
    ASSERT_GE(out.size(), 55u);
    const uint32_t all = (uint32_t)((1ull << MOCAP_MAX_SENSORS) - 1);
    for (const raw_frame &g : out) {
        EXPECT_EQ(g.fresh_mask, all) << "t " << g.t;
        EXPECT_EQ(g.valid_mask, all);
        for (int s = 0; s < MOCAP_MAX_SENSORS; s++) {
            EXPECT_LT(truth_error(g, s), 1e-3) << "sensor " << s << " t " << g.t;
            EXPECT_EQ(g.node_id[s], 0x60u + (uint32_t)s);
        }
    }
}

TEST(FrameAssembler, EmitterFarBehindUsesWhatRemainsOfTheHistory)
{
    // 1 s of samples pushed before any frame is asked for: the history keeps only the newest
    // ASSEMBLER_HISTORY per sensor, and early frames must use the oldest that remain.
    Sim sim;
    for (int k = 0; k < 100; k++)
        for (int s = 0; s < kSensors; s++)
            sim.push(truth_sample(s, k * 0.01));
    const double oldest = (100 - ASSEMBLER_HISTORY) * 0.01;
    sim.drain(0.99);
    ASSERT_FALSE(sim.frames.empty());
    sim.expect_consecutive();
    EXPECT_EQ(sim.frames[0].f.t, 0.0);
    for (const Emitted &e : sim.frames) {
        const raw_frame &f = e.f;
        EXPECT_LE(f.t, 0.99 + 1e-9);
        EXPECT_EQ(f.valid_mask, kAll);
        for (int s = 0; s < kSensors; s++) {
            if (f.t < oldest - 1e-9) {
                EXPECT_FALSE(f.fresh_mask & (1u << s));
                expect_holds(f, s, truth_sample(s, oldest));
            } else {
                EXPECT_TRUE(f.fresh_mask & (1u << s));
                EXPECT_LT(truth_error(f, s), 1e-6);
            }
        }
    }
}

TEST(FrameAssembler, LongRunFrameCountAndNoDrift)
{
    const double duration = 120.0;
    std::vector<SensorPlan> plans = uniform_plans(0.0005);
    for (int s = 0; s < kSensors; s++)
        plans[s].jitter = 0.002 + 0.0003 * s;
    plans[1].rate = 99.9; // a slightly slow sensor clock
    Sim sim;
    sim.run(plans, duration, false);
    sim.expect_consecutive();
    const size_t n = sim.frames.size();
    const double t0 = sim.frames.front().f.t;
    EXPECT_NEAR((double)n, duration * kRate, 1.0);
    // Frame times are grid points, computed from an index: no accumulated error.
    EXPECT_NEAR(sim.frames.back().f.t - t0, (double)(n - 1) * kPeriod, 1e-9);
    EXPECT_TRUE(on_grid(sim.frames.back().f.t));
    size_t bad = 0, partial = 0;
    for (const Emitted &e : sim.frames) {
        // With jitter a sensor's first sample can land after the first frame was due.
        if (e.f.valid_mask != kAll || e.f.fresh_mask != kAll) {
            partial++;
            continue;
        }
        for (int s = 0; s < kSensors; s++)
            bad += truth_error(e.f, s) >= 1e-6;
    }
    EXPECT_LE(partial, 2u);
    EXPECT_EQ(bad, 0u);
}

} // namespace
