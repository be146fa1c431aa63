// The threaded session through the public API: a replayed capture, and a live stream written in
// real time into a real pseudo-terminal (the engine opens the slave as its serial port; closing
// the master is an unplug).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>

#if !defined(_WIN32)
#include <csignal>
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#endif

#include "e2e_support.h"
#if !defined(_WIN32)
#include "fake_receiver.h"
#endif
#include "test_support.h"

extern "C" {
#include "calibration.h"
#include "capture_file.h"
#include "error.h"
#include "hipnuc_decoder.h"
#include "platform.h"
}

namespace {

constexpr int kSensors = 6; // the default set, sensor i on segment i

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0)
{
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

mocap_session_config serial_config(const std::string &port)
{
    mocap_session_config c;
    mocap_config_defaults(&c);
    c.source_kind = MOCAP_SOURCE_SERIAL;
    snprintf(c.path, sizeof c.path, "%s", port.c_str());
    c.baud = 460800;
    return c;
}

mocap_session_config replay_config(const std::string &path)
{
    mocap_session_config c;
    mocap_config_defaults(&c);
    c.source_kind = MOCAP_SOURCE_REPLAY;
    snprintf(c.path, sizeof c.path, "%s", path.c_str());
    return c;
}

// A walk capture with a short calibration prelude (1.2 s) before motion_s of motion.
bool write_short_walk(const std::string &path, uint32_t seed, double motion_s)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = seed;
    cfg.heading_s = 0.5;
    cfg.strap_s = 0.2;
    cfg.tpose_s = 0.5;
    cfg.motion_s = motion_s;
    return synth_write_capture(&cfg, synth_builtin_motion("walk"), nullptr, path.c_str(), nullptr) == MOCAP_OK;
}

struct SessionCloser {
    mocap_session *s = nullptr;
    ~SessionCloser() { mocap_session_close(s); }
};

// Drains frames until pred(stats, last frame) holds or the timeout passes.
template <typename Pred>
bool wait_until(mocap_session *s, double timeout_s, std::vector<mocap_frame> *frames, Pred pred)
{
    auto t0 = Clock::now();
    std::vector<mocap_frame> buf(64);
    while (seconds_since(t0) < timeout_s) {
        uint32_t n = 0;
        mocap_session_drain(s, buf.data(), (uint32_t)buf.size(), &n);
        if (frames) frames->insert(frames->end(), buf.begin(), buf.begin() + n);
        mocap_session_stats st;
        mocap_session_get_stats(s, &st);
        if (pred(st)) return true;
        if (n == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return false;
}

[[maybe_unused]] bool wait_for_calibration(mocap_session *s, double timeout_s, std::vector<mocap_frame> *frames,
                          mocap_calibration_report &rep)
{
    return wait_until(s, timeout_s, frames, [&](const mocap_session_stats &) {
        mocap_calibration_get_report(s, &rep);
        return rep.state == MOCAP_CALIBRATION_ACCEPTED || rep.state == MOCAP_CALIBRATION_REFUSED;
    });
}

}  // namespace

TEST(Session, ReplayEndToEndMatchesTruthAndEnds)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 21;
    cfg.motion_s = 8.0;
    add_realistic_noise(cfg);
    std::string capture = test_temp_path("walk.cap");
    ASSERT_EQ(synth_write_capture(&cfg, synth_builtin_motion("mixed"), nullptr, capture.c_str(), nullptr),
              MOCAP_OK) << mocap_last_error();
    auto packets = generate(cfg);  // same seed: the same stream, with its truth
    TruthTrack truth(cfg, packets);

    mocap_session_config config = replay_config(capture);
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
    // Both prelude windows are scheduled before the start: a fast replay outruns any caller.
    double t0 = synth_session_time(&cfg, 0.0);
    ASSERT_EQ(mocap_calibration_schedule(session.s, MOCAP_CALIBRATION_HEADING, t0 + 0.5,
                                         (float)(cfg.heading_s - 1.0)), MOCAP_OK);
    ASSERT_EQ(mocap_calibration_schedule(session.s, MOCAP_CALIBRATION_TPOSE,
                                         t0 + cfg.heading_s + cfg.strap_s + 0.5,
                                         (float)(cfg.tpose_s - 1.0)), MOCAP_OK);
    mocap_calibration_report rep;
    ASSERT_EQ(mocap_calibration_get_step_report(session.s, MOCAP_CALIBRATION_TPOSE, &rep), MOCAP_OK);
    EXPECT_EQ(rep.state, MOCAP_CALIBRATION_WAITING);
    ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);

    std::vector<mocap_frame> frames;
    ASSERT_TRUE(wait_until(session.s, 30, &frames, [&](const mocap_session_stats &) {
        mocap_calibration_get_step_report(session.s, MOCAP_CALIBRATION_TPOSE, &rep);
        return rep.state == MOCAP_CALIBRATION_ACCEPTED || rep.state == MOCAP_CALIBRATION_REFUSED;
    }));
    ASSERT_EQ(rep.state, MOCAP_CALIBRATION_ACCEPTED) << rep.reason;
    ASSERT_EQ(mocap_calibration_get_step_report(session.s, MOCAP_CALIBRATION_HEADING, &rep), MOCAP_OK);
    ASSERT_EQ(rep.state, MOCAP_CALIBRATION_ACCEPTED) << rep.reason;
    for (int s = 0; s < kSensors; ++s) EXPECT_TRUE(rep.sensors[s].ok);

    // Drain to the end: the replay reports END_OF_STREAM once everything was delivered.
    std::vector<mocap_frame> buf(128);
    mocap_status st = MOCAP_OK;
    auto start = Clock::now();
    while (seconds_since(start) < 60) {
        uint32_t n = 0;
        st = mocap_session_drain(session.s, buf.data(), (uint32_t)buf.size(), &n);
        frames.insert(frames.end(), buf.begin(), buf.begin() + n);
        if (st == MOCAP_ERR_END_OF_STREAM) break;
        if (n == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    ASSERT_EQ(st, MOCAP_ERR_END_OF_STREAM);
    mocap_frame latest;
    EXPECT_EQ(mocap_session_poll_latest(session.s, &latest), MOCAP_ERR_END_OF_STREAM);

    // Every frame exactly once, in order, none dropped, covering the whole capture.
    for (size_t i = 1; i < frames.size(); ++i) ASSERT_EQ(frames[i].sequence, frames[i - 1].sequence + 1);
    // After the last sample, frames hold the last values until the sensors go stale (0.25 s).
    const double duration = packets.back().info.t;
    EXPECT_GE((double)frames.size(), duration * 60.0 - 2.0);
    EXPECT_LE((double)frames.size(), (duration + config.stale_after_s) * 60.0 + 2.0);
    mocap_session_stats stats;
    ASSERT_EQ(mocap_session_get_stats(session.s, &stats), MOCAP_OK);
    EXPECT_EQ(stats.frames_dropped, 0u);
    EXPECT_EQ(stats.frames_decoded, packets.size());
    EXPECT_EQ(stats.crc_failures, 0u);
    EXPECT_EQ(stats.sensors_seen_mask, 0x3Fu);
    EXPECT_EQ(stats.connection_state, MOCAP_CONNECTION_ENDED);

    ErrorStats errors;
    for (const auto &f : frames) score_frame(truth, f, errors);
    for (int s = 0; s < kSensors; ++s) {
        SCOPED_TRACE(mocap_segment_name(s));
        ASSERT_GT(errors.count(s), 400u);
        EXPECT_LT(errors.mean(s), 1.0);
    }
}

#if !defined(_WIN32) // Windows: a pseudo-terminal stands in for the serial port
// Live: bytes written in real time into the pty, calibration steps triggered "now" as a user
// would, then the motion recovered. Also records the stream and checks the recording.
TEST(Session, LiveSerialPtyCalibratesAndTracksAndRecords)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 22;
    cfg.heading_s = 1.5;
    cfg.strap_s = 0.5;
    cfg.tpose_s = 1.5;
    cfg.motion_s = 3.0;
    cfg.start_sensor_ms = 4294960000u;  // the sensor clock wraps during the test
    add_realistic_noise(cfg);
    auto packets = generate(cfg);
    ASSERT_FALSE(packets.empty());

    std::string dir = test_temp_dir();
    FakeReceiver receiver(dir + "/ttyHIPNUC");
    std::string record = dir + "/live.cap";
    mocap_session_config config = serial_config(receiver.link);
    snprintf(config.capture_path, sizeof config.capture_path, "%s", record.c_str());
    // The test's writer thread paces packets in real time; on a loaded machine (parallel ctest)
    // it can stall for tens or hundreds of ms (sanitizer builds on a busy machine), which a real
    // receiver does not. A longer hold keeps those
    // frames fresh instead of held, so the test checks tracking, not the scheduler.
    config.hold_latency_s = 1.0f;  // the most the engine accepts
    config.stale_after_s = 2.0f;
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);

    // The writer paces packets in real time and remembers when each was written (monotonic, the
    // session's clock) so the truth can be placed on the session's time axis.
    std::atomic<int> phase{-1};
    std::atomic<bool> writer_ok{true};
    std::vector<double> written_at(packets.size(), 0.0);
    size_t total_bytes = 0;
    for (const auto &p : packets) total_bytes += p.bytes.size();
    std::thread writer([&] {
        auto start = Clock::now();
        for (size_t i = 0; i < packets.size(); ++i) {
            std::this_thread::sleep_until(start + std::chrono::duration<double>(packets[i].info.t));
            phase = packets[i].info.phase;
            written_at[i] = (double)mocap_monotonic_ns() * 1e-9;
            if (!receiver.write_all(packets[i].bytes.data(), packets[i].bytes.size())) writer_ok = false;
        }
        phase = 4;
    });
    // Join on every way out of the test (a failed ASSERT returns early).
    struct Joiner {
        std::thread &t;
        ~Joiner()
        {
            if (t.joinable()) t.join();
        }
    } join_writer{writer};

    std::vector<mocap_frame> frames;
    mocap_calibration_report rep;
    ASSERT_TRUE(wait_until(session.s, 5, &frames, [](const mocap_session_stats &st) {
        return st.frames_emitted > 10;
    }));
    ASSERT_EQ(mocap_calibration_schedule(session.s, MOCAP_CALIBRATION_HEADING, -1.0, 0.8f), MOCAP_OK);
    ASSERT_TRUE(wait_for_calibration(session.s, 5, &frames, rep));
    ASSERT_EQ(rep.state, MOCAP_CALIBRATION_ACCEPTED) << rep.reason;
    ASSERT_TRUE(wait_until(session.s, 5, &frames, [&](const mocap_session_stats &) { return phase >= 2; }));
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    ASSERT_EQ(mocap_calibration_schedule(session.s, MOCAP_CALIBRATION_TPOSE, -1.0, 0.8f), MOCAP_OK);
    ASSERT_TRUE(wait_for_calibration(session.s, 5, &frames, rep));
    ASSERT_EQ(rep.state, MOCAP_CALIBRATION_ACCEPTED) << rep.reason;
    ASSERT_TRUE(wait_until(session.s, 10, &frames, [&](const mocap_session_stats &) { return phase == 4; }));
    writer.join();  // (the Joiner then has nothing left to do)
    ASSERT_TRUE(writer_ok);
    wait_until(session.s, 0.3, &frames, [](const mocap_session_stats &) { return false; });

    // The session clock of stream time t is t plus the smallest write latency seen, as the
    // engine's clock mapping does; transport latency (a pty: microseconds) adds to the error.
    double offset = 1e30;
    for (size_t i = 0; i < packets.size(); ++i) offset = std::min(offset, written_at[i] - packets[i].info.t);
    synth_config shifted = cfg;
    shifted.start_receive_ns = (int64_t)(offset * 1e9);
    TruthTrack truth(shifted, packets);
    ErrorStats errors;
    for (const auto &f : frames) score_frame(truth, f, errors);
    for (int s = 0; s < kSensors; ++s) {
        SCOPED_TRACE(mocap_segment_name(s));
        ASSERT_GT(errors.count(s), 100u);
        EXPECT_LT(errors.mean(s), 1.5);
    }
    mocap_session_stats stats;
    mocap_session_get_stats(session.s, &stats);
    EXPECT_EQ(stats.bytes_received, total_bytes);
    EXPECT_EQ(stats.crc_failures, 0u);

    // The recording holds exactly the bytes that crossed the wire.
    mocap_session_close(session.s);
    session.s = nullptr;
    capture_reader *reader = nullptr;
    ASSERT_EQ(capture_reader_open(record.c_str(), &reader), MOCAP_OK) << mocap_last_error();
    std::vector<uint8_t> recorded, sent;
    for (const auto &p : packets) sent.insert(sent.end(), p.bytes.begin(), p.bytes.end());
    int64_t ns;
    const uint8_t *data;
    size_t len;
    while (capture_reader_next(reader, &ns, &data, &len) == MOCAP_OK) recorded.insert(recorded.end(), data, data + len);
    EXPECT_EQ(capture_reader_tail(reader), 0);
    capture_reader_close(reader);
    EXPECT_TRUE(recorded == sent);
}
#endif

