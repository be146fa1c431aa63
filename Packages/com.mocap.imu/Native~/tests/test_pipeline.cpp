// End to end without threads: generated HiPNUC bytes -> decode -> condition -> Kalman ->
// assemble -> calibrate, scored against the generator's ground truth.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <string>

#include "e2e_support.h"

extern "C" {
#include "pipeline.h"
}

namespace {

constexpr int kSensors = 6; // the default set, sensor i on segment i

struct PipelineRun {
    std::unique_ptr<pipeline> p{new pipeline()};
    std::vector<mocap_frame> frames;
    mocap_calibration_report heading_report{};
    mocap_calibration_report tpose_report{};
};

void on_frame(void *user, const mocap_frame *f) { static_cast<PipelineRun *>(user)->frames.push_back(*f); }

mocap_session_config default_config()
{
    mocap_session_config c;
    mocap_config_defaults(&c);
    c.source_kind = MOCAP_SOURCE_REPLAY;
    return c;
}

// Feeds a generated stream through one pipeline, running the two calibration steps inside the
// prelude windows (their middle, leaving 0.5 s at each edge) the way mocapctl replay does.
// `session`: the session's config (sensor set ...), default_config() when NULL.
void run_stream(const synth_config &cfg, const std::vector<GeneratedPacket> &packets, PipelineRun &run,
                double tpose_window_start = -1.0, size_t chunk = 0,
                const mocap_session_config *session = nullptr)
{
    mocap_session_config config = session ? *session : default_config();
    config.world_frame = cfg.world_frame;
    pipeline_init(run.p.get(), &config, on_frame, &run);
    double t0 = synth_session_time(&cfg, 0.0);
    pipeline_calibration_schedule(run.p.get(), MOCAP_CALIBRATION_HEADING, t0 + 0.5,
                                  (float)(cfg.heading_s - 1.0));
    if (tpose_window_start < 0) tpose_window_start = cfg.heading_s + cfg.strap_s + 0.5;
    int stage = 0;
    for (const auto &packet : packets) {
        if (packet.info.dropped) continue;
        if (chunk == 0) {
            pipeline_feed(run.p.get(), packet.bytes.data(), packet.bytes.size(), packet.info.receive_ns);
        } else {
            for (size_t i = 0; i < packet.bytes.size(); i += chunk)
                pipeline_feed(run.p.get(), packet.bytes.data() + i,
                              std::min(chunk, packet.bytes.size() - i), packet.info.receive_ns);
        }
        const mocap_calibration_report &rep = run.p->report;
        bool done = rep.state == MOCAP_CALIBRATION_ACCEPTED || rep.state == MOCAP_CALIBRATION_REFUSED;
        if (stage == 0 && done) {
            run.heading_report = rep;
            pipeline_calibration_schedule(run.p.get(), MOCAP_CALIBRATION_TPOSE,
                                          t0 + tpose_window_start, (float)(cfg.tpose_s - 1.0));
            stage = 1;
        } else if (stage == 1 && done) {
            run.tpose_report = rep;
            stage = 2;
        }
    }
    pipeline_finish(run.p.get(), packets.back().info.receive_ns + 2000000000LL);
}

synth_config base_config(uint64_t seed, int world)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = seed;
    cfg.world_frame = world;
    cfg.motion_s = 12.0;
    cfg.start_receive_ns = 5000000000LL;
    return cfg;
}

ErrorStats score(const synth_config &cfg, const std::vector<GeneratedPacket> &packets, const PipelineRun &run)
{
    TruthTrack truth(cfg, packets);
    ErrorStats stats;
    for (const auto &f : run.frames) score_frame(truth, f, stats);
    return stats;
}

}  // namespace

// Noise-free data: what is left is interpolation to the 60 Hz grid (slerp between 100 Hz
// samples is exact for constant angular velocity; the motions' angular accelerations of up to a
// few hundred deg/s^2 give < 0.05 deg) and float rounding.
TEST(Pipeline, RecoversBoneOrientationsExactlyWithoutNoiseInBothWorldFrames)
{
    for (int world : {MOCAP_WORLD_NWU, MOCAP_WORLD_ENU}) {
        synth_config cfg = base_config(11, world);
        auto packets = generate(cfg);
        ASSERT_GT(packets.size(), 1500u);
        PipelineRun run;
        run_stream(cfg, packets, run);
        ASSERT_EQ(run.heading_report.state, MOCAP_CALIBRATION_ACCEPTED) << run.heading_report.reason;
        ASSERT_EQ(run.tpose_report.state, MOCAP_CALIBRATION_ACCEPTED) << run.tpose_report.reason;
        ErrorStats stats = score(cfg, packets, run);
        for (int s = 0; s < kSensors; ++s) {
            SCOPED_TRACE(std::string(mocap_segment_name(s)) + (world ? " ENU" : " NWU"));
            ASSERT_GT(stats.count(s), 600u);  // ~12 s of motion at 60 Hz
            EXPECT_LT(stats.mean(s), 0.05);
            EXPECT_LT(stats.max(s), 0.3);
        }
    }
}