#if !defined(_WIN32) // Windows: a pseudo-terminal stands in for the serial port
// Unplug (master closed) surfaces within 1 s with the port named; replug at the same path
// resumes frames without any call from the user.
TEST(Session, UnplugIsReportedWithinOneSecondAndReplugResumes)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 23;
    cfg.motion_s = 20.0;
    auto packets = generate(cfg);
    std::string dir = test_temp_dir();
    FakeReceiver receiver(dir + "/ttyUSB-receiver");
    mocap_session_config config = serial_config(receiver.link);
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);

    std::atomic<bool> paused{false}, stop{false};
    std::atomic<size_t> next{0};
    std::mutex master_lock;
    std::thread writer([&] {
        while (!stop && next < packets.size()) {
            if (!paused) {
                std::lock_guard<std::mutex> g(master_lock);
                if (receiver.master >= 0) receiver.write_all(packets[next].bytes.data(), packets[next].bytes.size());
                next++;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
    });
    // Stop and join on every way out of the test (a failed ASSERT returns early).
    struct StopJoiner {
        std::atomic<bool> &stop;
        std::thread &t;
        ~StopJoiner()
        {
            stop = true;
            if (t.joinable()) t.join();
        }
    } join_writer{stop, writer};

    std::vector<mocap_frame> frames;
    ASSERT_TRUE(wait_until(session.s, 5, &frames, [](const mocap_session_stats &st) { return st.frames_emitted > 30; }));

    paused = true;
    {
        std::lock_guard<std::mutex> g(master_lock);
        receiver.unplug();
    }
    auto unplugged_at = Clock::now();
    bool noticed = wait_until(session.s, 5, nullptr, [](const mocap_session_stats &st) {
        return st.connection_state == MOCAP_CONNECTION_DISCONNECTED;
    });
    double delay = seconds_since(unplugged_at);
    ASSERT_TRUE(noticed);
    EXPECT_LT(delay, 1.0);
    mocap_session_stats stats;
    mocap_session_get_stats(session.s, &stats);
    EXPECT_NE(std::string(stats.last_error).find(receiver.link), std::string::npos) << stats.last_error;
    // While it stays away, last_error says why it cannot be opened again (the port is gone).
    ASSERT_TRUE(wait_until(session.s, 3, nullptr, [](const mocap_session_stats &st) {
        return std::string(st.last_error).find("reconnecting: ") == 0;
    }));
    mocap_session_get_stats(session.s, &stats);
    EXPECT_NE(std::string(stats.last_error).find(receiver.link), std::string::npos) << stats.last_error;

    uint64_t before = stats.frames_emitted;
    {
        std::lock_guard<std::mutex> g(master_lock);
        receiver.plug();
    }
    paused = false;
    ASSERT_TRUE(wait_until(session.s, 5, &frames, [&](const mocap_session_stats &st) {
        return st.connection_state == MOCAP_CONNECTION_CONNECTED && st.frames_emitted > before + 30;
    }));
    mocap_session_get_stats(session.s, &stats);
    EXPECT_EQ(stats.reconnects, 1u);
    stop = true;
    writer.join();
    for (size_t i = 1; i < frames.size(); ++i) ASSERT_GT(frames[i].sequence, frames[i - 1].sequence);
}
#endif

TEST(Session, WrongPortNamesThePortAndTheCause)
{
    mocap_session_config config = serial_config("/dev/ttyDOES-NOT-EXIST");
    mocap_session *s = nullptr;
    EXPECT_EQ(mocap_session_open(&config, &s), MOCAP_ERR_NOT_FOUND);
    EXPECT_EQ(s, nullptr);
    std::string err = mocap_last_error();
    EXPECT_NE(err.find("/dev/ttyDOES-NOT-EXIST"), std::string::npos) << err;

    mocap_session_config replay = replay_config(test_temp_path("missing.cap"));
    EXPECT_EQ(mocap_session_open(&replay, &s), MOCAP_ERR_NOT_FOUND);
    EXPECT_NE(std::string(mocap_last_error()).find("missing.cap"), std::string::npos);
}

TEST(Session, RejectsBadConfigurationWithAReason)
{
    mocap_session_config c = serial_config("/dev/null");
    c.struct_size = 12;
    mocap_session *s = nullptr;
    EXPECT_EQ(mocap_session_open(&c, &s), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("struct_size"), std::string::npos);
    c = serial_config("/dev/null");
    c.node_ids[2] = c.node_ids[1];
    EXPECT_EQ(mocap_session_open(&c, &s), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("right_wrist"), std::string::npos) << mocap_last_error();
    c = serial_config("/dev/null");
    c.output_rate_hz = NAN;
    EXPECT_EQ(mocap_session_open(&c, &s), MOCAP_ERR_INVALID_ARGUMENT);
}

#if !defined(_WIN32) // Windows: a pseudo-terminal stands in for the serial port
// Closing while the device is silent (the reader is inside a blocking wait) returns, and
// closing a session that was never started too.
TEST(Session, ClosesCleanlyWhileTheDeviceBlocks)
{
    std::string dir = test_temp_dir();
    FakeReceiver receiver(dir + "/ttySilent");
    for (int started = 0; started < 2; ++started) {
        mocap_session_config config = serial_config(receiver.link);
        mocap_session *s = nullptr;
        ASSERT_EQ(mocap_session_open(&config, &s), MOCAP_OK) << mocap_last_error();
        if (started) {
            ASSERT_EQ(mocap_session_start(s), MOCAP_OK);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        mocap_frame f;
        EXPECT_EQ(mocap_session_poll_latest(s, &f), MOCAP_ERR_NO_DATA);
        auto t0 = Clock::now();
        mocap_session_close(s);
        EXPECT_LT(seconds_since(t0), 5.0);  // a hang here would block forever
    }
}
#endif

#if !defined(_WIN32) // Windows: a pseudo-terminal stands in for the serial port
// NaN and non-unit quaternions from a broken sensor are rejected and counted; the other
// sensors keep producing frames.
TEST(Session, BadSamplesAreRejectedAndCountedWithoutStoppingOthers)
{
    std::string dir = test_temp_dir();
    FakeReceiver receiver(dir + "/ttyNaN");
    mocap_session_config config = serial_config(receiver.link);
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK);
    ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);

    const int packets = 60;
    for (int i = 0; i < packets; ++i) {
        hipnuc_sample samples[kSensors];
        std::memset(samples, 0, sizeof samples);
        for (int s = 0; s < kSensors; ++s) {
            samples[s].node_id = (uint32_t)s;
            samples[s].time_ms = 1000u + (uint32_t)i * 10u;
            samples[s].acc_g[2] = 1.0f;
            samples[s].quat[0] = 1.0f;
        }
        samples[1].quat[1] = NAN;             // left wrist: NaN
        samples[2].quat[0] = 0.0f;            // right wrist: zero quaternion
        samples[3].quat[0] = 1.7f;            // left shin: far from unit
        samples[4].acc_g[0] = INFINITY;       // right shin: infinite acceleration
        uint8_t payload[HIPNUC_MAX_PAYLOAD], frame[HIPNUC_MAX_PAYLOAD + 16];
        size_t plen = hipnuc_encode_gwsol(1, samples, kSensors, payload, sizeof payload);
        size_t flen = hipnuc_encode_frame(payload, plen, frame, sizeof frame);
        ASSERT_GT(flen, 0u);
        ASSERT_TRUE(receiver.write_all(frame, flen));
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    std::vector<mocap_frame> frames;
    ASSERT_TRUE(wait_until(session.s, 5, &frames, [&](const mocap_session_stats &st) {
        return st.samples_decoded + st.samples_rejected >= (uint64_t)packets * 6;
    }));
    wait_until(session.s, 0.3, &frames, [](const mocap_session_stats &) { return false; });
    mocap_session_stats stats;
    mocap_session_get_stats(session.s, &stats);
    EXPECT_EQ(stats.samples_rejected, (uint64_t)packets * 4);
    EXPECT_EQ(stats.samples_decoded, (uint64_t)packets * 2);
    EXPECT_EQ(stats.sensors_seen_mask, (1u << 0) | (1u << 5));
    ASSERT_GT(frames.size(), 10u);
    const mocap_frame &f = frames.back();
    for (int s = 0; s < kSensors; ++s) {
        for (int k = 0; k < 4; ++k) ASSERT_TRUE(std::isfinite(f.sensors[s].bone_orientation[k]));
        for (int k = 0; k < 3; ++k) ASSERT_TRUE(std::isfinite(f.sensors[s].bone_acceleration[k]));
    }
}
#endif

#if !defined(_WIN32) // Windows: a pseudo-terminal serial port and /dev/full
// A recording that cannot even start (a full device) fails the open with the file named.
TEST(Session, RecordingToAFullDeviceFailsTheOpenClearly)
{
    std::string dir = test_temp_dir();
    FakeReceiver receiver(dir + "/ttyFull");
    mocap_session_config config = serial_config(receiver.link);
    snprintf(config.capture_path, sizeof config.capture_path, "/dev/full");
    mocap_session *s = nullptr;
    EXPECT_EQ(mocap_session_open(&config, &s), MOCAP_ERR_IO);
    EXPECT_EQ(s, nullptr);
    EXPECT_NE(std::string(mocap_last_error()).find("/dev/full"), std::string::npos) << mocap_last_error();
}
#endif

// The disk filling up mid-session stops the recording with a clear error; tracking goes on.
// A forked child gets a small file-size limit (the kernel's EFBIG stands in for ENOSPC) and
// reports through its exit code.
// Waits (up to 10 s) until the session has decoded `frames` HiPNUC frames: every byte written
// so far went through the processing thread (and into the capture). Samples are no measure of
// that: a burst written faster than the sensor clock runs maps onto one instant, and the
// assembler keeps one sample of it per sensor.
[[maybe_unused]] bool wait_for_frames(mocap_session *s, uint64_t frames)
{
    return wait_until(s, 10.0, nullptr, [&](const mocap_session_stats &st) { return st.frames_decoded >= frames; });
}

#if !defined(_WIN32) // Windows: a pseudo-terminal serial port, fork + RLIMIT_FSIZE for a full disk
TEST(Session, DiskFullMidSessionStopsRecordingButNotTracking)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 24;
    cfg.motion_s = 4.0;
    auto packets = generate(cfg);
    std::string dir = test_temp_dir();
    std::string record = dir + "/limited.cap";
    const int code = exit_code_with_file_size_limit(40000, [&]() -> int {
        FakeReceiver receiver(dir + "/ttyLimited");
        mocap_session_config config = serial_config(receiver.link);
        snprintf(config.capture_path, sizeof config.capture_path, "%s", record.c_str());
        mocap_session *s = nullptr;
        if (mocap_session_open(&config, &s) != MOCAP_OK) return 11;
        if (mocap_session_start(s) != MOCAP_OK) return 12;
        for (size_t i = 0; i < packets.size(); ++i) {
            if (!receiver.write_all(packets[i].bytes.data(), packets[i].bytes.size())) return 13;
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        // A loaded machine (parallel suites) may lag behind the writer: wait for the frames.
        wait_until(s, 10.0, nullptr, [&](const mocap_session_stats &st) {
            return st.frames_decoded >= packets.size() - 5;
        });
        mocap_session_stats stats;
        mocap_session_get_stats(s, &stats);
        int result = 0;
        if (stats.capture_error != MOCAP_ERR_IO) result = 14;
        else if (std::string(stats.last_error).find("limited.cap") == std::string::npos) result = 15;
        // Kept tracking: every frame after the disk filled was decoded and all its samples taken
        // (the writer runs 5x faster than the sensor clock, so a loaded reader gets several
        // frames per read: clock_map keeps them in order).
        else if (stats.frames_decoded < packets.size() - 5 ||
                 stats.samples_decoded != stats.frames_decoded * 6)
            result = 16;
        else if (stats.connection_state != MOCAP_CONNECTION_CONNECTED) result = 17;
        if (result != 0)
            fprintf(stderr, "child %d: sent %zu packets, samples decoded %llu, bytes received %llu, "
                    "dropped %llu, frames %llu, crc failures %llu, rejected %llu, capture error %d (%s)\n",
                    result, packets.size(),
                    (unsigned long long)stats.samples_decoded, (unsigned long long)stats.bytes_received,
                    (unsigned long long)stats.bytes_dropped, (unsigned long long)stats.frames_decoded,
                    (unsigned long long)stats.crc_failures, (unsigned long long)stats.samples_rejected,
                    (int)stats.capture_error, stats.last_error);
        mocap_session_close(s);
        return result;
    });
    EXPECT_EQ(code, 0) << "14: no capture error, 15: file not named, 16: tracking stopped, "
                          "17: connection lost";
    // What reached the disk is still a readable capture.
    capture_reader *reader = nullptr;
    ASSERT_EQ(capture_reader_open(record.c_str(), &reader), MOCAP_OK) << mocap_last_error();
    int64_t ns;
    const uint8_t *data;
    size_t len;
    std::vector<uint8_t> on_disk;
    while (capture_reader_next(reader, &ns, &data, &len) == MOCAP_OK) on_disk.insert(on_disk.end(), data, data + len);
    capture_reader_close(reader);
    // The chunks written before the limit hold the start of the byte stream, exactly. How much
    // that is depends on where the chunk that hit the limit began (chunks close every 100 ms, so
    // on a loaded machine they are longer), so only the content is checked, not an amount.
    std::vector<uint8_t> sent;
    for (const auto &p : packets) sent.insert(sent.end(), p.bytes.begin(), p.bytes.end());
    EXPECT_GT(on_disk.size(), 0u);
    EXPECT_LT(on_disk.size(), 40000u);
    ASSERT_LE(on_disk.size(), sent.size());
    EXPECT_TRUE(std::equal(on_disk.begin(), on_disk.end(), sent.begin())) << "not the stream's first bytes";
}
#endif

#if !defined(_WIN32) // Windows: a pseudo-terminal stands in for the serial port
// stop() hands back the recording's outcome and final numbers, before the handle is freed.
TEST(Session, StopFlushesTheCaptureAndReportsItsFinalSize)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 31;
    cfg.motion_s = 1.0;
    auto packets = generate(cfg);
    std::string dir = test_temp_dir();
    FakeReceiver receiver(dir + "/ttyStop");
    std::string record = dir + "/stopped.cap";
    mocap_session_config config = serial_config(receiver.link);
    snprintf(config.capture_path, sizeof config.capture_path, "%s", record.c_str());
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);
    size_t sent = 0;
    for (size_t i = 0; i < 40; ++i) {
        ASSERT_TRUE(receiver.write_all(packets[i].bytes.data(), packets[i].bytes.size()));
        sent += packets[i].bytes.size();
    }
    ASSERT_TRUE(wait_for_frames(session.s, 40));
    ASSERT_EQ(mocap_session_stop(session.s), MOCAP_OK) << mocap_last_error();
    mocap_session_stats stats;
    ASSERT_EQ(mocap_session_get_stats(session.s, &stats), MOCAP_OK);
    EXPECT_EQ(stats.capture_error, MOCAP_OK);
    EXPECT_EQ(stats.bytes_received, sent);
    // The file is complete and closed now, and the stats say exactly how big it is.
    EXPECT_EQ(stats.capture_bytes_written, (uint64_t)std::filesystem::file_size(record));
    capture_reader *reader = nullptr;
    ASSERT_EQ(capture_reader_open(record.c_str(), &reader), MOCAP_OK) << mocap_last_error();
    int64_t ns;
    const uint8_t *data;
    size_t len, bytes = 0;
    while (capture_reader_next(reader, &ns, &data, &len) == MOCAP_OK) bytes += len;
    capture_reader_close(reader);
    EXPECT_EQ(bytes, sent);
    // Stopping twice is harmless; a stopped session does not start again.
    EXPECT_EQ(mocap_session_stop(session.s), MOCAP_OK);
    EXPECT_EQ(mocap_session_start(session.s), MOCAP_ERR_STATE);
    EXPECT_NE(std::string(mocap_last_error()).find("stopped"), std::string::npos);
}
#endif

#if !defined(_WIN32) // Windows: a pseudo-terminal serial port, fork + RLIMIT_FSIZE for a full disk
// A disk that fills at the very end (the last flush, written as the session stops) is the
// stop's failure: a caller that only stops and closes still learns the capture is incomplete.
TEST(Session, StopReturnsAFailedLastFlush)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 32;
    cfg.motion_s = 1.0;
    auto packets = generate(cfg);
    std::string dir = test_temp_dir();
    std::string record = dir + "/last.cap";
    // Room for the file header (a few hundred bytes), not for the first chunk.
    const int code = exit_code_with_file_size_limit(1024, [&]() -> int {
        FakeReceiver receiver(dir + "/ttyLast");
        mocap_session_config config = serial_config(receiver.link);
        snprintf(config.capture_path, sizeof config.capture_path, "%s", record.c_str());
        mocap_session *s = nullptr;
        if (mocap_session_open(&config, &s) != MOCAP_OK) return 11;
        if (mocap_session_start(s) != MOCAP_OK) return 12;
        for (size_t i = 0; i < 10; ++i)
            if (!receiver.write_all(packets[i].bytes.data(), packets[i].bytes.size())) return 13;
        if (!wait_for_frames(s, 10)) return 14;
        int result = 0;
        const mocap_status stopped = mocap_session_stop(s);
        const std::string why = mocap_last_error();
        mocap_session_stats stats;
        mocap_session_get_stats(s, &stats);
        if (stopped != MOCAP_ERR_IO) result = 15;
        else if (why.find("last.cap") == std::string::npos) result = 16;
        else if (stats.capture_error != MOCAP_ERR_IO) result = 17;
        else if (mocap_session_stop(s) != MOCAP_ERR_IO) result = 18;  // the same answer again
        else if (stats.capture_bytes_written > 1024) result = 19;
        mocap_session_close(s);
        return result;
    });
    EXPECT_EQ(code, 0) << "15: stop said OK, 16: file not named, 17: stats disagree, "
                          "18: second stop differs, 19: size beyond the limit";
}
#endif