// Realistic noise: 0.3 deg orientation noise per axis (about 0.5 deg of angle), 0.2 deg tremor
// and 0.01 g bias during calibration. Calibration averages ~120 frames so its own error is
// small; the per-frame error is dominated by the sensor's orientation noise, so a mean under
// 1 deg and a maximum under 3.5 deg (beyond 6 sigma of the per-axis noise) are the bounds.
TEST(Pipeline, RecoversBoneOrientationsWithRealisticNoise)
{
    synth_config cfg = base_config(12, MOCAP_WORLD_ENU);
    add_realistic_noise(cfg);
    cfg.heading_spread_deg = 180.0;
    auto packets = generate(cfg);
    PipelineRun run;
    run_stream(cfg, packets, run);
    ASSERT_EQ(run.tpose_report.state, MOCAP_CALIBRATION_ACCEPTED) << run.tpose_report.reason;
    ErrorStats stats = score(cfg, packets, run);
    for (int s = 0; s < kSensors; ++s) {
        SCOPED_TRACE(mocap_segment_name(s));
        ASSERT_GT(stats.count(s), 600u);
        EXPECT_LT(stats.mean(s), 1.0);
        EXPECT_LT(stats.max(s), 3.5);
        // Gravity and bias removed: the residual is far below the motion's own acceleration.
        EXPECT_LT(stats.acc_rms(s), 0.35 * stats.acc_truth_rms(s) + 0.3);
    }
}

// The world convention only changes each sensor's yaw: with identical noise the calibrated
// output must be the same whether the sensors report NWU or ENU.
TEST(Pipeline, OutputDoesNotDependOnWorldConvention)
{
    PipelineRun runs[2];
    for (int world : {MOCAP_WORLD_NWU, MOCAP_WORLD_ENU}) {
        synth_config cfg = base_config(13, world);
        add_realistic_noise(cfg);
        cfg.motion_s = 5.0;
        run_stream(cfg, generate(cfg), runs[world]);
        ASSERT_EQ(runs[world].tpose_report.state, MOCAP_CALIBRATION_ACCEPTED);
    }
    ASSERT_EQ(runs[0].frames.size(), runs[1].frames.size());
    double worst = 0;
    for (size_t i = 0; i < runs[0].frames.size(); ++i) {
        for (int s = 0; s < kSensors; ++s) {
            const float *a = runs[0].frames[i].sensors[s].bone_orientation;
            const float *b = runs[1].frames[i].sensors[s].bone_orientation;
            double qa[4] = {a[0], a[1], a[2], a[3]}, qb[4] = {b[0], b[1], b[2], b[3]};
            worst = std::max(worst, quat_angle_deg(qa, qb));
        }
    }
    EXPECT_LT(worst, 0.05);
}

// Byte-level faults: 1% corrupted bytes and 3% dropped nodes. Frames keep flowing at the output
// rate, calibration still succeeds, and accuracy holds on the frames whose sensors were fresh.
TEST(Pipeline, SurvivesCorruptedBytesAndDroppedNodes)
{
    synth_config cfg = base_config(14, MOCAP_WORLD_NWU);
    add_realistic_noise(cfg);
    cfg.corrupt_byte_prob = 0.001;
    cfg.node_dropout_prob = 0.03;
    cfg.packet_dropout_prob = 0.01;
    auto packets = generate(cfg);
    PipelineRun run;
    run_stream(cfg, packets, run, -1.0, 37);
    ASSERT_EQ(run.tpose_report.state, MOCAP_CALIBRATION_ACCEPTED) << run.tpose_report.reason;
    // Frames cover the stream, plus held frames until the sensors go stale after the end.
    const double duration = packets.back().info.t;
    EXPECT_GE((double)run.frames.size(), duration * 60.0 - 2.0);
    EXPECT_LE((double)run.frames.size(), (duration + run.p->config.stale_after_s) * 60.0 + 2.0);
    for (size_t i = 1; i < run.frames.size(); ++i)
        ASSERT_EQ(run.frames[i].sequence, run.frames[i - 1].sequence + 1);
    EXPECT_GT(run.p->decoder.stats.crc_failures, 0u);
    ErrorStats stats = score(cfg, packets, run);
    for (int s = 0; s < kSensors; ++s) {
        SCOPED_TRACE(mocap_segment_name(s));
        EXPECT_LT(stats.mean(s), 1.0);
    }
}

// Moving during the T-pose window must be refused, and the refusal must leave the heading
// calibration in place and no sensor marked as calibrated.
TEST(Pipeline, RefusesATposeTakenWhileMoving)
{
    synth_config cfg = base_config(15, MOCAP_WORLD_NWU);
    cfg.motion_s = 6.0;
    auto packets = generate(cfg);
    PipelineRun run;
    double motion_start = cfg.heading_s + cfg.strap_s + cfg.tpose_s;
    run_stream(cfg, packets, run, motion_start + 1.0);
    ASSERT_EQ(run.heading_report.state, MOCAP_CALIBRATION_ACCEPTED);
    ASSERT_EQ(run.tpose_report.state, MOCAP_CALIBRATION_REFUSED);
    EXPECT_NE(std::string(run.tpose_report.reason).find("deg"), std::string::npos)
        << run.tpose_report.reason;
    EXPECT_EQ(run.p->calibration.valid_mask, 0u);
    EXPECT_EQ(run.p->calibration.heading_mask, 0x3Fu);
    for (const auto &f : run.frames) ASSERT_FALSE(f.flags & MOCAP_FRAME_CALIBRATED);
}

// A sensor missing from the stream: the other five calibrate and track, the frame says who is
// missing, and a calibration that needs all six names the absent segment.
TEST(Pipeline, MissingSensorIsFlaggedAndNamed)
{
    synth_config cfg = base_config(16, MOCAP_WORLD_NWU);
    cfg.motion_s = 4.0;
    cfg.node_ids[MOCAP_SEGMENT_HEAD] = 40;  // the engine expects node 5 for the head
    auto packets = generate(cfg);
    PipelineRun run;
    run_stream(cfg, packets, run);
    EXPECT_EQ(run.heading_report.state, MOCAP_CALIBRATION_REFUSED);
    EXPECT_NE(std::string(run.heading_report.reason).find("head"), std::string::npos)
        << run.heading_report.reason;
    ASSERT_FALSE(run.frames.empty());
    const mocap_frame &last = run.frames.back();
    EXPECT_EQ(last.sensors[MOCAP_SEGMENT_HEAD].flags & MOCAP_SENSOR_VALID, 0u);
    EXPECT_EQ(last.fresh_mask & (1u << MOCAP_SEGMENT_HEAD), 0u);
    EXPECT_GT(run.p->counters.unknown_nodes, 0u);
    for (int s = 0; s < MOCAP_SEGMENT_HEAD; ++s) EXPECT_TRUE(last.sensors[s].flags & MOCAP_SENSOR_VALID);
}

// Steps queue: one whose window began while the step before it was still collecting starts when
// that one finishes and keeps its whole duration; its own report shows it collecting, not only
// waiting and then its result.
TEST(Pipeline, AQueuedStepStartsAfterTheOneBeforeAndKeepsItsDuration)
{
    synth_config cfg = base_config(41, MOCAP_WORLD_ENU);
    cfg.motion_s = 1.0;
    auto packets = generate(cfg);
    PipelineRun run;
    mocap_session_config config = default_config();
    config.world_frame = cfg.world_frame;
    pipeline_init(run.p.get(), &config, on_frame, &run);
    const double t0 = synth_session_time(&cfg, 0.0);
    // Two heading steps while the sensors lie still (0..3 s): the second window [1.0, 2.0]
    // overlaps the first [0.5, 1.5].
    ASSERT_EQ(pipeline_calibration_schedule(run.p.get(), MOCAP_CALIBRATION_HEADING, t0 + 0.5, 1.0f), MOCAP_OK);
    ASSERT_EQ(pipeline_calibration_schedule(run.p.get(), MOCAP_CALIBRATION_HEADING, t0 + 1.0, 1.0f), MOCAP_OK);
    int collecting_reports = 0, first_accepted = 0;
    for (const auto &packet : packets) {
        if (packet.info.dropped) continue;
        pipeline_feed(run.p.get(), packet.bytes.data(), packet.bytes.size(), packet.info.receive_ns);
        const mocap_calibration_report &now = run.p->step_reports[MOCAP_CALIBRATION_HEADING];
        if (now.state == MOCAP_CALIBRATION_COLLECTING) ++collecting_reports;
        if (run.p->calibration.heading_mask == 0x3F && !first_accepted) first_accepted = 1;
    }
    pipeline_finish(run.p.get(), packets.back().info.receive_ns + 2000000000LL);
    EXPECT_TRUE(first_accepted);
    const mocap_calibration_report &second = run.p->step_reports[MOCAP_CALIBRATION_HEADING];
    ASSERT_EQ(second.state, MOCAP_CALIBRATION_ACCEPTED) << second.reason;
    // The step's report followed it while it collected (each packet is one 100 Hz sample).
    EXPECT_GT(collecting_reports, 100);
    // A whole second at 60 Hz, not the half second left of its scheduled window.
    for (int s = 0; s < kSensors; ++s) EXPECT_GE(second.sensors[s].samples, 58u) << s;
}