// A replay passes over damaged chunks and a cut-off end (it must: a crash-damaged capture is
// still worth replaying); the stats say so, so a consumer can tell the frames miss part of it.
TEST(Session, ReplayStatsCountDamagedChunksAndACutEnd)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 29;
    cfg.motion_s = 3.0;
    const std::string clean = test_temp_path("clean.cap");
    ASSERT_EQ(synth_write_capture(&cfg, synth_builtin_motion("walk"), nullptr, clean.c_str(), nullptr),
              MOCAP_OK) << mocap_last_error();
    std::vector<uint8_t> bytes = read_file_bytes(clean);
    ASSERT_GT(bytes.size(), 200000u);
    for (size_t k = 0; k < 3; ++k) bytes[bytes.size() / 3 + k * 30000] ^= 0xff;  // three chunks
    bytes.resize(bytes.size() - 100);                                          // and a cut end
    const std::string damaged = test_temp_path("damaged.cap");
    write_file_bytes(damaged, bytes);

    auto replay_to_end = [](const std::string &path, mocap_session_stats &stats) {
        mocap_session_config config = replay_config(path);
        SessionCloser session;
        ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
        ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);
        ASSERT_TRUE(wait_until(session.s, 30, nullptr, [](const mocap_session_stats &st) {
            return st.connection_state == MOCAP_CONNECTION_ENDED;
        }));
        ASSERT_EQ(mocap_session_get_stats(session.s, &stats), MOCAP_OK);
    };
    mocap_session_stats whole, part;
    replay_to_end(clean, whole);
    replay_to_end(damaged, part);
    EXPECT_EQ(whole.replay_chunks_skipped, 0u);
    EXPECT_EQ(whole.replay_tail_damaged, 0);
    EXPECT_EQ(part.replay_chunks_skipped, 3u);
    EXPECT_EQ(part.replay_tail_damaged, 1);
    // What could be read was replayed, and the loss is not an error that ended the replay.
    EXPECT_GT(part.frames_emitted, whole.frames_emitted / 2);
    EXPECT_LT(part.bytes_received, whole.bytes_received);
    EXPECT_STREQ(part.last_error, "");
}

// A replay that meets a long stretch of plausible fake chunk headers (tens of seconds of 64 KiB
// reads and CRCs to skip) still stops promptly: the skipping happens in bounded slices.
TEST(Session, StopIsPromptWhileAReplaySkipsALongDamagedStretch)
{
    std::string dir = test_temp_dir();
    std::string path = dir + "/fakes.cap";
    capture_writer *w = nullptr;
    ASSERT_EQ(capture_writer_open(path.c_str(), &w), MOCAP_OK) << mocap_last_error();
    const uint8_t byte = 0x5A;
    ASSERT_EQ(capture_writer_append(w, 1000000000LL, &byte, 1), MOCAP_OK);
    ASSERT_EQ(capture_writer_close(w), MOCAP_OK);
    std::vector<uint8_t> bytes = read_file_bytes(path);
    for (size_t i = 0; i < 200000; i++) {  // 7 MB: ~13 GB of reads and CRCs to skip it all
        uint8_t h[36] = {'M', 'C', 'H', 'K'};
        const uint32_t payload = 65536, count = 1;
        memcpy(h + 4, &payload, 4);
        memcpy(h + 8, &count, 4);
        bytes.insert(bytes.end(), h, h + sizeof h);
    }
    write_file_bytes(path, bytes);

    mocap_session_config c;
    mocap_config_defaults(&c);
    c.source_kind = MOCAP_SOURCE_REPLAY;
    snprintf(c.path, sizeof c.path, "%s", path.c_str());
    mocap_session *s = nullptr;
    ASSERT_EQ(mocap_session_open(&c, &s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_session_start(s), MOCAP_OK);
    // The one good record is read, then the reader is deep in the damaged stretch.
    ASSERT_TRUE(wait_until(s, 5, nullptr, [](const mocap_session_stats &st) { return st.bytes_received == 1; }));
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    mocap_session_stats stats;
    mocap_session_get_stats(s, &stats);
    EXPECT_NE(stats.connection_state, MOCAP_CONNECTION_ENDED);  // still skipping
    auto t0 = Clock::now();
    EXPECT_EQ(mocap_session_stop(s), MOCAP_OK);
    mocap_session_close(s);
    // A read slice is 50 ms plus one candidate; sanitizer builds are several times slower.
    EXPECT_LT(seconds_since(t0), 2.0);
}

// A capture whose receive times sit next to INT64_MAX (damaged or hand-made) still replays to
// its end: the end-of-stream arithmetic must not overflow (UBSan aborts on it).
TEST(Session, ReplayWithReceiveTimesAtTheEndOfInt64Ends)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.motion_s = 0.5;
    cfg.start_receive_ns = INT64_MAX - 60000000000LL;  // the capture ends ~50 s before the limit
    auto packets = generate(cfg);
    std::string path = test_temp_path("int64_end.cap");
    capture_writer *w = nullptr;
    ASSERT_EQ(capture_writer_open(path.c_str(), &w), MOCAP_OK) << mocap_last_error();
    for (const auto &p : packets)
        ASSERT_EQ(capture_writer_append(w, p.info.receive_ns, p.bytes.data(), p.bytes.size()), MOCAP_OK);
    const uint8_t last = 0;
    ASSERT_EQ(capture_writer_append(w, INT64_MAX - 1, &last, 1), MOCAP_OK);  // then one at the edge
    ASSERT_EQ(capture_writer_close(w), MOCAP_OK);
    mocap_session_config config = replay_config(path);
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);
    std::vector<mocap_frame> buf(64);
    mocap_status st = MOCAP_ERR_NO_DATA;
    size_t frames = 0;
    auto t0 = Clock::now();
    while (st != MOCAP_ERR_END_OF_STREAM && seconds_since(t0) < 10.0) {
        uint32_t n = 0;
        st = mocap_session_drain(session.s, buf.data(), (uint32_t)buf.size(), &n);
        frames += n;
        if (st == MOCAP_ERR_NO_DATA) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    EXPECT_EQ(st, MOCAP_ERR_END_OF_STREAM);
    EXPECT_GT(frames, 100u);
}

TEST(Session, StructLayoutTableMatchesTheHeader)
{
    uint32_t n = 0;
    const mocap_field_layout *rows = mocap_struct_layout(&n);
    ASSERT_GT(n, 40u);
    bool saw_frame = false;
    for (uint32_t i = 0; i < n; ++i) {
        if (std::string(rows[i].struct_name) == "mocap_frame" && rows[i].field_name[0] == '\0') {
            EXPECT_EQ(rows[i].size, sizeof(mocap_frame));
            saw_frame = true;
        }
        if (std::string(rows[i].struct_name) == "mocap_frame" && std::string(rows[i].field_name) == "sensors") {
            EXPECT_EQ(rows[i].offset, offsetof(mocap_frame, sensors));
        }
    }
    EXPECT_TRUE(saw_frame);
    EXPECT_EQ(mocap_api_version(), MOCAP_API_VERSION);
}

// Up to 8 calibration steps may wait behind the one collecting; one more is refused clearly.
// mocap_calibration_set takes what save and load take, nothing else: a scaled matrix would flag
// every frame calibrated while distorting it, and the calibration in use could not be saved.
TEST(Session, CalibrationSetRefusesWhatSaveAndLoadRefuse)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.motion_s = 1.0;
    std::string capture = test_temp_path("set.cap");
    ASSERT_EQ(synth_write_capture(&cfg, synth_builtin_motion("walk"), nullptr, capture.c_str(), nullptr), MOCAP_OK);
    mocap_session_config config = replay_config(capture);
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK);
    static mocap_calibration good, bad;
    const int32_t six[kSensors] = {0, 1, 2, 3, 4, 5};
    calib_identity(&good, kSensors, six);
    good.valid_mask = good.heading_mask = 0x3F;
    ASSERT_EQ(mocap_calibration_set(session.s, &good), MOCAP_OK) << mocap_last_error();

    bad = good;
    for (int i = 0; i < 9; ++i) bad.sensor_to_bone[2][i] *= 2.0f;  // scaled: not a rotation
    EXPECT_EQ(mocap_calibration_set(session.s, &bad), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("not a rotation"), std::string::npos) << mocap_last_error();
    bad = good;
    bad.heading_mask = 0x1F;  // sensor 5 calibrated without a heading
    EXPECT_EQ(mocap_calibration_set(session.s, &bad), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("without a heading"), std::string::npos) << mocap_last_error();
    bad = good;
    bad.valid_mask = bad.heading_mask = 0x7F;  // a seventh sensor
    EXPECT_EQ(mocap_calibration_set(session.s, &bad), MOCAP_ERR_INVALID_ARGUMENT);

    // The calibration in use is still the good one, and it saves.
    static mocap_calibration now;
    ASSERT_EQ(mocap_calibration_get(session.s, &now), MOCAP_OK);
    EXPECT_EQ(std::memcmp(&now, &good, sizeof now), 0);
    EXPECT_EQ(mocap_calibration_save(&now, test_temp_path("in_use.calibration").c_str()), MOCAP_OK) << mocap_last_error();
}