// Older chained firmware sends no sensor time: the samples of one read share its receive time.
// A read holding several samples of a sensor (USB latency, a late reader) must lose none.
// Sensor-timed samples arriving five times faster than the sensors made them, ten frames per
// read (a backlog, a receiver catching up): none may be refused as older than the one before.
TEST(Pipeline, TimedSamplesDeliveredFasterThanRealTimeAreAllKept)
{
    synth_config cfg = base_config(71, MOCAP_WORLD_NWU);
    cfg.motion_s = 2.0;
    std::vector<GeneratedPacket> packets = generate(cfg);
    PipelineRun run;
    mocap_session_config config = default_config();
    pipeline_init(run.p.get(), &config, on_frame, &run);
    int64_t receive_ns = 1000000000LL;
    uint64_t samples = 0;
    std::vector<uint8_t> bytes;
    for (size_t i = 0; i < packets.size(); ++i) {
        bytes.insert(bytes.end(), packets[i].bytes.begin(), packets[i].bytes.end());
        samples += kSensors;
        if (bytes.size() && (i % 10 == 9 || i + 1 == packets.size())) {
            pipeline_feed(run.p.get(), bytes.data(), bytes.size(), receive_ns);
            bytes.clear();
            receive_ns += 20000000LL;
        }
    }
    pipeline_finish(run.p.get(), receive_ns + 2000000000LL);
    EXPECT_EQ(run.p->counters.samples_rejected, 0u);
    EXPECT_EQ(run.p->counters.samples_decoded, samples);
    ASSERT_GT(run.frames.size(), 10u);
    for (size_t i = 1; i < run.frames.size(); ++i)
        ASSERT_GT(run.frames[i].time_s, run.frames[i - 1].time_s) << "frame " << i;
}

TEST(Pipeline, SamplesWithoutSensorTimeInOneReadAreAllKept)
{
    PipelineRun run;
    mocap_session_config config = default_config();
    pipeline_init(run.p.get(), &config, on_frame, &run);
    int64_t receive_ns = 1000000000LL;
    for (int read = 0; read < 20; ++read, receive_ns += 30000000LL) {
        std::vector<uint8_t> bytes;
        for (int k = 0; k < 3; ++k) {          // three samples of each sensor in this read
            for (uint8_t node = 0; node < kSensors; ++node) {
                uint8_t payload[2 + 1 + 16] = {HIPNUC_TAG_ID, node, HIPNUC_TAG_QUAT};
                const float q[4] = {1.0f, 0.0f, 0.0f, 0.0f};
                std::memcpy(payload + 3, q, sizeof q);
                uint8_t frame[64];
                size_t n = hipnuc_encode_frame(payload, sizeof payload, frame, sizeof frame);
                ASSERT_GT(n, 0u);
                bytes.insert(bytes.end(), frame, frame + n);
            }
        }
        pipeline_feed(run.p.get(), bytes.data(), bytes.size(), receive_ns);
    }
    EXPECT_EQ(run.p->counters.samples_decoded, 20u * 3u * kSensors);
    EXPECT_EQ(run.p->counters.samples_rejected, 0u);
    EXPECT_EQ(run.p->assembler.out_of_order, 0u);
    EXPECT_GT(run.frames.size(), 20u);  // 0.6 s at 60 Hz, less the hold at the end
}