TEST(Session, CalibrationQueueHoldsEightWaitingSteps)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.motion_s = 1.0;
    std::string capture = test_temp_path("queue.cap");
    ASSERT_EQ(synth_write_capture(&cfg, synth_builtin_motion("walk"), nullptr, capture.c_str(), nullptr), MOCAP_OK);
    mocap_session_config config = replay_config(capture);
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK);
    for (int i = 0; i < 9; ++i)
        ASSERT_EQ(mocap_calibration_schedule(session.s, MOCAP_CALIBRATION_HEADING, 100.0 + i, 1.0f), MOCAP_OK) << i;
    EXPECT_EQ(mocap_calibration_schedule(session.s, MOCAP_CALIBRATION_TPOSE, 200.0, 1.0f), MOCAP_ERR_STATE);
    EXPECT_NE(std::string(mocap_last_error()).find("8 calibration steps"), std::string::npos) << mocap_last_error();
}

// A paced replay delivers the recorded timeline (frame times, count and poses) of a fast one;
// only the wall-clock pace differs.
TEST(Session, RealtimeReplayKeepsTheRecordedTimeline)
{
    std::string capture = test_temp_path("paced.cap");
    ASSERT_TRUE(write_short_walk(capture, 25, 1.0));
    std::vector<mocap_frame> runs[2];
    double wall[2];
    for (int paced = 0; paced < 2; ++paced) {
        mocap_session_config config = replay_config(capture);
        config.replay_realtime = paced;
        config.replay_speed = 4.0f;
        SessionCloser session;
        ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK);
        auto t0 = Clock::now();
        ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);
        std::vector<mocap_frame> buf(64);
        for (;;) {
            uint32_t n = 0;
            mocap_status st = mocap_session_drain(session.s, buf.data(), (uint32_t)buf.size(), &n);
            runs[paced].insert(runs[paced].end(), buf.begin(), buf.begin() + n);
            if (st == MOCAP_ERR_END_OF_STREAM || seconds_since(t0) > 20) break;
            if (n == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        wall[paced] = seconds_since(t0);
    }
    ASSERT_EQ(runs[0].size(), runs[1].size());
    ASSERT_GT(runs[0].size(), 100u);
    for (size_t i = 0; i < runs[0].size(); ++i) {
        ASSERT_EQ(runs[0][i].time_s, runs[1][i].time_s) << i;
        ASSERT_EQ(0, std::memcmp(runs[0][i].sensors, runs[1][i].sensors, sizeof runs[0][i].sensors)) << i;
    }
    // 2.2 s of capture at 4x takes at least ~0.55 s of wall time when paced.
    EXPECT_GE(wall[1], 0.45);
}

#if !defined(_WIN32) // Windows: swaps the replay's open descriptor through /proc/self/fd and dup2
namespace {

// The descriptor this process holds open on path (Linux: /proc/self/fd), or -1.
int find_open_descriptor(const std::string &path)
{
    const std::string want = std::filesystem::canonical(path).string();
    for (const auto &entry : std::filesystem::directory_iterator("/proc/self/fd")) {
        std::error_code ec;
        auto target = std::filesystem::read_symlink(entry.path(), ec);
        if (!ec && target.string() == want) return std::stoi(entry.path().filename().string());
    }
    return -1;
}

}  // namespace

// A capture file that stops reading mid-replay (its drive removed) ends the stream there: the
// consumers drain what was read and get END_OF_STREAM, with the cause in last_error, instead of
// NO_DATA forever.
TEST(Session, ReplayReadFailureEndsTheStreamWithTheCause)
{
    if (!std::filesystem::exists("/proc/self/fd")) GTEST_SKIP() << "needs /proc/self/fd";
    std::string capture = test_temp_path("vanishing.cap");
    ASSERT_TRUE(write_short_walk(capture, 31, 6.0));
    mocap_session_config config = replay_config(capture);
    config.replay_realtime = 1;
    config.replay_speed = 1.0f;
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK);
    ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);
    std::vector<mocap_frame> frames;
    ASSERT_TRUE(wait_until(session.s, 10.0, &frames, [&](const mocap_session_stats &) { return frames.size() >= 20; }));
    // From now on every read of the file fails (EISDIR), as a vanished drive's would (EIO).
    int fd = find_open_descriptor(capture);
    ASSERT_GE(fd, 0);
    int dir = open(std::filesystem::path(capture).parent_path().c_str(), O_RDONLY | O_DIRECTORY);
    ASSERT_GE(dir, 0);
    ASSERT_EQ(dup2(dir, fd), fd);
    close(dir);
    auto t0 = Clock::now();
    mocap_status st = MOCAP_ERR_NO_DATA;
    std::vector<mocap_frame> buf(64);
    while (seconds_since(t0) < 10.0) {
        uint32_t n = 0;
        st = mocap_session_drain(session.s, buf.data(), (uint32_t)buf.size(), &n);
        frames.insert(frames.end(), buf.begin(), buf.begin() + n);
        if (st == MOCAP_ERR_END_OF_STREAM) break;
        if (n == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    ASSERT_EQ(st, MOCAP_ERR_END_OF_STREAM) << "the stream never ended after the file failed";
    // 7.2 s of capture at 100 Hz: the failure came well before its end.
    EXPECT_LT(frames.size(), 600u);
    mocap_session_stats stats;
    ASSERT_EQ(mocap_session_get_stats(session.s, &stats), MOCAP_OK);
    EXPECT_EQ(stats.connection_state, MOCAP_CONNECTION_ENDED);
    EXPECT_NE(std::string(stats.last_error).find("read failed"), std::string::npos) << stats.last_error;
    EXPECT_NE(std::string(stats.last_error).find("vanishing.cap"), std::string::npos) << stats.last_error;
}
#endif

// Calibration requests may come from any thread, also while another thread starts the session:
// each one lands exactly once (and ThreadSanitizer sees no race on the pipeline).
TEST(Session, CalibrationRequestsRacingStartAreAllApplied)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 32;
    std::string capture = test_temp_path("race.cap");
    ASSERT_EQ(synth_write_capture(&cfg, synth_builtin_motion("walk"), nullptr, capture.c_str(), nullptr), MOCAP_OK);
    for (int round = 0; round < 20; ++round) {
        mocap_session_config config = replay_config(capture);
        config.replay_realtime = 1;
        SessionCloser session;
        ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK);
        mocap_calibration cal;
        ASSERT_EQ(mocap_calibration_get(session.s, &cal), MOCAP_OK);
        cal.acceleration_offset[0][0] = 0.25f + 0.01f * (float)round;
        std::atomic<int> go{0};
        std::thread other([&] {
            while (!go.load()) {}
            EXPECT_EQ(mocap_calibration_set(session.s, &cal), MOCAP_OK);
            EXPECT_EQ(mocap_calibration_schedule(session.s, MOCAP_CALIBRATION_HEADING, 1000.0, 1.0f), MOCAP_OK);
        });
        go.store(1);
        ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);
        other.join();
        mocap_calibration got;
        mocap_calibration_report step;
        bool applied = false;
        auto t0 = Clock::now();
        while (!applied && seconds_since(t0) < 5.0) {
            ASSERT_EQ(mocap_calibration_get(session.s, &got), MOCAP_OK);
            ASSERT_EQ(mocap_calibration_get_step_report(session.s, MOCAP_CALIBRATION_HEADING, &step), MOCAP_OK);
            applied = got.acceleration_offset[0][0] == cal.acceleration_offset[0][0] &&
                      step.state == MOCAP_CALIBRATION_WAITING;
            if (!applied) std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        EXPECT_TRUE(applied) << "round " << round;
        EXPECT_EQ(mocap_session_start(session.s), MOCAP_ERR_STATE);
    }
}

// A consumer that stops polling for longer than the frame ring holds (an editor paused on a
// breakpoint) gets the newest frame from its next poll, not the newest of the 1024 the ring
// kept (before, that frame was 17 s old at 60 Hz). What poll handed out is not handed out again,
// neither by the next poll nor by a drain.
TEST(Session, PollAfterALongPauseReturnsTheNewestFrame)
{
    std::string capture = test_temp_path("long_pause.cap");
    ASSERT_TRUE(write_short_walk(capture, 41, 40.0));
    mocap_session_config config = replay_config(capture);
    config.output_rate_hz = 400.0f; // several thousand frames from the walk
    config.replay_realtime = 1;
    config.replay_speed = 10.0f;  // live-like: a full ring drops frames instead of waiting
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_session_start(session.s), MOCAP_OK);
    mocap_session_stats stats{};
    const auto t0 = Clock::now();
    do {  // the pause: nobody polls until the replay has ended
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        ASSERT_EQ(mocap_session_get_stats(session.s, &stats), MOCAP_OK);
    } while (stats.connection_state != MOCAP_CONNECTION_ENDED && seconds_since(t0) < 30);
    std::this_thread::sleep_for(std::chrono::milliseconds(200)); // the last frames through
    ASSERT_EQ(mocap_session_get_stats(session.s, &stats), MOCAP_OK);
    ASSERT_GT(stats.frames_dropped, 0u) << "the ring never filled: the test shows nothing";

    mocap_frame frame{};
    ASSERT_EQ(mocap_session_poll_latest(session.s, &frame), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(frame.sequence + 1, stats.frames_emitted) << "not the newest frame";
    EXPECT_GT(frame.sequence, 1024u);
    EXPECT_EQ(mocap_session_poll_latest(session.s, &frame), MOCAP_ERR_END_OF_STREAM);
    mocap_frame rest[8];
    uint32_t n = 99;
    EXPECT_EQ(mocap_session_drain(session.s, rest, 8, &n), MOCAP_ERR_END_OF_STREAM);
    EXPECT_EQ(n, 0u);
}

namespace {

// A replay session of `capture` with the default set plus a chest on node 6.
mocap_session_config seven_sensor_replay(const std::string &capture, uint32_t optional_mask = 0)
{
    mocap_session_config c = replay_config(capture);
    c.sensor_count = 7;
    c.sensor_segments[6] = MOCAP_SEGMENT_CHEST;
    c.node_ids[6] = 6;
    c.optional_mask = optional_mask;
    return c;
}

// Schedules both prelude steps, starts, and drains to the end of the replay.
std::vector<mocap_frame> replay_with_prelude(mocap_session *s, const synth_config &cfg)
{
    std::vector<mocap_frame> frames;
    const double t0 = synth_session_time(&cfg, 0.0);
    EXPECT_EQ(mocap_calibration_schedule(s, MOCAP_CALIBRATION_HEADING, t0 + 0.5, (float)(cfg.heading_s - 1.0)),
              MOCAP_OK);
    EXPECT_EQ(mocap_calibration_schedule(s, MOCAP_CALIBRATION_TPOSE, t0 + cfg.heading_s + cfg.strap_s + 0.5,
                                         (float)(cfg.tpose_s - 1.0)), MOCAP_OK);
    EXPECT_EQ(mocap_session_start(s), MOCAP_OK) << mocap_last_error();
    std::vector<mocap_frame> buf(128);
    const auto start = Clock::now();
    while (seconds_since(start) < 60) {
        uint32_t n = 0;
        mocap_status st = mocap_session_drain(s, buf.data(), (uint32_t)buf.size(), &n);
        frames.insert(frames.end(), buf.begin(), buf.begin() + n);
        if (st == MOCAP_ERR_END_OF_STREAM) return frames;
        if (n == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    ADD_FAILURE() << "the replay did not end";
    return frames;
}

}  // namespace

// A generated 7-sensor capture (the chest on node 6) through a session configured with the same
// seven: heading and T-pose accepted with every sensor calibrated, the chest's bone within the
// six-sensor replay's bound of its truth, frames of 7 sensors in config order with their states.
TEST(Session, SevenSensorReplayCalibratesTheChestToo)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 22;
    cfg.motion_s = 8.0;
    cfg.sensor_count = 7;
    cfg.segments[6] = MOCAP_SEGMENT_CHEST;
    cfg.node_ids[6] = 6;
    add_realistic_noise(cfg);
    std::string capture = test_temp_path("seven.cap");
    ASSERT_EQ(synth_write_capture(&cfg, synth_builtin_motion("mixed"), nullptr, capture.c_str(), nullptr),
              MOCAP_OK) << mocap_last_error();
    auto packets = generate(cfg);
    TruthTrack truth(cfg, packets);

    // Listed in another order than the capture's: the session's order is what frames follow.
    mocap_session_config config = seven_sensor_replay(capture);
    const int32_t order[7] = {MOCAP_SEGMENT_CHEST, MOCAP_SEGMENT_PELVIS, MOCAP_SEGMENT_HEAD,
                              MOCAP_SEGMENT_LEFT_WRIST, MOCAP_SEGMENT_RIGHT_WRIST,
                              MOCAP_SEGMENT_LEFT_SHIN, MOCAP_SEGMENT_RIGHT_SHIN};
    for (int i = 0; i < 7; ++i) {
        config.sensor_segments[i] = order[i];
        config.node_ids[i] = order[i] == MOCAP_SEGMENT_CHEST ? 6 : order[i];
    }
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
    std::vector<mocap_frame> frames = replay_with_prelude(session.s, cfg);
    for (int step : {MOCAP_CALIBRATION_HEADING, MOCAP_CALIBRATION_TPOSE}) {
        mocap_calibration_report rep;
        ASSERT_EQ(mocap_calibration_get_step_report(session.s, step, &rep), MOCAP_OK);
        ASSERT_EQ(rep.state, MOCAP_CALIBRATION_ACCEPTED) << rep.reason;
        ASSERT_EQ(rep.sensor_count, 7u);
        for (int i = 0; i < 7; ++i) {
            EXPECT_EQ(rep.sensors[i].segment, order[i]);
            EXPECT_TRUE(rep.sensors[i].ok) << i;
            EXPECT_EQ(rep.sensors[i].left_out, 0);
        }
    }
    static mocap_calibration cal;
    ASSERT_EQ(mocap_calibration_get(session.s, &cal), MOCAP_OK);
    EXPECT_EQ(cal.sensor_count, 7u);
    EXPECT_EQ(cal.valid_mask, 0x7Fu);
    EXPECT_EQ(cal.segments[0], MOCAP_SEGMENT_CHEST);
    mocap_session_stats stats;
    ASSERT_EQ(mocap_session_get_stats(session.s, &stats), MOCAP_OK);
    EXPECT_EQ(stats.sensors_seen_mask, 0x7Fu);

    ASSERT_FALSE(frames.empty());
    size_t fresh_chest = 0;
    int states_seen = 0;
    for (const mocap_frame &f : frames) {
        ASSERT_EQ(f.sensor_count, 7u);
        for (int i = 0; i < 7; ++i) {
            ASSERT_EQ(f.sensors[i].segment, order[i]);
            ASSERT_EQ(f.sensors[i].node_id, (uint32_t)config.node_ids[i]);
            const int32_t state = f.sensors[i].state;
            ASSERT_TRUE(state >= MOCAP_SENSOR_FRESH && state <= MOCAP_SENSOR_ABSENT) << state;
            states_seen |= 1 << state;
            // The state says what the flags and the fresh mask say.
            EXPECT_EQ(state == MOCAP_SENSOR_FRESH, (f.fresh_mask >> i & 1u) != 0) << "frame " << f.sequence;
            EXPECT_EQ(state == MOCAP_SENSOR_SILENT, (f.sensors[i].flags & MOCAP_SENSOR_STALE) != 0);
        }
        for (int i = 7; i < MOCAP_MAX_SENSORS; ++i) ASSERT_EQ(f.sensors[i].flags, 0u);
        fresh_chest += f.sensors[0].state == MOCAP_SENSOR_FRESH;
    }
    EXPECT_GT(fresh_chest, frames.size() * 9 / 10);
    EXPECT_TRUE(states_seen & (1 << MOCAP_SENSOR_FRESH));
    EXPECT_TRUE(states_seen & (1 << MOCAP_SENSOR_HOLDING)); // after the last sample, held
    // Within the six-sensor replay's bound (mean 1 deg) of each segment's own truth.
    ErrorStats errors;
    for (const auto &f : frames) score_frame(truth, f, errors);
    for (int i = 0; i < 7; ++i) {
        SCOPED_TRACE(mocap_segment_name(order[i]));
        ASSERT_GT(errors.count(i), 400u);
        EXPECT_LT(errors.mean(i), 1.0);
    }
}

// The chest configured but its node never sends (a six-sensor capture). Optional: calibration
// is accepted with the chest left out and frames are calibrated; required: refused naming it.
TEST(Session, ASilentChestIsLeftOutOnlyWhenOptional)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 23;
    cfg.motion_s = 2.0;
    add_realistic_noise(cfg);
    std::string capture = test_temp_path("six.cap");
    ASSERT_EQ(synth_write_capture(&cfg, synth_builtin_motion("walk"), nullptr, capture.c_str(), nullptr),
              MOCAP_OK) << mocap_last_error();
    {
        mocap_session_config config = seven_sensor_replay(capture, 1u << 6);
        SessionCloser session;
        ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
        std::vector<mocap_frame> frames = replay_with_prelude(session.s, cfg);
        mocap_calibration_report rep;
        ASSERT_EQ(mocap_calibration_get_step_report(session.s, MOCAP_CALIBRATION_TPOSE, &rep), MOCAP_OK);
        ASSERT_EQ(rep.state, MOCAP_CALIBRATION_ACCEPTED) << rep.reason;
        EXPECT_EQ(rep.sensors[6].segment, MOCAP_SEGMENT_CHEST);
        EXPECT_EQ(rep.sensors[6].left_out, 1);
        ASSERT_FALSE(frames.empty());
        const mocap_frame &last = frames.back();
        EXPECT_TRUE(last.flags & MOCAP_FRAME_CALIBRATED);
        EXPECT_EQ(last.sensors[6].state, MOCAP_SENSOR_ABSENT);
        EXPECT_FALSE(last.sensors[6].flags & MOCAP_SENSOR_CALIBRATED);
        EXPECT_FALSE(last.flags & MOCAP_FRAME_COMPLETE);
    }
    {
        mocap_session_config config = seven_sensor_replay(capture, 0);
        SessionCloser session;
        ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
        std::vector<mocap_frame> frames = replay_with_prelude(session.s, cfg);
        mocap_calibration_report rep;
        ASSERT_EQ(mocap_calibration_get_step_report(session.s, MOCAP_CALIBRATION_HEADING, &rep), MOCAP_OK);
        EXPECT_EQ(rep.state, MOCAP_CALIBRATION_REFUSED);
        EXPECT_NE(std::string(rep.reason).find("chest"), std::string::npos) << rep.reason;
        for (const auto &f : frames) ASSERT_FALSE(f.flags & MOCAP_FRAME_CALIBRATED);
    }
}