namespace {

// The default set plus a chest sensor on node 6, in the generator and in the session.
synth_config seven_sensor_capture(uint64_t seed, int world)
{
    synth_config cfg = base_config(seed, world);
    cfg.sensor_count = 7;
    cfg.segments[6] = MOCAP_SEGMENT_CHEST;
    cfg.node_ids[6] = 6;
    return cfg;
}

mocap_session_config seven_sensor_session(uint32_t optional_mask = 0)
{
    mocap_session_config c = default_config();
    c.sensor_count = 7;
    c.sensor_segments[6] = MOCAP_SEGMENT_CHEST;
    c.node_ids[6] = 6;
    c.optional_mask = optional_mask;
    return c;
}

}  // namespace

// Seven sensors, the chest on node 6: both calibration steps accept every sensor, the chest
// included, and its bone follows the generator's chest truth within the six-sensor bounds (noise
// free: mean 0.05 deg, max 0.3 deg). Frames list the sensors in config order, each with its
// segment, node and state.
TEST(Pipeline, SevenSensorsWithAChestCalibrateAndTrack)
{
    for (int world : {MOCAP_WORLD_NWU, MOCAP_WORLD_ENU}) {
        synth_config cfg = seven_sensor_capture(21, world);
        auto packets = generate(cfg);
        ASSERT_GT(packets.size(), 1500u);
        const mocap_session_config session = seven_sensor_session();
        PipelineRun run;
        run_stream(cfg, packets, run, -1.0, 0, &session);
        ASSERT_EQ(run.heading_report.state, MOCAP_CALIBRATION_ACCEPTED) << run.heading_report.reason;
        ASSERT_EQ(run.tpose_report.state, MOCAP_CALIBRATION_ACCEPTED) << run.tpose_report.reason;
        ASSERT_EQ(run.tpose_report.sensor_count, 7u);
        for (int s = 0; s < 7; ++s) {
            EXPECT_EQ(run.tpose_report.sensors[s].segment, session.sensor_segments[s]);
            EXPECT_TRUE(run.tpose_report.sensors[s].ok) << s;
            EXPECT_FALSE(run.tpose_report.sensors[s].left_out) << s;
        }
        EXPECT_EQ(run.p->calibration.valid_mask, 0x7Fu);
        EXPECT_EQ(run.p->calibration.sensor_count, 7u);
        EXPECT_EQ(run.p->calibration.segments[6], MOCAP_SEGMENT_CHEST);

        ErrorStats stats = score(cfg, packets, run);
        for (int s = 0; s < 7; ++s) {
            SCOPED_TRACE(std::string(mocap_segment_name(session.sensor_segments[s])) + (world ? " ENU" : " NWU"));
            ASSERT_GT(stats.count(s), 600u);
            EXPECT_LT(stats.mean(s), 0.05);
            EXPECT_LT(stats.max(s), 0.3);
        }
        // The chest is scored against its own truth: against the pelvis's it would be off.
        TruthTrack truth(cfg, packets);
        double chest_vs_pelvis = 0;
        size_t calibrated = 0;
        for (const mocap_frame &f : run.frames) {
            ASSERT_EQ(f.sensor_count, 7u);
            for (int s = 0; s < 7; ++s) {
                EXPECT_EQ(f.sensors[s].segment, session.sensor_segments[s]);
                EXPECT_EQ(f.sensors[s].node_id, (uint32_t)session.node_ids[s]);
            }
            for (int s = 7; s < MOCAP_MAX_SENSORS; ++s) EXPECT_EQ(f.sensors[s].flags, 0u);
            if (!(f.flags & MOCAP_FRAME_CALIBRATED)) continue;
            ++calibrated;
            if (f.fresh_mask & (1u << 6)) { EXPECT_EQ(f.sensors[6].state, MOCAP_SENSOR_FRESH); }
            EXPECT_TRUE(f.sensors[6].flags & MOCAP_SENSOR_CALIBRATED);
            synth_pose pose;
            int phase = -1;
            if (!truth.at(f.time_s, pose, phase) || phase != 3) continue;
            const float *q = f.sensors[6].bone_orientation;
            double qd[4] = {q[0], q[1], q[2], q[3]};
            chest_vs_pelvis = std::max(chest_vs_pelvis, quat_angle_deg(qd, pose.bone_quat[MOCAP_SEGMENT_PELVIS]));
        }
        EXPECT_GT(calibrated, 600u);
        EXPECT_GT(chest_vs_pelvis, 3.0);
    }
}