// Each mistake in a sensor set is refused at open with a message that names it.
TEST(Session, RejectsBadSensorSetsNamingTheProblem)
{
    struct Case {
        const char *what;
        void (*change)(mocap_session_config &);
        const char *needle;
    };
    const Case cases[] = {
        {"duplicate segment", [](mocap_session_config &c) { c.sensor_segments[3] = MOCAP_SEGMENT_PELVIS; },
         "pelvis"},
        {"duplicate node", [](mocap_session_config &c) { c.node_ids[6] = 2; }, "node id 2"},
        {"unknown segment", [](mocap_session_config &c) { c.sensor_segments[6] = 7; }, "segment 7"},
        {"negative segment", [](mocap_session_config &c) { c.sensor_segments[1] = -1; }, "segment -1"},
        {"node out of range", [](mocap_session_config &c) { c.node_ids[6] = 256; }, "256"},
        {"no sensors", [](mocap_session_config &c) { c.sensor_count = 0; }, "sensor_count 0"},
        {"too many sensors", [](mocap_session_config &c) { c.sensor_count = 17; }, "sensor_count 17"},
        {"optional beyond the count", [](mocap_session_config &c) { c.optional_mask = 1u << 7; },
         "optional_mask"},
    };
    for (const Case &k : cases) {
        mocap_session_config c = serial_config("/dev/null");
        c.sensor_count = 7;
        c.sensor_segments[6] = MOCAP_SEGMENT_CHEST;
        c.node_ids[6] = 6;
        k.change(c);
        mocap_session *s = nullptr;
        mocap_clear_error();
        EXPECT_EQ(mocap_session_open(&c, &s), MOCAP_ERR_INVALID_ARGUMENT) << k.what;
        EXPECT_EQ(s, nullptr) << k.what;
        EXPECT_NE(std::string(mocap_last_error()).find(k.needle), std::string::npos)
            << k.what << ": " << mocap_last_error();
        mocap_session_close(s);
    }
}

// A saved calibration is applied by segment: a session listing the sensors in another order, or
// only some of them, gets each sensor's own entry.
TEST(Session, CalibrationSetMatchesEntriesBySegment)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.motion_s = 1.0;
    std::string capture = test_temp_path("bysegment.cap");
    ASSERT_EQ(synth_write_capture(&cfg, synth_builtin_motion("walk"), nullptr, capture.c_str(), nullptr), MOCAP_OK);
    static mocap_calibration six, now;
    const int32_t segments[kSensors] = {0, 1, 2, 3, 4, 5};
    calib_identity(&six, kSensors, segments);
    for (int i = 0; i < kSensors; ++i) {
        six.acceleration_offset[i][1] = 9.0f + 0.1f * (float)i; // tells the entries apart
    }
    six.valid_mask = six.heading_mask = 0x3F;
    mocap_session_config config = replay_config(capture);
    config.sensor_count = 3;
    config.sensor_segments[0] = MOCAP_SEGMENT_HEAD;
    config.sensor_segments[1] = MOCAP_SEGMENT_CHEST;
    config.sensor_segments[2] = MOCAP_SEGMENT_PELVIS;
    config.node_ids[0] = 5;
    config.node_ids[1] = 6;
    config.node_ids[2] = 0;
    SessionCloser session;
    ASSERT_EQ(mocap_session_open(&config, &session.s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_calibration_set(session.s, &six), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_calibration_get(session.s, &now), MOCAP_OK);
    EXPECT_EQ(now.sensor_count, 3u);
    EXPECT_EQ(now.segments[0], MOCAP_SEGMENT_HEAD);
    EXPECT_EQ(now.segments[1], MOCAP_SEGMENT_CHEST);
    EXPECT_EQ(now.segments[2], MOCAP_SEGMENT_PELVIS);
    EXPECT_FLOAT_EQ(now.acceleration_offset[0][1], 9.5f); // the head's entry
    EXPECT_FLOAT_EQ(now.acceleration_offset[2][1], 9.0f); // the pelvis's
    EXPECT_EQ(now.valid_mask, 0x5u); // the chest has no entry: uncalibrated

    // Nothing in common: refused.
    mocap_session_config chest_only = replay_config(capture);
    chest_only.sensor_count = 1;
    chest_only.sensor_segments[0] = MOCAP_SEGMENT_CHEST;
    chest_only.node_ids[0] = 6;
    SessionCloser other;
    ASSERT_EQ(mocap_session_open(&chest_only, &other.s), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(mocap_calibration_set(other.s, &six), MOCAP_ERR_INVALID_ARGUMENT);
}