// The same with realistic noise: the six-sensor bounds (mean 1 deg, max 3.5 deg) hold for the chest.
TEST(Pipeline, SevenSensorsWithAChestWithRealisticNoise)
{
    synth_config cfg = seven_sensor_capture(22, MOCAP_WORLD_ENU);
    add_realistic_noise(cfg);
    auto packets = generate(cfg);
    const mocap_session_config session = seven_sensor_session();
    PipelineRun run;
    run_stream(cfg, packets, run, -1.0, 0, &session);
    ASSERT_EQ(run.tpose_report.state, MOCAP_CALIBRATION_ACCEPTED) << run.tpose_report.reason;
    ErrorStats stats = score(cfg, packets, run);
    for (int s = 0; s < 7; ++s) {
        SCOPED_TRACE(mocap_segment_name(session.sensor_segments[s]));
        ASSERT_GT(stats.count(s), 600u);
        EXPECT_LT(stats.mean(s), 1.0);
        EXPECT_LT(stats.max(s), 3.5);
        EXPECT_LT(stats.acc_rms(s), 0.35 * stats.acc_truth_rms(s) + 0.3);
    }
}

// The chest configured but silent (the capture has no node 6). Optional: both steps accept the
// six and leave the chest out, frames are MOCAP_FRAME_CALIBRATED and the chest ABSENT. Required:
// the heading step is refused naming the chest, and nothing is calibrated.
TEST(Pipeline, ASilentChestIsLeftOutWhenOptionalAndRefusedWhenRequired)
{
    synth_config cfg = base_config(23, MOCAP_WORLD_NWU); // six sensors sending
    cfg.motion_s = 4.0;
    auto packets = generate(cfg);
    {
        const mocap_session_config session = seven_sensor_session(1u << 6);
        PipelineRun run;
        run_stream(cfg, packets, run, -1.0, 0, &session);
        ASSERT_EQ(run.heading_report.state, MOCAP_CALIBRATION_ACCEPTED) << run.heading_report.reason;
        ASSERT_EQ(run.tpose_report.state, MOCAP_CALIBRATION_ACCEPTED) << run.tpose_report.reason;
        for (const mocap_calibration_report *rep : {&run.heading_report, &run.tpose_report}) {
            ASSERT_EQ(rep->sensor_count, 7u);
            EXPECT_EQ(rep->sensors[6].segment, MOCAP_SEGMENT_CHEST);
            EXPECT_EQ(rep->sensors[6].left_out, 1);
            for (int s = 0; s < 6; ++s) {
                EXPECT_EQ(rep->sensors[s].left_out, 0) << s;
                EXPECT_TRUE(rep->sensors[s].ok) << s;
            }
        }
        EXPECT_EQ(run.p->calibration.valid_mask, 0x3Fu);
        ASSERT_FALSE(run.frames.empty());
        const mocap_frame &last = run.frames.back();
        EXPECT_TRUE(last.flags & MOCAP_FRAME_CALIBRATED);
        EXPECT_EQ(last.sensor_count, 7u);
        EXPECT_EQ(last.sensors[6].segment, MOCAP_SEGMENT_CHEST);
        EXPECT_EQ(last.sensors[6].state, MOCAP_SENSOR_ABSENT);
        EXPECT_FALSE(last.sensors[6].flags & (MOCAP_SENSOR_VALID | MOCAP_SENSOR_CALIBRATED));
        ErrorStats stats = score(cfg, packets, run);
        EXPECT_EQ(stats.count(6), 0u);
        for (int s = 0; s < 6; ++s) EXPECT_GT(stats.count(s), 100u) << s;
    }
    {
        const mocap_session_config session = seven_sensor_session(0);
        PipelineRun run;
        run_stream(cfg, packets, run, -1.0, 0, &session);
        EXPECT_EQ(run.heading_report.state, MOCAP_CALIBRATION_REFUSED);
        EXPECT_NE(std::string(run.heading_report.reason).find("chest"), std::string::npos)
            << run.heading_report.reason;
        EXPECT_EQ(run.p->calibration.heading_mask, 0u);
        EXPECT_EQ(run.p->calibration.valid_mask, 0u);
        for (const auto &f : run.frames) ASSERT_FALSE(f.flags & MOCAP_FRAME_CALIBRATED);
    }
}
