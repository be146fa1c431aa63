// The pose solver (src/pose/solver.c, src/pose/model.c) through the public API against the REAL ONNX
// Runtime (scripts/fetch_onnxruntime.sh) and the shipped model (Runtime/Models/
// mocap_pose_fp32.onnx, untrained: only its contract is relied on, never its accuracy).
// Skips only when ONNX Runtime cannot be loaded.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "e2e_support.h"
#if !defined(_WIN32)
#include "fake_receiver.h"
#endif
#include "test_support.h"

extern "C" {
#include "mocap_math.h"
#include "onnx_runtime.h"
#include "pose_limits.h"
#include "chest_follow.h"
#include "platform.h"
#include "skeleton_fk.h"
#include "smpl_skeleton.h"
#include "solver.h"
}

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;
const fs::path kTestsDir = fs::path(__FILE__).parent_path();
const std::string kShippedModel =
    (kTestsDir / ".." / ".." / "Runtime" / "Models" / "mocap_pose_fp32.onnx").string();
const std::string kShippedChestModel =
    (kTestsDir / ".." / ".." / "Runtime" / "Models" / "mocap_pose_chest_int8.onnx").string();

#define REQUIRE_ORT()                                                                         \
    do {                                                                                      \
        if (!ort_library_available(nullptr))                                                  \
            GTEST_SKIP() << "ONNX Runtime not available: " << mocap_last_error();             \
    } while (0)

double seconds_since(Clock::time_point t0)
{
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct Model {
    mocap_model *m = nullptr;
    ~Model() { mocap_model_close(m); }
};
struct Solver {
    mocap_solver *s = nullptr;
    ~Solver() { mocap_solver_close(s); }
};
struct Sessions {
    std::vector<mocap_session *> list;
    ~Sessions()
    {
        for (auto *s : list) mocap_session_close(s);
    }
};

// A hand-made frame of the default six sensors, each calibrated and fresh, at rest.
mocap_frame calibrated_six_frame()
{
    mocap_frame f;
    memset(&f, 0, sizeof f);
    f.flags = MOCAP_FRAME_CALIBRATED | MOCAP_FRAME_COMPLETE;
    f.sensor_count = 6;
    for (int s = 0; s < 6; ++s) {
        f.sensors[s].segment = s;
        f.sensors[s].state = MOCAP_SENSOR_FRESH;
        f.sensors[s].flags = MOCAP_SENSOR_VALID | MOCAP_SENSOR_CALIBRATED;
        f.sensors[s].bone_orientation[0] = 1.0f;
    }
    f.fresh_mask = 0x3f;
    return f;
}

// The same frame with no sensor calibrated.
mocap_frame uncalibrated(mocap_frame f)
{
    f.flags &= ~(uint32_t)MOCAP_FRAME_CALIBRATED;
    for (uint32_t s = 0; s < f.sensor_count; ++s) f.sensors[s].flags &= ~(uint32_t)MOCAP_SENSOR_CALIBRATED;
    return f;
}

mocap_status open_model(const std::string &path, mocap_model **out)
{
    mocap_model_options o;
    mocap_model_options_defaults(&o);
    o.intra_op_threads = 1;  // the machine may be busy: one thread gives stable timings
    return mocap_model_open(path.c_str(), &o, out);
}

// A short generated capture with a calibration prelude (2 s heading, 1 s strap, 2 s T-pose);
// extra_chest adds a chest sensor on node 6 to the default six.
synth_config short_capture(uint64_t seed, double motion_s, const char *motion,
                           const std::string &path, bool extra_chest = false,
                           const std::vector<synth_silence> &silences = {})
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = seed;
    cfg.heading_s = 2.0;
    cfg.strap_s = 1.0;
    cfg.tpose_s = 2.0;
    cfg.motion_s = motion_s;
    add_realistic_noise(cfg);
    if (extra_chest) {
        cfg.segments[cfg.sensor_count] = MOCAP_SEGMENT_CHEST;
        cfg.node_ids[cfg.sensor_count] = 6;
        cfg.sensor_count++;
    }
    for (const synth_silence &s : silences) cfg.silences[cfg.silence_count++] = s;
    EXPECT_EQ(synth_write_capture(&cfg, synth_builtin_motion(motion), nullptr, path.c_str(), nullptr),
              MOCAP_OK) << mocap_last_error();
    return cfg;
}

// A replay session config of the capture (the default sensor set).
mocap_session_config replay_config(const std::string &path)
{
    mocap_session_config c;
    mocap_config_defaults(&c);
    c.source_kind = MOCAP_SOURCE_REPLAY;
    snprintf(c.path, sizeof c.path, "%s", path.c_str());
    return c;
}

// Opens the session with both prelude windows of cfg's capture scheduled before the start.
mocap_session *open_with_prelude(const mocap_session_config &c, const synth_config &cfg)
{
    mocap_session *s = nullptr;
    EXPECT_EQ(mocap_session_open(&c, &s), MOCAP_OK) << mocap_last_error();
    if (!s) return nullptr;
    double t0 = synth_session_time(&cfg, 0.0);
    EXPECT_EQ(mocap_calibration_schedule(s, MOCAP_CALIBRATION_HEADING, t0 + 0.5,
                                         (float)(cfg.heading_s - 1.0)), MOCAP_OK);
    EXPECT_EQ(mocap_calibration_schedule(s, MOCAP_CALIBRATION_TPOSE,
                                         t0 + cfg.heading_s + cfg.strap_s + 0.5,
                                         (float)(cfg.tpose_s - 1.0)), MOCAP_OK);
    return s;
}

// Opens a replay of the capture with both prelude windows scheduled before the start.
mocap_session *open_replay(const std::string &path, const synth_config &cfg, int realtime = 0,
                           float rate = 60.0f)
{
    mocap_session_config c = replay_config(path);
    c.replay_realtime = realtime;
    c.output_rate_hz = rate;
    return open_with_prelude(c, cfg);
}

// Drains every character until each reported END_OF_STREAM (or the timeout).
bool drain_to_end(mocap_solver *solver, int characters, std::vector<std::vector<mocap_pose>> &poses,
                  double timeout_s)
{
    poses.assign(characters, {});
    std::vector<int> ended(characters, 0);
    std::vector<mocap_pose> buf(64);
    auto t0 = Clock::now();
    int remaining = characters;
    while (remaining > 0 && seconds_since(t0) < timeout_s) {
        bool any = false;
        for (int c = 0; c < characters; ++c) {
            if (ended[c]) continue;
            uint32_t n = 0;
            mocap_status st = mocap_solver_drain(solver, c, buf.data(), (uint32_t)buf.size(), &n);
            poses[c].insert(poses[c].end(), buf.begin(), buf.begin() + n);
            if (n > 0) any = true;
            if (st == MOCAP_ERR_END_OF_STREAM) {
                ended[c] = 1;
                --remaining;
            } else if (st != MOCAP_OK && st != MOCAP_ERR_NO_DATA) {
                ADD_FAILURE() << mocap_status_name(st) << ": " << mocap_last_error();
                return false;
            }
        }
        if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return remaining == 0;
}

double quat_norm_f(const float q[4])
{
    return std::sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3]);
}

// Every pose: unit finite rotations, FK positions consistent with the rotations, consecutive.
void check_poses(const std::vector<mocap_pose> &poses, const mocap_model_info &info, int character)
{
    skeleton sk;
    ASSERT_EQ(skeleton_init(&sk, info.joint_parents, info.rest_offsets, MOCAP_JOINT_COUNT), MOCAP_OK);
    for (size_t i = 0; i < poses.size(); ++i) {
        const mocap_pose &p = poses[i];
        SCOPED_TRACE(testing::Message() << "character " << character << " pose " << i);
        ASSERT_EQ(p.sequence, (uint64_t)i);
        ASSERT_EQ(p.character, (uint32_t)character);
        if (i > 0) {
            ASSERT_GT(p.frame_sequence, poses[i - 1].frame_sequence);
            ASSERT_GT(p.time_s, poses[i - 1].time_s);
        }
        double q[MOCAP_JOINT_COUNT][4], pos[MOCAP_JOINT_COUNT][3];
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            for (int k = 0; k < 4; ++k) {
                ASSERT_TRUE(std::isfinite(p.joint_rotations[j][k]));
                q[j][k] = p.joint_rotations[j][k];
            }
            ASSERT_NEAR(quat_norm_f(p.joint_rotations[j]), 1.0, 1e-5);
        }
        double root[3] = {p.root_position[0], p.root_position[1], p.root_position[2]};
        skeleton_fk(&sk, q, root, nullptr, pos);
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
            for (int k = 0; k < 3; ++k) ASSERT_NEAR(p.joint_positions[j][k], pos[j][k], 2e-5) << j;
        for (int k = 0; k < 2; ++k) {
            ASSERT_GE(p.foot_contact[k], 0.0f);
            ASSERT_LE(p.foot_contact[k], 1.0f);
        }
        ASSERT_EQ((p.flags & MOCAP_POSE_CONTACT_LEFT) != 0, p.foot_contact[0] >= 0.5f);
        // Latency stamps of a replay: receive <= frame <= pose, all on the recorded timeline.
        ASSERT_LE(p.newest_receive_ns, p.frame_emitted_ns);
        ASSERT_LE(p.frame_emitted_ns, p.pose_emitted_ns);
        // Drift correction keeps every sole on or above the floor (0).
        for (int f = 0; f < 2; ++f) {
            int j = f == 0 ? SKELETON_LEFT_FOOT : SKELETON_RIGHT_FOOT;
            ASSERT_GE(p.joint_positions[j][1] - sk.foot_height[f], -1e-4);
        }
    }
}

std::string python_with_onnx()
{
    for (const char *p : {"/usr/bin/python3", "python3"}) {
        std::string cmd = std::string("\"") + p + "\" -c \"import onnx\" >/dev/null 2>&1";
        if (std::system(cmd.c_str()) == 0) return p;
    }
    return "";
}

// The fixture models of make_onnx_fixtures.py written into dir; false (with a failure) if not.
bool write_onnx_fixtures(const std::string &dir)
{
#if defined(MOCAP_ONNX_FIXTURES_DIR)
    // Python cannot be started from inside the test here (Windows under Wine): ctest's
    // onnx_fixtures step ran make_onnx_fixtures.py on the build machine before this test.
    std::error_code ec;
    for (const auto &model : std::filesystem::directory_iterator(MOCAP_ONNX_FIXTURES_DIR))
        if (!ec) std::filesystem::copy_file(model.path(), std::filesystem::path(dir) / model.path().filename(),
                                 std::filesystem::copy_options::overwrite_existing, ec);
    EXPECT_FALSE(ec) << "copying the fixtures of " MOCAP_ONNX_FIXTURES_DIR ": " << ec.message();
    return std::filesystem::exists(dir + "/valid.onnx");
#endif
    std::string py = python_with_onnx();
    EXPECT_FALSE(py.empty()) << "python3 with the onnx package is needed (python3-onnx)";
    if (py.empty()) return false;
    std::string cmd = "\"" + py + "\" \"" + (kTestsDir / "make_onnx_fixtures.py").string() + "\" \"" +
                      dir + "\" >/dev/null";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    return std::filesystem::exists(dir + "/valid.onnx");
}

void report_timing(mocap_solver *solver, const char *what)
{
    mocap_solver_stats st;
    ASSERT_EQ(mocap_solver_get_stats(solver, -1, &st), MOCAP_OK);
    if (st.ticks == 0) return;
    printf("[ timing   ] %s: %llu ticks, per tick %.1f us (inference %.1f us), max %.1f us, "
           "batched calls %llu, max batch %llu\n", what, (unsigned long long)st.ticks,
           st.solve_ns_total / 1e3 / st.ticks, st.run_ns_total / 1e3 / st.ticks,
           st.solve_ns_max / 1e3, (unsigned long long)st.batched_calls,
           (unsigned long long)st.max_batch);
}

}  // namespace

// Most solver tests run on the shipped model: skipped without ONNX Runtime, opened once per test.
class SolverOnShippedModel : public ::testing::Test {
protected:
    void SetUp() override
    {
        REQUIRE_ORT();
        ASSERT_EQ(open_model(kShippedModel, &model.m), MOCAP_OK) << mocap_last_error();
    }
    Model model;
};

TEST(Solver, MissingModelIsNotFoundNamingTheFile)
{
    REQUIRE_ORT();
    mocap_model *m = nullptr;
    std::string path = test_temp_path("no_such_pose_model.onnx");
    EXPECT_EQ(open_model(path, &m), MOCAP_ERR_NOT_FOUND);
    EXPECT_EQ(m, nullptr);
    EXPECT_NE(std::string(mocap_last_error()).find("no_such_pose_model.onnx"), std::string::npos)
        << mocap_last_error();
}

TEST_F(SolverOnShippedModel, ModelInfoFollowsTheContract)
{
    mocap_model_info info;
    ASSERT_EQ(mocap_model_get_info(model.m, &info), MOCAP_OK);
    EXPECT_EQ(info.contract_version, 1);
    EXPECT_FLOAT_EQ(info.frame_rate, 60.0f);
    EXPECT_GE(info.state_layers, 1);
    EXPECT_GE(info.state_size, 1);
    EXPECT_EQ(info.joint_parents[0], -1);
    EXPECT_EQ(info.joint_parents[20], 18);
    EXPECT_STREQ(info.joint_names[10], "left_foot");
    EXPECT_STREQ(info.precision, "fp32");
    EXPECT_GT(info.rest_offsets[0][1], 0.5f);  // pelvis height
    mocap_model_options bad;
    mocap_model_options_defaults(&bad);
    bad.struct_size = 4;
    mocap_model *m = nullptr;
    EXPECT_EQ(mocap_model_open(kShippedModel.c_str(), &bad, &m), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("struct_size"), std::string::npos);
}

#if defined(__linux__)
// Threads of this process, from /proc/self/task.
size_t process_threads()
{
    size_t n = 0;
    for (const auto &entry : fs::directory_iterator("/proc/self/task")) {
        (void)entry;
        ++n;
    }
    return n;
}

// The default options run ONNX Runtime on the calling thread: its own default (a pool thread
// per core) kept an idle thread spinning, a whole core busy for the life of a live session, for
// no faster frames. Asking for two threads does start a pool, so the count can tell.
TEST(Solver, DefaultModelOptionsStartNoOnnxRuntimeThreadPool)
{
    REQUIRE_ORT();
    mocap_model_options o;
    ASSERT_EQ(mocap_model_options_defaults(&o), MOCAP_OK);
    EXPECT_EQ(o.intra_op_threads, 1);
    {
        Model warm;   // the runtime's own one-off threads (environment, logging) start here
        ASSERT_EQ(mocap_model_open(kShippedModel.c_str(), &o, &warm.m), MOCAP_OK) << mocap_last_error();
    }
    const size_t before = process_threads();
    {
        Model m;
        ASSERT_EQ(mocap_model_open(kShippedModel.c_str(), &o, &m.m), MOCAP_OK) << mocap_last_error();
        EXPECT_EQ(process_threads(), before);
    }
    o.intra_op_threads = 2;
    Model two;
    ASSERT_EQ(mocap_model_open(kShippedModel.c_str(), &o, &two.m), MOCAP_OK) << mocap_last_error();
    EXPECT_GT(process_threads(), before);
}
#endif

// Wrong models are refused naming what differs; afterwards a correct model still opens and
// solves a capture end to end in the same process.
TEST(Solver, WrongModelIsRefusedByNameAndTheProcessStaysUsable)
{
    REQUIRE_ORT();
    std::string dir = test_temp_dir();
    ASSERT_TRUE(write_onnx_fixtures(dir));
    struct Case {
        const char *file, *mention;
    } cases[] = {{"wrong_version.onnx", "contract_version"},
                 {"wrong_joint_name.onnx", "left_forearm"},
                 {"wrong_input_name.onnx", "imu_orientation"},
                 {"state_mismatch.onnx", "state"},
                 {"not_onnx.onnx", "not a model ONNX Runtime can load"}};
    for (const auto &c : cases) {
        SCOPED_TRACE(c.file);
        mocap_model *m = nullptr;
        EXPECT_EQ(open_model(dir + "/" + c.file, &m), MOCAP_ERR_FORMAT);
        EXPECT_EQ(m, nullptr);
        std::string err = mocap_last_error();
        EXPECT_NE(err.find(c.mention), std::string::npos) << err;
        EXPECT_NE(err.find(c.file), std::string::npos) << err;
    }

    Model model;
    ASSERT_EQ(open_model(kShippedModel, &model.m), MOCAP_OK) << mocap_last_error();
    std::string cap = dir + "/after.cap";
    synth_config cfg = short_capture(31, 2.0, "walk", cap);
    Sessions sessions;
    sessions.list.push_back(open_replay(cap, cfg));
    ASSERT_NE(sessions.list[0], nullptr);
    Solver solver;
    ASSERT_EQ(mocap_solver_open(model.m, nullptr, &solver.s), MOCAP_OK) << mocap_last_error();
    int32_t ch = -1;
    ASSERT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_solver_start(solver.s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_session_start(sessions.list[0]), MOCAP_OK);
    std::vector<std::vector<mocap_pose>> poses;
    ASSERT_TRUE(drain_to_end(solver.s, 1, poses, 60));
    EXPECT_GT(poses[0].size(), 100u);
}

TEST_F(SolverOnShippedModel, SessionRateDifferentFromTheModelRateIsRefusedAtAddCharacter)
{
    std::string cap = test_temp_path("rate.cap");
    synth_config cfg = short_capture(32, 1.0, "walk", cap);
    Sessions sessions;
    sessions.list.push_back(open_replay(cap, cfg, 0, 50.0f));
    ASSERT_NE(sessions.list[0], nullptr);
    Solver solver;
    ASSERT_EQ(mocap_solver_open(model.m, nullptr, &solver.s), MOCAP_OK);
    int32_t ch = -1;
    EXPECT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_ERR_INVALID_ARGUMENT);
    std::string err = mocap_last_error();
    EXPECT_NE(err.find("50 Hz"), std::string::npos) << err;
    EXPECT_NE(err.find("60 Hz"), std::string::npos) << err;
    // Nothing was added: starting is refused clearly, and bad indices too.
    EXPECT_EQ(mocap_solver_start(solver.s), MOCAP_ERR_STATE);
    mocap_pose pose;
    EXPECT_EQ(mocap_solver_poll_latest(solver.s, 0, &pose), MOCAP_ERR_INVALID_ARGUMENT);
}

TEST_F(SolverOnShippedModel, ReplaySolvedEndToEnd)
{
    mocap_model_info info;
    mocap_model_get_info(model.m, &info);
    std::string cap = test_temp_path("walk.cap");
    synth_config cfg = short_capture(33, 6.0, "mixed", cap);
    Sessions sessions;
    sessions.list.push_back(open_replay(cap, cfg));
    ASSERT_NE(sessions.list[0], nullptr);
    Solver solver;
    ASSERT_EQ(mocap_solver_open(model.m, nullptr, &solver.s), MOCAP_OK) << mocap_last_error();
    int32_t ch = -1;
    ASSERT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(ch, 0);
    EXPECT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_ERR_INVALID_ARGUMENT);
    mocap_pose pose;
    EXPECT_EQ(mocap_solver_poll_latest(solver.s, 0, &pose), MOCAP_ERR_NO_DATA);
    ASSERT_EQ(mocap_solver_start(solver.s), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_ERR_STATE);
    ASSERT_EQ(mocap_session_start(sessions.list[0]), MOCAP_OK);

    std::vector<std::vector<mocap_pose>> poses;
    ASSERT_TRUE(drain_to_end(solver.s, 1, poses, 60));
    EXPECT_EQ(mocap_solver_poll_latest(solver.s, 0, &pose), MOCAP_ERR_END_OF_STREAM);
    uint32_t n = 0;
    EXPECT_EQ(mocap_solver_drain(solver.s, 0, &pose, 1, &n), MOCAP_ERR_END_OF_STREAM);
    EXPECT_EQ(n, 0u);

    // Every calibrated frame became a pose, nothing lost: poses + skipped == frames emitted.
    mocap_session_stats ss;
    ASSERT_EQ(mocap_session_get_stats(sessions.list[0], &ss), MOCAP_OK);
    mocap_solver_stats st;
    ASSERT_EQ(mocap_solver_get_stats(solver.s, 0, &st), MOCAP_OK);
    EXPECT_EQ(ss.frames_dropped, 0u);
    EXPECT_EQ(st.frames_nonfinite, 0u);
    EXPECT_EQ(st.poses_dropped, 0u);
    EXPECT_GT(st.frames_uncalibrated, 200u);  // the prelude
    EXPECT_EQ(st.frames_solved, poses[0].size());
    EXPECT_EQ(st.frames_solved + st.frames_uncalibrated, ss.frames_emitted);
    // Calibrated from the end of the T-pose window (0.5 s before the motion) to the end.
    EXPECT_GE((double)poses[0].size(), (cfg.motion_s + 0.4) * 60.0);
    for (size_t i = 1; i < poses[0].size(); ++i)
        ASSERT_EQ(poses[0][i].frame_sequence, poses[0][i - 1].frame_sequence + 1) << i;
    check_poses(poses[0], info, 0);
    report_timing(solver.s, "1 character");

    // The same counters by key (the replay has ended: nothing moves any more).
    ASSERT_EQ(mocap_session_get_stats(sessions.list[0], &ss), MOCAP_OK);
    const uint64_t session_expected[MOCAP_SESSION_COUNTER_COUNT] = {
        ss.bytes_received, ss.frames_decoded, ss.crc_failures, ss.bytes_skipped, ss.unknown_packets,
        ss.samples_decoded, ss.samples_rejected, ss.frames_emitted, ss.frames_dropped,
        ss.bytes_dropped, ss.reconnects, ss.capture_bytes_written, ss.replay_chunks_skipped,
        (uint64_t)ss.replay_tail_damaged, ss.sensors_seen_mask};
    for (int32_t key = 0; key < MOCAP_SESSION_COUNTER_COUNT; ++key) {
        uint64_t value = 12345;
        ASSERT_EQ(mocap_session_get_counter(sessions.list[0], key, &value), MOCAP_OK) << key;
        EXPECT_EQ(value, session_expected[key]) << "session counter " << key;
    }
    EXPECT_GT(session_expected[MOCAP_SESSION_BYTES_RECEIVED], 0u);
    EXPECT_EQ(session_expected[MOCAP_SESSION_SENSORS_SEEN_MASK], 0x3Fu);
    for (int32_t character : {-1, 0}) {
        ASSERT_EQ(mocap_solver_get_stats(solver.s, character, &st), MOCAP_OK);
        const uint64_t solver_expected[MOCAP_SOLVER_COUNTER_COUNT] = {
            st.ticks, st.batched_calls, st.max_batch, st.frames_solved, st.frames_uncalibrated,
            st.frames_nonfinite, st.outputs_nonfinite, st.poses_dropped, st.run_failures,
            st.solve_ns_total, st.solve_ns_max, st.run_ns_total};
        for (int32_t key = 0; key < MOCAP_SOLVER_COUNTER_COUNT; ++key) {
            uint64_t value = 12345;
            ASSERT_EQ(mocap_solver_get_counter(solver.s, character, key, &value), MOCAP_OK) << key;
            EXPECT_EQ(value, solver_expected[key]) << "solver counter " << key << ", character " << character;
        }
        EXPECT_EQ(solver_expected[MOCAP_SOLVER_FRAMES_SOLVED], poses[0].size());
    }
}

// Counters grow as keys: a key the library does not know is refused by name, not read as 0.
TEST_F(SolverOnShippedModel, UnknownCounterKeysAreRefusedWithTheKeyAndTheVersion)
{
    std::string cap = test_temp_path("keys.cap");
    synth_config cfg = short_capture(35, 1.0, "walk", cap);
    Sessions sessions;
    sessions.list.push_back(open_replay(cap, cfg));
    ASSERT_NE(sessions.list[0], nullptr);
    Solver solver;
    ASSERT_EQ(mocap_solver_open(model.m, nullptr, &solver.s), MOCAP_OK) << mocap_last_error();
    int32_t ch = -1;
    ASSERT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_OK);
    uint64_t value = 7;
    EXPECT_EQ(mocap_session_get_counter(sessions.list[0], MOCAP_SESSION_COUNTER_COUNT, &value),
              MOCAP_ERR_UNSUPPORTED);
    EXPECT_NE(std::string(mocap_last_error()).find("session counter 15 is not known"), std::string::npos)
        << mocap_last_error();
    const std::string version = "API " + std::to_string(MOCAP_API_VERSION) + "." +
                                std::to_string(MOCAP_API_VERSION_MINOR);
    EXPECT_NE(std::string(mocap_last_error()).find(version), std::string::npos) << mocap_last_error();
    EXPECT_EQ(value, 7u);
    EXPECT_EQ(mocap_session_get_counter(sessions.list[0], -1, &value), MOCAP_ERR_UNSUPPORTED);
    EXPECT_EQ(mocap_solver_get_counter(solver.s, -1, MOCAP_SOLVER_COUNTER_COUNT, &value), MOCAP_ERR_UNSUPPORTED);
    EXPECT_NE(std::string(mocap_last_error()).find("solver counter 12 is not known"), std::string::npos)
        << mocap_last_error();
    EXPECT_EQ(mocap_session_get_counter(sessions.list[0], 0, nullptr), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(mocap_session_get_counter(nullptr, 0, &value), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(mocap_solver_get_counter(solver.s, 5, MOCAP_SOLVER_TICKS, &value), MOCAP_ERR_INVALID_ARGUMENT)
        << "character 5 does not exist";
    EXPECT_EQ(mocap_api_version_minor(), MOCAP_API_VERSION_MINOR);
}

// The solver's defaults with the output filter off: poses are the model's own outputs.
mocap_solver_config raw_output_config()
{
    mocap_solver_config c;
    mocap_solver_config_defaults(&c);
    c.smoothing_min_cutoff_hz = 0.0f;
    return c;
}

// The poses of one replay solved with the given solver config (nullptr: defaults), smoothing
// delay, foot pinning and pose limits.
std::vector<mocap_pose> solve_replay(mocap_model *model, const std::string &cap, const synth_config &cfg,
                                     const mocap_solver_config *config, int32_t smoothing_delay = 0,
                                     float foot_pin = 0.0f, float pose_limits = 0.0f)
{
    Sessions sessions;
    sessions.list.push_back(open_replay(cap, cfg));
    Solver solver;
    std::vector<std::vector<mocap_pose>> poses;
    int32_t ch = -1;
    if (!sessions.list[0] || mocap_solver_open(model, config, &solver.s) != MOCAP_OK ||
        mocap_solver_set_smoothing_delay(solver.s, smoothing_delay) != MOCAP_OK ||
        mocap_solver_set_foot_pinning(solver.s, foot_pin) != MOCAP_OK ||
        mocap_solver_set_pose_limits(solver.s, pose_limits) != MOCAP_OK ||
        mocap_solver_add_character(solver.s, sessions.list[0], &ch) != MOCAP_OK ||
        mocap_solver_start(solver.s) != MOCAP_OK || mocap_session_start(sessions.list[0]) != MOCAP_OK) {
        ADD_FAILURE() << mocap_last_error();
        return {};
    }
    EXPECT_TRUE(drain_to_end(solver.s, 1, poses, 60));
    return poses[0];
}

// Mean |third difference| of the root-relative joint positions (m per frame^3): jitter.
double mean_jerk(const std::vector<mocap_pose> &poses)
{
    double sum = 0.0;
    size_t n = 0;
    for (size_t t = 3; t < poses.size(); ++t)
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            double d2 = 0.0;
            for (int k = 0; k < 3; ++k) {
                auto rel = [&](size_t i) {
                    return (double)poses[i].joint_positions[j][k] - poses[i].root_position[k];
                };
                double d = rel(t) - 3.0 * rel(t - 1) + 3.0 * rel(t - 2) - rel(t - 3);
                d2 += d * d;
            }
            sum += std::sqrt(d2);
            ++n;
        }
    return n ? sum / n : 0.0;
}

TEST_F(SolverOnShippedModel, SmoothingRemovesJitterAndCanBeTurnedOff)
{
    std::string cap = test_temp_path("smooth.cap");
    synth_config cfg = short_capture(21, 6.0, "mixed", cap);
    const mocap_solver_config off = raw_output_config();
    std::vector<mocap_pose> raw = solve_replay(model.m, cap, cfg, &off);
    std::vector<mocap_pose> raw_again = solve_replay(model.m, cap, cfg, &off);
    std::vector<mocap_pose> smooth = solve_replay(model.m, cap, cfg, nullptr);
    ASSERT_GT(raw.size(), 300u);
    ASSERT_EQ(smooth.size(), raw.size());
    ASSERT_EQ(raw_again.size(), raw.size());
    // off: the model's output as it is (a replay is deterministic)
    EXPECT_EQ(0, memcmp(raw.back().joint_rotations, raw_again.back().joint_rotations,
                        sizeof raw.back().joint_rotations));
    // on: the same motion (a few degrees from the raw output on average) with far less jitter
    double angle = 0.0;
    size_t count = 0;
    for (size_t t = 0; t < raw.size(); ++t)
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            double a[4], b[4];
            for (int k = 0; k < 4; ++k) {
                a[k] = raw[t].joint_rotations[j][k];
                b[k] = smooth[t].joint_rotations[j][k];
            }
            angle += quat_angle_deg(a, b);
            ++count;
        }
    angle /= (double)count;
    EXPECT_GT(angle, 0.05);
    EXPECT_LT(angle, 4.0);
    double jr = mean_jerk(raw), js = mean_jerk(smooth);
    printf("smoothing: mean %.2f deg from the raw output, jerk %.3g -> %.3g m/frame^3\n", angle, jr, js);
    EXPECT_LT(js, jr / 2.0) << "jerk raw " << jr << " smoothed " << js;
    check_poses(smooth, [&] { mocap_model_info i; mocap_model_get_info(model.m, &i); return i; }(), 0);
}

// Smoothing that waits: each pose is the binomial average of the raw rotations around its frame,
// stamped with that frame, one frame later; every frame keeps its pose, the last ones too.
TEST_F(SolverOnShippedModel, SmoothingThatWaitsAveragesAroundEachFrameAndKeepsEveryFrame)
{
    std::string cap = test_temp_path("smooth_wait.cap");
    synth_config cfg = short_capture(22, 5.0, "mixed", cap);
    const mocap_solver_config off = raw_output_config();
    std::vector<mocap_pose> raw = solve_replay(model.m, cap, cfg, &off);
    mocap_solver_config defaults;   // the one-euro filter's setting is ignored while waiting
    mocap_solver_config_defaults(&defaults);
    std::vector<mocap_pose> waited = solve_replay(model.m, cap, cfg, &defaults, 1);
    ASSERT_GT(raw.size(), 250u);
    ASSERT_EQ(waited.size(), raw.size());
    const size_t n = raw.size();
    auto expected = [&](size_t t, int j, double out[4]) {
        const double w[3] = {0.25, 0.5, 0.25};
        double sum[4] = {0, 0, 0, 0};
        for (int o = -1; o <= 1; ++o) {
            size_t i = (size_t)std::min<long>(std::max<long>((long)t + o, 0), (long)n - 1);
            double dot = 0.0;
            for (int k = 0; k < 4; ++k) dot += (double)raw[i].joint_rotations[j][k] * raw[t].joint_rotations[j][k];
            for (int k = 0; k < 4; ++k) sum[k] += w[o + 1] * (dot < 0 ? -1.0 : 1.0) * raw[i].joint_rotations[j][k];
        }
        double norm = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2] + sum[3] * sum[3]);
        for (int k = 0; k < 4; ++k) out[k] = sum[k] / norm;
    };
    double worst = 0.0;
    std::vector<double> waits_ms;
    for (size_t t = 0; t < n; ++t) {
        ASSERT_EQ(waited[t].frame_sequence, raw[t].frame_sequence) << t;
        ASSERT_EQ(waited[t].time_s, raw[t].time_s) << t;
        ASSERT_EQ(waited[t].sequence, (uint64_t)t);
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            double e[4], got[4];
            expected(t, j, e);
            for (int k = 0; k < 4; ++k) got[k] = waited[t].joint_rotations[j][k];
            worst = std::max(worst, quat_angle_deg(e, got));
        }
        // the pose of frame t was ready only once frame t + 1 was: its latency holds the wait
        if (t + 1 < n) {
            ASSERT_GE(waited[t].pose_emitted_ns, waited[t + 1].frame_emitted_ns) << t;
            waits_ms.push_back((waited[t].pose_emitted_ns - waited[t].frame_emitted_ns) / 1e6);
        }
    }
    EXPECT_LT(worst, 1e-3) << "deg from the binomial average of the raw rotations";
    std::sort(waits_ms.begin(), waits_ms.end());
    const double median_wait = waits_ms[waits_ms.size() / 2];
    EXPECT_GE(median_wait, 1000.0 / 60.0 - 0.5);
    double jr = mean_jerk(raw), jw = mean_jerk(waited);
    printf("smoothing that waits: jerk %.3g -> %.3g m/frame^3, latency median %.1f ms\n", jr, jw, median_wait);
    EXPECT_LT(jw, jr / 2.0);
    check_poses(waited, [&] { mocap_model_info i; mocap_model_get_info(model.m, &i); return i; }(), 0);
}

// A solver of the shipped model ticked by hand (solver_prepare + solver_solve, no thread), with
// one character on a replay session that is never started (only its frame rate is used).
void prepare_tick_solver(mocap_model *model, Sessions &sessions, Solver &solver, int32_t *ch,
                         const char *capture_name, int seed, int32_t smoothing_delay = 0)
{
    std::string cap = test_temp_path(capture_name);
    synth_config cfg = short_capture(seed, 1.0, "walk", cap);
    sessions.list.push_back(open_replay(cap, cfg));
    ASSERT_EQ(mocap_solver_open(model, nullptr, &solver.s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_solver_set_smoothing_delay(solver.s, smoothing_delay), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_solver_add_character(solver.s, sessions.list.back(), ch), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(solver_prepare(solver.s), MOCAP_OK) << mocap_last_error();
}

// While waiting, a frame with NaN holds the pose before it (in frame order, flagged incomplete),
// and a reset first hands out the frames still waiting.
TEST(Solver, SmoothingThatWaitsHoldsNonFiniteFramesAndFlushesOnReset)
{
    REQUIRE_ORT();
    Model model;
    ASSERT_EQ(open_model(kShippedModel, &model.m), MOCAP_OK) << mocap_last_error();
    Sessions sessions;
    Solver solver;
    int32_t ch = -1;
    ASSERT_NO_FATAL_FAILURE(prepare_tick_solver(model.m, sessions, solver, &ch, "nan_wait.cap", 61, 1));
    mocap_frame f = calibrated_six_frame();
    std::vector<mocap_frame> frames(6, f);
    for (size_t i = 0; i < frames.size(); ++i) {
        double q[4], axis[3] = {0.3, 1.0, -0.2};
        quat_from_axis_angle(q, axis, 0.05 * (double)i);   // a slow turn of every sensor
        for (int s = 0; s < 6; ++s)
            for (int k = 0; k < 4; ++k) frames[i].sensors[s].bone_orientation[k] = (float)q[k];
        frames[i].sequence = i;
        frames[i].time_s = 10.0 + (double)i / 60.0;
    }
    frames[2].sensors[3].bone_acceleration[0] = NAN;
    frames[3].sensors[1].bone_orientation[0] = INFINITY;
    for (size_t i = 0; i < 5; ++i) {
        const mocap_frame *fp = &frames[i];
        ASSERT_EQ(solver_solve(solver.s, &ch, &fp, nullptr, 1), MOCAP_OK) << mocap_last_error();
    }
    std::vector<mocap_pose> poses(16);
    uint32_t n = 0;
    ASSERT_EQ(mocap_solver_drain(solver.s, 0, poses.data(), (uint32_t)poses.size(), &n), MOCAP_OK);
    ASSERT_EQ(n, 4u) << "frame 4 waits for frame 5";
    for (uint32_t i = 0; i < n; ++i) EXPECT_EQ(poses[i].frame_sequence, i);
    for (int i : {2, 3}) {
        EXPECT_TRUE(poses[i].flags & MOCAP_POSE_INCOMPLETE) << i;
        EXPECT_EQ(0, memcmp(poses[i].joint_rotations, poses[1].joint_rotations, sizeof poses[1].joint_rotations));
    }
    EXPECT_NE(0, memcmp(poses[1].joint_rotations, poses[0].joint_rotations, sizeof poses[0].joint_rotations));
    // A reset (a new calibration) hands out frame 4 before the state is cleared; frame 5 then
    // starts a new window and waits.
    ASSERT_EQ(mocap_solver_reset_character(solver.s, ch), MOCAP_OK);
    const mocap_frame *fp = &frames[5];
    ASSERT_EQ(solver_solve(solver.s, &ch, &fp, nullptr, 1), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_solver_drain(solver.s, 0, poses.data(), (uint32_t)poses.size(), &n), MOCAP_OK);
    ASSERT_EQ(n, 1u);
    EXPECT_EQ(poses[0].frame_sequence, 4u);
    EXPECT_FALSE(poses[0].flags & MOCAP_POSE_INCOMPLETE);
}

TEST_F(SolverOnShippedModel, SmoothingDelayAndFootPinningAreCheckedAndSetBeforeTheStart)
{
    Sessions sessions;   // closed after the solver
    Solver solver;
    ASSERT_EQ(mocap_solver_open(model.m, nullptr, &solver.s), MOCAP_OK) << mocap_last_error();
    for (int32_t bad : {-1, MOCAP_SMOOTHING_DELAY_MAX + 1}) {
        EXPECT_EQ(mocap_solver_set_smoothing_delay(solver.s, bad), MOCAP_ERR_INVALID_ARGUMENT);
        EXPECT_NE(std::string(mocap_last_error()).find("smoothing delay"), std::string::npos);
    }
    EXPECT_EQ(mocap_solver_set_smoothing_delay(nullptr, 1), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(mocap_solver_set_smoothing_delay(solver.s, MOCAP_SMOOTHING_DELAY_MAX), MOCAP_OK);
    EXPECT_EQ(mocap_solver_set_smoothing_delay(solver.s, 0), MOCAP_OK);
    for (float bad : {-0.01f, MOCAP_FOOT_PIN_SLIDE_MAX * 1.5f, std::nanf("")}) {
        EXPECT_EQ(mocap_solver_set_foot_pinning(solver.s, bad), MOCAP_ERR_INVALID_ARGUMENT) << bad;
        EXPECT_NE(std::string(mocap_last_error()).find("foot pinning"), std::string::npos);
    }
    EXPECT_EQ(mocap_solver_set_foot_pinning(nullptr, 0.06f), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(mocap_solver_set_foot_pinning(solver.s, MOCAP_FOOT_PIN_SLIDE_MAX), MOCAP_OK);
    EXPECT_EQ(mocap_solver_set_foot_pinning(solver.s, 0.0f), MOCAP_OK);
    for (float bad : {-1.0f, 0.5f, MOCAP_POSE_LIMITS_MAX_DEG + 1.0f, std::nanf("")}) {
        EXPECT_EQ(mocap_solver_set_pose_limits(solver.s, bad), MOCAP_ERR_INVALID_ARGUMENT) << bad;
        EXPECT_NE(std::string(mocap_last_error()).find("pose limits"), std::string::npos);
    }
    EXPECT_EQ(mocap_solver_set_pose_limits(nullptr, 25.0f), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(mocap_solver_set_pose_limits(solver.s, MOCAP_POSE_LIMITS_MAX_DEG), MOCAP_OK);
    EXPECT_EQ(mocap_solver_set_pose_limits(solver.s, 0.0f), MOCAP_OK);
    for (float bad : {-0.1f, 1.01f, std::nanf("")}) {
        EXPECT_EQ(mocap_solver_set_chest_follow(solver.s, bad), MOCAP_ERR_INVALID_ARGUMENT) << bad;
        EXPECT_NE(std::string(mocap_last_error()).find("chest following"), std::string::npos);
    }
    EXPECT_EQ(mocap_solver_set_chest_follow(nullptr, 0.5f), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(mocap_solver_set_chest_follow(solver.s, 1.0f), MOCAP_OK);
    EXPECT_EQ(mocap_solver_set_chest_follow(solver.s, 0.0f), MOCAP_OK);
    std::string cap = test_temp_path("smooth_delay_state.cap");
    synth_config cfg = short_capture(23, 1.0, "mixed", cap);
    sessions.list.push_back(open_replay(cap, cfg));
    int32_t ch = -1;
    ASSERT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_solver_start(solver.s), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(mocap_solver_set_smoothing_delay(solver.s, 1), MOCAP_ERR_STATE);
    EXPECT_EQ(mocap_solver_set_foot_pinning(solver.s, 0.06f), MOCAP_ERR_STATE);
    EXPECT_EQ(mocap_solver_set_pose_limits(solver.s, 25.0f), MOCAP_ERR_STATE);
    EXPECT_EQ(mocap_solver_set_chest_follow(solver.s, 0.5f), MOCAP_ERR_STATE);
}

// Pose limits guard the network's pose and nothing else: with every sensor live the network reads
// the same inputs either way, so each guarded pose is the guard applied to the free one. A
// tolerance far tighter than the shipped setting makes the guard act on most frames.
TEST_F(SolverOnShippedModel, PoseLimitsGuardEachPoseAndLeaveTheRootAlone)
{
    std::string cap = test_temp_path("pose_limits.cap");
    synth_config cfg = short_capture(25, 4.0, "mixed", cap);
    const mocap_solver_config off = raw_output_config();
    const float tolerance = 3.0f;
    std::vector<mocap_pose> free_pose = solve_replay(model.m, cap, cfg, &off);
    std::vector<mocap_pose> guarded = solve_replay(model.m, cap, cfg, &off, 0, 0.0f, tolerance);
    ASSERT_GT(free_pose.size(), 200u);
    ASSERT_EQ(free_pose.size(), guarded.size());
    pose_limits_state state;
    pose_limits_reset(&state);
    size_t turned = 0, outside_before = 0;
    double worst = 0.0;
    for (size_t t = 0; t < guarded.size(); ++t) {
        double q[MOCAP_JOINT_COUNT][4];
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
            for (int i = 0; i < 4; ++i) q[j][i] = free_pose[t].joint_rotations[j][i];
        for (int j = 1; j < MOCAP_JOINT_COUNT; ++j)
            if (pose_limits_distance_deg(j, q[j]) > tolerance) ++outside_before;
        turned += (size_t)pose_limits_apply(&state, tolerance, q, nullptr);
        for (int i = 0; i < 4; ++i)
            EXPECT_EQ(guarded[t].joint_rotations[0][i], free_pose[t].joint_rotations[0][i]) << t;
        for (int j = 1; j < MOCAP_JOINT_COUNT; ++j) {
            double g[4];
            for (int i = 0; i < 4; ++i) {
                g[i] = guarded[t].joint_rotations[j][i];
                EXPECT_NEAR(g[i], q[j][i], 2e-5) << "pose " << t << " joint " << j;
            }
            worst = std::max(worst, pose_limits_distance_deg(j, g));
        }
        EXPECT_EQ(guarded[t].foot_contact[0], free_pose[t].foot_contact[0]);
        EXPECT_EQ(guarded[t].root_velocity[0], free_pose[t].root_velocity[0]);
    }
    EXPECT_GT(outside_before, guarded.size()) << "the free poses leave a 3 deg range often";
    EXPECT_EQ(turned, outside_before);
    EXPECT_LT(worst, tolerance + 0.01);
}

// Horizontal speeds (m/s) of the feet in the frames where the pose says a foot is planted (in
// contact now and in the frame before).
std::vector<double> planted_foot_speeds(const std::vector<mocap_pose> &poses, double fps)
{
    std::vector<double> out;
    const uint32_t flag[2] = {MOCAP_POSE_CONTACT_LEFT, MOCAP_POSE_CONTACT_RIGHT};
    const int joint[2] = {10, 11};
    for (size_t t = 1; t < poses.size(); ++t)
        for (int f = 0; f < 2; ++f) {
            if (!(poses[t].flags & flag[f]) || !(poses[t - 1].flags & flag[f])) continue;
            const float *a = poses[t - 1].joint_positions[joint[f]], *b = poses[t].joint_positions[joint[f]];
            out.push_back(std::hypot(b[0] - a[0], b[2] - a[2]) * fps);
        }
    return out;
}

// Foot pinning bends the legs of planted feet only: the root, the contacts and the upper body
// are those of the unpinned poses, and a planted foot slides at most the set speed except where
// the hold reaches its 5 cm and the foot is dragged along.
TEST_F(SolverOnShippedModel, FootPinningHoldsPlantedFeetAndLeavesTheRestAlone)
{
    std::string cap = test_temp_path("foot_pin.cap");
    synth_config cfg = short_capture(24, 8.0, "mixed", cap);
    const mocap_solver_config off = raw_output_config();
    const float slide = 0.06f;
    std::vector<mocap_pose> free_feet = solve_replay(model.m, cap, cfg, &off);
    std::vector<mocap_pose> pinned = solve_replay(model.m, cap, cfg, &off, 0, slide);
    ASSERT_GT(free_feet.size(), 400u);
    ASSERT_EQ(pinned.size(), free_feet.size());
    mocap_model_info info;
    ASSERT_EQ(mocap_model_get_info(model.m, &info), MOCAP_OK);
    const double fps = info.frame_rate;
    size_t legs_moved = 0;
    for (size_t t = 0; t < pinned.size(); ++t) {
        const mocap_pose &a = free_feet[t], &b = pinned[t];
        ASSERT_EQ(0, memcmp(a.root_position, b.root_position, sizeof a.root_position)) << t;
        ASSERT_EQ(a.flags, b.flags) << t;
        for (int j : {0, 3, 6, 9, 12, 15, 16, 17, 20, 21})   // the trunk, head and arms
            for (int k = 0; k < 3; ++k)
                ASSERT_NEAR(a.joint_positions[j][k], b.joint_positions[j][k], 1e-6) << t << " joint " << j;
        double d[3] = {b.joint_positions[10][0] - a.joint_positions[10][0],
                       b.joint_positions[10][1] - a.joint_positions[10][1],
                       b.joint_positions[10][2] - a.joint_positions[10][2]};
        EXPECT_LE(std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), 0.05 + 1e-5) << t;
        legs_moved += memcmp(a.joint_rotations[4], b.joint_rotations[4], sizeof a.joint_rotations[4]) != 0;
    }
    std::vector<double> before = planted_foot_speeds(free_feet, fps), after = planted_foot_speeds(pinned, fps);
    ASSERT_GT(before.size(), 100u) << "the capture should plant a foot";
    auto mean = [](const std::vector<double> &v) {
        double s = 0.0;
        for (double x : v) s += x;
        return s / (double)v.size();
    };
    auto median = [](std::vector<double> v) {
        std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
        return v[v.size() / 2];
    };
    printf("planted feet: mean %.3f -> %.3f m/s, median %.3f -> %.3f; legs bent in %zu of %zu poses\n",
           mean(before), mean(after), median(before), median(after), legs_moved, pinned.size());
    EXPECT_GT(legs_moved, 50u);
    EXPECT_LE(median(after), slide + 1e-3);
    EXPECT_LT(mean(after), mean(before));
    check_poses(pinned, info, 0);
}

// Three characters from three replays are solved in batched inference calls.
TEST_F(SolverOnShippedModel, ThreeReplaysAreBatchedInOneCallPerTick)
{
    mocap_model_info info;
    mocap_model_get_info(model.m, &info);
    Sessions sessions;
    Solver solver;
    ASSERT_EQ(mocap_solver_open(model.m, nullptr, &solver.s), MOCAP_OK);
    const char *motions[3] = {"mixed", "mixed", "mixed"};
    for (int c = 0; c < 3; ++c) {
        std::string cap = test_temp_path("c" + std::to_string(c) + ".cap");
        synth_config cfg = short_capture(40 + c, 3.0 + c, motions[c], cap);
        sessions.list.push_back(open_replay(cap, cfg));
        ASSERT_NE(sessions.list.back(), nullptr);
        int32_t ch = -1;
        ASSERT_EQ(mocap_solver_add_character(solver.s, sessions.list.back(), &ch), MOCAP_OK);
        EXPECT_EQ(ch, c);
    }
    ASSERT_EQ(mocap_solver_start(solver.s), MOCAP_OK) << mocap_last_error();
    for (auto *s : sessions.list) ASSERT_EQ(mocap_session_start(s), MOCAP_OK);
    std::vector<std::vector<mocap_pose>> poses;
    ASSERT_TRUE(drain_to_end(solver.s, 3, poses, 120));
    mocap_solver_stats total;
    ASSERT_EQ(mocap_solver_get_stats(solver.s, -1, &total), MOCAP_OK);
    EXPECT_GT(total.batched_calls, 100u);
    EXPECT_EQ(total.max_batch, 3u);
    EXPECT_LT(total.ticks, total.frames_solved);  // fewer calls than frames: batching
    for (int c = 0; c < 3; ++c) {
        mocap_session_stats ss;
        mocap_session_get_stats(sessions.list[c], &ss);
        mocap_solver_stats st;
        mocap_solver_get_stats(solver.s, c, &st);
        EXPECT_EQ(ss.frames_dropped, 0u);
        EXPECT_EQ(st.frames_solved, poses[c].size());
        EXPECT_EQ(st.frames_solved + st.frames_uncalibrated, ss.frames_emitted) << c;
        check_poses(poses[c], info, c);
    }
    // Longer motions give more poses: the characters did not get mixed up.
    EXPECT_LT(poses[0].size(), poses[1].size());
    EXPECT_LT(poses[1].size(), poses[2].size());
    report_timing(solver.s, "3 characters");
}

#if !defined(_WIN32) // Windows: a pseudo-terminal stands in for the serial port
// A live character on a pseudo-terminal is unplugged; two paced replays keep producing poses at
// the frame rate, without waiting for it.
TEST_F(SolverOnShippedModel, UnpluggedCharacterDoesNotStallTheOthers)
{
    mocap_solver_config sc;
    mocap_solver_config_defaults(&sc);
    sc.require_calibration = 0;  // live + paced replays: no time for calibration preludes here
    Sessions sessions;           // declared first: the solver closes before its sessions
    Solver solver;
    ASSERT_EQ(mocap_solver_open(model.m, &sc, &solver.s), MOCAP_OK);

    std::string dir = test_temp_dir();
    FakeReceiver receiver(dir + "/ttyLive");
    mocap_session_config live;
    mocap_config_defaults(&live);
    live.source_kind = MOCAP_SOURCE_SERIAL;
    snprintf(live.path, sizeof live.path, "%s", receiver.link.c_str());
    mocap_session *ls = nullptr;
    ASSERT_EQ(mocap_session_open(&live, &ls), MOCAP_OK) << mocap_last_error();
    sessions.list.push_back(ls);
    int32_t ch = -1;
    ASSERT_EQ(mocap_solver_add_character(solver.s, ls, &ch), MOCAP_OK);
    for (int c = 1; c <= 2; ++c) {
        std::string cap = dir + "/paced" + std::to_string(c) + ".cap";
        synth_config cfg = short_capture(50 + c, 10.0, "walk", cap);
        sessions.list.push_back(open_replay(cap, cfg, 1));
        ASSERT_NE(sessions.list.back(), nullptr);
        ASSERT_EQ(mocap_solver_add_character(solver.s, sessions.list.back(), &ch), MOCAP_OK);
    }
    ASSERT_EQ(mocap_solver_start(solver.s), MOCAP_OK);
    for (auto *s : sessions.list) ASSERT_EQ(mocap_session_start(s), MOCAP_OK);

    synth_config wcfg;
    synth_config_defaults(&wcfg);
    wcfg.seed = 55;
    wcfg.motion_s = 20.0;
    auto packets = generate(wcfg);
    std::atomic<bool> stop{false}, plugged{true};
    std::mutex master_lock;
    std::thread writer([&] {
        auto start = Clock::now();
        for (size_t i = 0; i < packets.size() && !stop; ++i) {
            std::this_thread::sleep_until(start + std::chrono::duration<double>(packets[i].info.t));
            std::lock_guard<std::mutex> g(master_lock);
            if (plugged) receiver.write_all(packets[i].bytes.data(), packets[i].bytes.size());
        }
    });

    std::vector<uint64_t> counts(3, 0);
    std::vector<mocap_pose> buf(64), last(3);
    auto pump = [&](double seconds) {
        auto t0 = Clock::now();
        while (seconds_since(t0) < seconds) {
            for (int c = 0; c < 3; ++c) {
                uint32_t n = 0;
                mocap_solver_drain(solver.s, c, buf.data(), (uint32_t)buf.size(), &n);
                for (uint32_t i = 0; i < n; ++i) {
                    ASSERT_EQ(buf[i].sequence, counts[c] + i);
                    ASSERT_TRUE(std::isfinite(buf[i].joint_rotations[0][0]));
                }
                counts[c] += n;
                if (n > 0) last[c] = buf[n - 1];
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
    };
    // Progress is awaited, not timed: a loaded machine (CI, a training job) may start slowly.
    auto pump_until = [&](double timeout_s, auto done) {
        auto t0 = Clock::now();
        while (!done() && seconds_since(t0) < timeout_s) pump(0.05);
        return done();
    };
    ASSERT_TRUE(pump_until(15.0, [&] { return counts[0] > 40 && counts[1] > 40 && counts[2] > 40; }))
        << "every character produces poses before the unplug: " << counts[0] << " " << counts[1] << " "
        << counts[2];
    {
        std::lock_guard<std::mutex> g(master_lock);
        plugged = false;
        receiver.unplug();
    }
    pump(0.5);  // the unplug is noticed; the live character's last held frames drain
    std::vector<uint64_t> mid = counts;
    // The replays go on (two seconds of their poses) ...
    EXPECT_TRUE(pump_until(15.0, [&] { return counts[1] >= mid[1] + 120 && counts[2] >= mid[2] + 120; }))
        << counts[1] - mid[1] << " " << counts[2] - mid[2];
    // ... without falling behind their sessions: a solver that waited for the unplugged
    // character, even for a bounded time per frame, would leave their frames piling up.
    for (int c = 1; c <= 2; ++c) {
        pump(0.1);
        mocap_session_stats rs;
        mocap_session_get_stats(sessions.list[c], &rs);
        EXPECT_LE((double)rs.frames_emitted - (double)counts[c], 30.0)
            << "replay " << c << ": " << rs.frames_emitted << " frames, " << counts[c] << " poses";
    }
    stop = true;
    writer.join();
    // ... while the unplugged character produced nothing more.
    EXPECT_EQ(counts[0], mid[0]);
    mocap_session_stats ss;
    mocap_session_get_stats(ls, &ss);
    EXPECT_EQ(ss.connection_state, MOCAP_CONNECTION_DISCONNECTED);
    mocap_solver_stats st;
    mocap_solver_get_stats(solver.s, -1, &st);
    EXPECT_EQ(st.poses_dropped, 0u);
    // Live poses are stamped on the monotonic clock: receive <= frame <= pose <= now.
    EXPECT_LE(last[0].newest_receive_ns, last[0].frame_emitted_ns);
    EXPECT_LE(last[0].frame_emitted_ns, last[0].pose_emitted_ns);
    EXPECT_LE(last[0].pose_emitted_ns, mocap_monotonic_ns());
    EXPECT_LT(last[0].pose_emitted_ns - last[0].frame_emitted_ns, 200000000LL);  // < 200 ms
}
#endif

// An inference that fails (here a model that cannot run inputs above 50 m/s^2; on a GPU, out of
// memory) holds the previous pose and state, and the stats say how often and why: the solver
// thread has no caller to return the error to.
TEST(Solver, InferenceFailuresAreCountedWithTheirCause)
{
    REQUIRE_ORT();
    std::string dir = test_temp_dir();
    ASSERT_TRUE(write_onnx_fixtures(dir));
    Model model;
    ASSERT_EQ(open_model(dir + "/fails_on_impact.onnx", &model.m), MOCAP_OK) << mocap_last_error();
    std::string cap = dir + "/rate.cap";
    synth_config cfg = short_capture(61, 1.0, "walk", cap);
    Sessions sessions;
    sessions.list.push_back(open_replay(cap, cfg));  // never started: only its rate is used
    Solver solver;
    ASSERT_EQ(mocap_solver_open(model.m, nullptr, &solver.s), MOCAP_OK) << mocap_last_error();
    int32_t ch = -1;
    ASSERT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_OK);
    ASSERT_EQ(solver_prepare(solver.s), MOCAP_OK) << mocap_last_error();

    mocap_frame f = calibrated_six_frame();
    std::vector<mocap_frame> frames(5, f);
    frames[2].sensors[3].bone_acceleration[1] = 80.0f;  // an impact the model cannot run
    frames[3].sensors[0].bone_acceleration[0] = -60.0f;
    mocap_solver_stats st;
    ASSERT_EQ(mocap_solver_get_stats(solver.s, -1, &st), MOCAP_OK);
    EXPECT_EQ(st.run_failures, 0u);
    EXPECT_EQ(st.last_run_status, MOCAP_OK);
    EXPECT_STREQ(st.last_run_error, "");
    for (size_t i = 0; i < frames.size(); ++i) {
        frames[i].sequence = i;
        frames[i].time_s = 1.0 + i / 60.0;
        const mocap_frame *fp = &frames[i];
        solver_solve(solver.s, &ch, &fp, nullptr, 1);
    }
    ASSERT_EQ(mocap_solver_get_stats(solver.s, 0, &st), MOCAP_OK);
    EXPECT_EQ(st.frames_solved, 5u);
    EXPECT_EQ(st.run_failures, 2u);
    EXPECT_NE(st.last_run_status, MOCAP_OK);
    // The text names the model and carries ONNX Runtime's reason.
    EXPECT_NE(std::string(st.first_run_error).find("fails_on_impact.onnx"), std::string::npos)
        << st.first_run_error;
    EXPECT_NE(std::string(st.last_run_error).find("Reshape"), std::string::npos) << st.last_run_error;
    // Every frame still gave a pose: the failed ones hold the previous one, flagged incomplete.
    std::vector<mocap_pose> poses(8);
    uint32_t n = 0;
    ASSERT_EQ(mocap_solver_drain(solver.s, 0, poses.data(), (uint32_t)poses.size(), &n), MOCAP_OK);
    ASSERT_EQ(n, 5u);
    for (int i : {2, 3}) {
        EXPECT_TRUE(poses[i].flags & MOCAP_POSE_INCOMPLETE) << i;
        EXPECT_EQ(0, memcmp(poses[i].joint_rotations, poses[1].joint_rotations, sizeof poses[1].joint_rotations));
    }
    EXPECT_FALSE(poses[4].flags & MOCAP_POSE_INCOMPLETE);
}

// The performer's height scales one character's root velocity by (height / training height)^(e-1)
// from the model's metadata (stride_scaled: 1.70 m, e = 0.6) and its root integrates the scaled
// velocity; the other character, and the same one set back to 0, keep the model's own.
TEST(Solver, PerformerHeightScalesTheRootVelocityByTheModelsStrideLaw)
{
    REQUIRE_ORT();
    std::string dir = test_temp_dir();
    ASSERT_TRUE(write_onnx_fixtures(dir));
    Model model;
    ASSERT_EQ(open_model(dir + "/stride_scaled.onnx", &model.m), MOCAP_OK) << mocap_last_error();
    float training_height = 0, exponent = 0;
    ASSERT_EQ(mocap_model_get_stride_scaling(model.m, &training_height, &exponent), MOCAP_OK);
    EXPECT_FLOAT_EQ(training_height, 1.70f);
    EXPECT_FLOAT_EQ(exponent, 0.6f);

    std::string cap = dir + "/height.cap";
    synth_config cfg = short_capture(62, 1.0, "walk", cap);
    Sessions sessions;  // never started: only their rates are used
    sessions.list.push_back(open_replay(cap, cfg));
    sessions.list.push_back(open_replay(cap, cfg));
    mocap_solver_config config = raw_output_config();
    config.drift_correction = 0;  // the root is then the pure integral of the velocity
    Solver solver;
    ASSERT_EQ(mocap_solver_open(model.m, &config, &solver.s), MOCAP_OK) << mocap_last_error();
    int32_t ids[2] = {-1, -1};
    for (int c = 0; c < 2; ++c) {
        ASSERT_EQ(mocap_solver_add_character(solver.s, sessions.list[c], &ids[c]), MOCAP_OK);
    }
    ASSERT_EQ(mocap_solver_set_character_height(solver.s, ids[1], 1.87f), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(solver_prepare(solver.s), MOCAP_OK) << mocap_last_error();
    const double gain = std::pow(1.87 / 1.70, 0.6 - 1.0);

    mocap_frame f = calibrated_six_frame();
    const int frames = 6;
    for (int i = 0; i < frames; ++i) {
        if (i == 4) {
            ASSERT_EQ(mocap_solver_set_character_height(solver.s, ids[1], 0.0f), MOCAP_OK);
        }
        f.sequence = (uint64_t)i;
        f.time_s = 1.0 + i / 60.0;
        f.sensors[0].bone_acceleration[0] = 0.2f * (float)(i + 1);
        const mocap_frame *both[2] = {&f, &f};
        ASSERT_EQ(solver_solve(solver.s, ids, both, nullptr, 2), MOCAP_OK) << mocap_last_error();
    }
    std::vector<mocap_pose> poses[2];
    for (int c = 0; c < 2; ++c) {
        poses[c].resize(16);
        uint32_t n = 0;
        ASSERT_EQ(mocap_solver_drain(solver.s, ids[c], poses[c].data(), 16, &n), MOCAP_OK);
        ASSERT_EQ(n, (uint32_t)frames);
    }
    for (int i = 0; i < frames; ++i) {
        SCOPED_TRACE(i);
        const double g = i < 4 ? gain : 1.0;
        const mocap_pose &own = poses[0][i], &tall = poses[1][i];
        ASSERT_GT(std::fabs(own.root_velocity[0]), 0.05f);  // something to scale
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(tall.root_velocity[k], g * own.root_velocity[k], 1e-5 * (1 + std::fabs(own.root_velocity[k])));
            if (i == 0) continue;
            const double step_own = own.root_position[k] - poses[0][i - 1].root_position[k];
            const double step_tall = tall.root_position[k] - poses[1][i - 1].root_position[k];
            EXPECT_NEAR(step_tall, g * step_own, 1e-5 * (1 + std::fabs(step_own)));
        }
        // The pose itself is the model's either way.
        EXPECT_EQ(0, memcmp(own.joint_rotations, tall.joint_rotations, sizeof own.joint_rotations));
    }
}

// Heights outside 1..2.5 m, unknown characters and models without stride scaling are refused
// naming the reason; 0 (the model's own) is always accepted; half the metadata, or an exponent
// outside 0..2, is a malformed model.
TEST(Solver, HeightIsRefusedOutsideItsRangeAndWithoutStrideScaling)
{
    REQUIRE_ORT();
    std::string dir = test_temp_dir();
    ASSERT_TRUE(write_onnx_fixtures(dir));
    std::string cap = dir + "/height.cap";
    synth_config cfg = short_capture(63, 1.0, "walk", cap);
    Sessions sessions;
    sessions.list.push_back(open_replay(cap, cfg));
    sessions.list.push_back(open_replay(cap, cfg));

    Model plain;
    ASSERT_EQ(open_model(dir + "/valid.onnx", &plain.m), MOCAP_OK) << mocap_last_error();
    float h = -1, e = -1;
    EXPECT_EQ(mocap_model_get_stride_scaling(plain.m, &h, &e), MOCAP_ERR_UNSUPPORTED);
    Solver without;
    ASSERT_EQ(mocap_solver_open(plain.m, nullptr, &without.s), MOCAP_OK);
    int32_t ch = -1;
    ASSERT_EQ(mocap_solver_add_character(without.s, sessions.list[0], &ch), MOCAP_OK);
    EXPECT_EQ(mocap_solver_set_character_height(without.s, ch, 1.8f), MOCAP_ERR_UNSUPPORTED);
    std::string err = mocap_last_error();
    EXPECT_NE(err.find("mocap.training_height"), std::string::npos) << err;
    EXPECT_NE(err.find("fixture"), std::string::npos) << err;
    EXPECT_EQ(mocap_solver_set_character_height(without.s, ch, 0.0f), MOCAP_OK);

    Model scaled;
    ASSERT_EQ(open_model(dir + "/stride_scaled.onnx", &scaled.m), MOCAP_OK) << mocap_last_error();
    Solver with;
    ASSERT_EQ(mocap_solver_open(scaled.m, nullptr, &with.s), MOCAP_OK);
    ASSERT_EQ(mocap_solver_add_character(with.s, sessions.list[1], &ch), MOCAP_OK);
    for (float bad : {0.5f, 0.99f, 2.6f, -1.8f, NAN, INFINITY}) {
        SCOPED_TRACE(bad);
        EXPECT_EQ(mocap_solver_set_character_height(with.s, ch, bad), MOCAP_ERR_INVALID_ARGUMENT);
        EXPECT_NE(std::string(mocap_last_error()).find("1..2.5 m"), std::string::npos) << mocap_last_error();
    }
    EXPECT_EQ(mocap_solver_set_character_height(with.s, ch, 1.0f), MOCAP_OK);
    EXPECT_EQ(mocap_solver_set_character_height(with.s, ch, 2.5f), MOCAP_OK);
    EXPECT_EQ(mocap_solver_set_character_height(with.s, ch + 1, 1.8f), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(mocap_solver_set_character_height(nullptr, 0, 1.8f), MOCAP_ERR_INVALID_ARGUMENT);

    for (const char *file : {"stride_height_only.onnx", "stride_bad_exponent.onnx"}) {
        SCOPED_TRACE(file);
        mocap_model *m = nullptr;
        EXPECT_EQ(open_model(dir + "/" + file, &m), MOCAP_ERR_FORMAT);
        EXPECT_EQ(m, nullptr);
        err = mocap_last_error();
        EXPECT_NE(err.find("mocap.stride_exponent"), std::string::npos) << err;
        EXPECT_NE(err.find(file), std::string::npos) << err;
    }
}

// NaN/Inf in a frame: the frame is not fed to the model, the previous pose is held and flagged,
// and the recurrent state never sees it.
TEST(Solver, NonFiniteInputFramesAreNotFed)
{
    mocap_frame f = calibrated_six_frame();
    for (int s = 0; s < 6; ++s) {
        double q[4], axis[3] = {0.3, 1.0, -0.2};
        quat_from_axis_angle(q, axis, 0.2 * (s + 1));
        quat_normalize(q);
        for (int k = 0; k < 4; ++k) f.sensors[s].bone_orientation[k] = (float)q[k];
        for (int k = 0; k < 3; ++k) f.sensors[s].bone_acceleration[k] = 0.5f * (k + 1) - s;
    }
    const int8_t slots[6] = {0, 1, 2, 3, 4, 5};
    float ori[54], acc[18];
    ASSERT_EQ(solver_frame_input(&f, slots, 6, 0, ori, acc, nullptr), 0);
    for (int s = 0; s < 6; ++s) {
        double q[4], m[9];
        for (int k = 0; k < 4; ++k) q[k] = f.sensors[s].bone_orientation[k];
        quat_to_mat3(m, q);
        for (int k = 0; k < 9; ++k) EXPECT_NEAR(ori[s * 9 + k], m[k], 1e-6);
        for (int k = 0; k < 3; ++k) EXPECT_EQ(acc[s * 3 + k], f.sensors[s].bone_acceleration[k]);
    }
    mocap_frame bad = f;
    bad.sensors[4].bone_orientation[2] = NAN;
    EXPECT_EQ(solver_frame_input(&bad, slots, 6, 0, ori, acc, nullptr), -1);
    bad = f;
    bad.sensors[0].bone_acceleration[1] = INFINITY;
    EXPECT_EQ(solver_frame_input(&bad, slots, 6, 0, ori, acc, nullptr), -1);
    bad = f;
    memset(bad.sensors[5].bone_orientation, 0, sizeof bad.sensors[5].bone_orientation);
    EXPECT_EQ(solver_frame_input(&bad, slots, 6, 0, ori, acc, nullptr), -1);

    // Through the solver's tick (no thread: solver_prepare + solver_solve).
    REQUIRE_ORT();
    Model model;
    ASSERT_EQ(open_model(kShippedModel, &model.m), MOCAP_OK) << mocap_last_error();
    Sessions sessions;
    Solver solver;
    int32_t ch = -1;
    ASSERT_NO_FATAL_FAILURE(prepare_tick_solver(model.m, sessions, solver, &ch, "nan.cap", 60));

    std::vector<mocap_frame> frames(6, f);
    frames[2].sensors[3].bone_acceleration[0] = NAN;
    frames[3].sensors[1].bone_orientation[0] = INFINITY;
    frames[5] = uncalibrated(frames[5]);  // skipped
    for (size_t i = 0; i < frames.size(); ++i) {
        frames[i].sequence = i;
        frames[i].time_s = 10.0 + i / 60.0;
        const mocap_frame *fp = &frames[i];
        ASSERT_EQ(solver_solve(solver.s, &ch, &fp, nullptr, 1), MOCAP_OK) << mocap_last_error();
    }
    std::vector<mocap_pose> poses(16);
    uint32_t n = 0;
    ASSERT_EQ(mocap_solver_drain(solver.s, 0, poses.data(), (uint32_t)poses.size(), &n), MOCAP_OK);
    ASSERT_EQ(n, 5u);
    mocap_solver_stats st;
    mocap_solver_get_stats(solver.s, 0, &st);
    EXPECT_EQ(st.frames_nonfinite, 2u);
    EXPECT_EQ(st.frames_uncalibrated, 1u);
    EXPECT_EQ(st.frames_solved, 3u);
    for (uint32_t i = 0; i < n; ++i) {
        EXPECT_EQ(poses[i].sequence, i);
        EXPECT_EQ(poses[i].frame_sequence, i);
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
            for (int k = 0; k < 4; ++k) ASSERT_TRUE(std::isfinite(poses[i].joint_rotations[j][k]));
        for (int k = 0; k < 3; ++k) ASSERT_TRUE(std::isfinite(poses[i].root_position[k]));
    }
    // Frames 2 and 3 hold pose 1 (flagged incomplete), frame 4 is solved again.
    for (int i : {2, 3}) {
        EXPECT_TRUE(poses[i].flags & MOCAP_POSE_INCOMPLETE) << i;
        EXPECT_EQ(0, memcmp(poses[i].joint_rotations, poses[1].joint_rotations, sizeof poses[1].joint_rotations));
        EXPECT_EQ(0, memcmp(poses[i].root_position, poses[1].root_position, sizeof poses[1].root_position));
    }
    EXPECT_FALSE(poses[4].flags & MOCAP_POSE_INCOMPLETE);

    // The state after the NaN frames equals the state of a clean run of the 3 good frames: a
    // second character-free check through a fresh solver fed only frames 0, 1, 4.
    Solver clean;
    ASSERT_EQ(mocap_solver_open(model.m, nullptr, &clean.s), MOCAP_OK);
    ASSERT_EQ(mocap_solver_add_character(clean.s, sessions.list[0], &ch), MOCAP_OK);
    ASSERT_EQ(solver_prepare(clean.s), MOCAP_OK);
    for (int i : {0, 1, 4}) {
        const mocap_frame *fp = &frames[i];
        ASSERT_EQ(solver_solve(clean.s, &ch, &fp, nullptr, 1), MOCAP_OK);
    }
    std::vector<mocap_pose> ref(4);
    ASSERT_EQ(mocap_solver_drain(clean.s, 0, ref.data(), (uint32_t)ref.size(), &n), MOCAP_OK);
    ASSERT_EQ(n, 3u);
    EXPECT_EQ(0, memcmp(ref[2].joint_rotations, poses[4].joint_rotations, sizeof ref[2].joint_rotations));
    EXPECT_EQ(0, memcmp(ref[2].foot_contact, poses[4].foot_contact, sizeof ref[2].foot_contact));
}

TEST_F(SolverOnShippedModel, ConfigIsValidated)
{
    mocap_solver_config c;
    mocap_solver_config_defaults(&c);
    EXPECT_EQ(c.struct_size, sizeof c);
    EXPECT_FLOAT_EQ(c.contact_threshold, 0.5f);
    EXPECT_EQ(c.drift_correction, 1);
    EXPECT_EQ(c.require_calibration, 1);
    EXPECT_FLOAT_EQ(c.smoothing_min_cutoff_hz, 2.0f);
    EXPECT_FLOAT_EQ(c.smoothing_beta, 12.0f);
    mocap_solver *s = nullptr;
    c.contact_threshold = 1.5f;
    EXPECT_EQ(mocap_solver_open(model.m, &c, &s), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("contact_threshold"), std::string::npos);
    for (float bad : {-1.0f, NAN, INFINITY}) {
        mocap_solver_config_defaults(&c);
        c.smoothing_min_cutoff_hz = bad;
        EXPECT_EQ(mocap_solver_open(model.m, &c, &s), MOCAP_ERR_INVALID_ARGUMENT);
        EXPECT_NE(std::string(mocap_last_error()).find("smoothing_min_cutoff_hz"), std::string::npos);
        mocap_solver_config_defaults(&c);
        c.smoothing_beta = bad;
        EXPECT_EQ(mocap_solver_open(model.m, &c, &s), MOCAP_ERR_INVALID_ARGUMENT);
        EXPECT_NE(std::string(mocap_last_error()).find("smoothing_beta"), std::string::npos);
    }
    mocap_solver_config_defaults(&c);
    c.struct_size = 8;
    EXPECT_EQ(mocap_solver_open(model.m, &c, &s), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(s, nullptr);
    EXPECT_EQ(mocap_solver_open(nullptr, nullptr, &s), MOCAP_ERR_INVALID_ARGUMENT);
    mocap_solver_close(nullptr);
    mocap_model_close(nullptr);
}

// Bindings verify their mirrors against mocap_struct_layout: the solver's structs are in it.
TEST(Solver, StructLayoutTableHasTheSolverStructs)
{
    uint32_t n = 0;
    const mocap_field_layout *rows = mocap_struct_layout(&n);
    auto find = [&](const char *s, const char *f) -> const mocap_field_layout * {
        for (uint32_t i = 0; i < n; ++i)
            if (std::string(rows[i].struct_name) == s && std::string(rows[i].field_name) == f) return &rows[i];
        return nullptr;
    };
    struct Row {
        const char *s, *f;
        size_t offset, size;
    } expected[] = {
        {"mocap_pose", "", 0, sizeof(mocap_pose)},
        {"mocap_pose", "joint_rotations", offsetof(mocap_pose, joint_rotations), 24 * 4 * 4},
        {"mocap_pose", "pose_emitted_ns", offsetof(mocap_pose, pose_emitted_ns), 8},
        {"mocap_model_info", "", 0, sizeof(mocap_model_info)},
        {"mocap_model_info", "joint_names", offsetof(mocap_model_info, joint_names), 24 * 32},
        {"mocap_model_options", "onnxruntime_path", offsetof(mocap_model_options, onnxruntime_path), MOCAP_PATH_MAX},
        {"mocap_solver_config", "require_calibration", offsetof(mocap_solver_config, require_calibration), 4},
        {"mocap_solver_config", "smoothing_min_cutoff_hz", offsetof(mocap_solver_config, smoothing_min_cutoff_hz), 4},
        {"mocap_solver_config", "smoothing_beta", offsetof(mocap_solver_config, smoothing_beta), 4},
        {"mocap_solver_config", "", 0, sizeof(mocap_solver_config)},
        {"mocap_solver_stats", "", 0, sizeof(mocap_solver_stats)},
        {"mocap_solver_stats", "run_failures", offsetof(mocap_solver_stats, run_failures), 8},
        {"mocap_solver_stats", "last_run_error", offsetof(mocap_solver_stats, last_run_error), 256},
    };
    for (const auto &e : expected) {
        const mocap_field_layout *r = find(e.s, e.f);
        ASSERT_NE(r, nullptr) << e.s << "." << e.f;
        EXPECT_EQ(r->offset, e.offset) << e.s << "." << e.f;
        EXPECT_EQ(r->size, e.size) << e.s << "." << e.f;
    }
    EXPECT_EQ(mocap_api_version(), 6);        // 6: sensor sets (counts, segments, states)
    EXPECT_EQ(mocap_api_version_minor(), 6);  // 6.1: performer height; 6.2: smoothing that waits;
                                              // 6.3: foot pinning; 6.4: model contract 3;
                                              // 6.5: pose limits; 6.6: chest following
    // The sensor-set fields a binding mirrors are in the table too.
    const mocap_field_layout *count = find("mocap_frame", "sensor_count");
    ASSERT_NE(count, nullptr);
    EXPECT_EQ(count->offset, offsetof(mocap_frame, sensor_count));
    const mocap_field_layout *sensors = find("mocap_frame", "sensors");
    ASSERT_NE(sensors, nullptr);
    EXPECT_EQ(sensors->size, MOCAP_MAX_SENSORS * sizeof(mocap_sensor_frame));
    ASSERT_NE(find("mocap_model_info", "sensor_required_mask"), nullptr);
    ASSERT_NE(find("mocap_session_config", "optional_mask"), nullptr);
}

// A consumer that stops polling for longer than the pose ring holds gets the newest pose from
// its next poll, not the newest of the 1024 the ring kept; it is not handed out again.
TEST_F(SolverOnShippedModel, PollAfterALongPauseReturnsTheNewestPose)
{
    std::string cap = test_temp_path("long_pause.cap");
    synth_config cfg = short_capture(43, 60.0, "mixed", cap);  // ~1,350 poses (22 s of motion)
    Sessions sessions;
    sessions.list.push_back(open_replay(cap, cfg, 1));
    ASSERT_NE(sessions.list[0], nullptr);
    // Realtime at 10x: live-like (full rings drop instead of waiting), about 3 s of wall time.
    mocap_session_close(sessions.list[0]);
    mocap_session_config c;
    mocap_config_defaults(&c);
    c.source_kind = MOCAP_SOURCE_REPLAY;
    c.replay_realtime = 1;
    c.replay_speed = 10.0f;
    snprintf(c.path, sizeof c.path, "%s", cap.c_str());
    ASSERT_EQ(mocap_session_open(&c, &sessions.list[0]), MOCAP_OK) << mocap_last_error();
    const double t0 = synth_session_time(&cfg, 0.0);
    ASSERT_EQ(mocap_calibration_schedule(sessions.list[0], MOCAP_CALIBRATION_HEADING, t0 + 0.5,
                                         (float)(cfg.heading_s - 1.0)), MOCAP_OK);
    ASSERT_EQ(mocap_calibration_schedule(sessions.list[0], MOCAP_CALIBRATION_TPOSE,
                                         t0 + cfg.heading_s + cfg.strap_s + 0.5,
                                         (float)(cfg.tpose_s - 1.0)), MOCAP_OK);
    Solver solver;
    int32_t ch = -1;
    ASSERT_EQ(mocap_solver_open(model.m, nullptr, &solver.s), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_OK);
    ASSERT_EQ(mocap_solver_start(solver.s), MOCAP_OK);
    ASSERT_EQ(mocap_session_start(sessions.list[0]), MOCAP_OK);

    // The pause: nobody polls until the replay ended and the solver has nothing left to do.
    mocap_session_stats ss{};
    mocap_solver_stats st{};
    uint64_t last_done = ~0ull;
    const auto start = Clock::now();
    for (;;) {
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        ASSERT_EQ(mocap_session_get_stats(sessions.list[0], &ss), MOCAP_OK);
        ASSERT_EQ(mocap_solver_get_stats(solver.s, 0, &st), MOCAP_OK);
        const uint64_t done = st.frames_solved + st.frames_uncalibrated;
        if (ss.connection_state == MOCAP_CONNECTION_ENDED && done == last_done) break;
        last_done = done;
        ASSERT_LT(seconds_since(start), 120.0);
    }
    ASSERT_GT(st.poses_dropped, 0u) << "the ring never filled: the test shows nothing";

    mocap_pose pose{};
    ASSERT_EQ(mocap_solver_poll_latest(solver.s, 0, &pose), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(pose.sequence + 1, st.frames_solved) << "not the newest pose";
    EXPECT_GT(pose.sequence, 1024u);
    EXPECT_EQ(mocap_solver_poll_latest(solver.s, 0, &pose), MOCAP_ERR_END_OF_STREAM);
    uint32_t n = 99;
    EXPECT_EQ(mocap_solver_drain(solver.s, 0, &pose, 1, &n), MOCAP_ERR_END_OF_STREAM);
    EXPECT_EQ(n, 0u);
}

// ---------------------------------------------------------------------------------------------
// Sensor sets: a session carrying more sensors than the six, and a contract-2 model with an
// optional chest sensor.

namespace {

// A replay whose session carries the first `count` sensors of the default set, plus the chest
// on node 6 when with_chest; calibration scheduled as open_replay does.
mocap_session *open_replay_sensors(const std::string &path, const synth_config &cfg, uint32_t count,
                                   bool with_chest, uint32_t optional_mask = 0)
{
    mocap_session_config c = replay_config(path);
    c.sensor_count = count;
    if (with_chest) {
        c.sensor_segments[c.sensor_count] = MOCAP_SEGMENT_CHEST;
        c.node_ids[c.sensor_count] = 6;
        c.sensor_count++;
    }
    c.optional_mask = optional_mask;
    return open_with_prelude(c, cfg);
}

struct ChestTap {
    std::map<uint64_t, std::array<float, 4>> chest;  // frame sequence -> chest bone orientation
    std::map<uint64_t, std::vector<float>> mask;
    int sensors = 0;
};

void chest_tap(void *user, int32_t, const mocap_frame *frame, const float *, const float *,
               const float *mask, int sensor_count)
{
    ChestTap *t = static_cast<ChestTap *>(user);
    t->sensors = sensor_count;
    for (uint32_t i = 0; i < frame->sensor_count; ++i)
        if (frame->sensors[i].segment == MOCAP_SEGMENT_CHEST)
            std::copy(frame->sensors[i].bone_orientation, frame->sensors[i].bone_orientation + 4,
                      t->chest[frame->sequence].begin());
    if (mask) t->mask[frame->sequence].assign(mask, mask + sensor_count);
}

// Runs one session through a fresh solver of `model` to the end; smoothing off, so the poses are
// the model's own outputs (turned towards a chest sensor by chest_follow). tap (may be null) sees
// every model input.
std::vector<mocap_pose> solve_to_end(mocap_model *model, mocap_session *session, solver_input_tap tap,
                                     void *tap_user, float chest_follow = 0.0f)
{
    const mocap_solver_config sc = raw_output_config();
    Solver solver;
    int32_t ch = -1;
    if (mocap_solver_open(model, &sc, &solver.s) != MOCAP_OK ||
        mocap_solver_set_chest_follow(solver.s, chest_follow) != MOCAP_OK ||
        mocap_solver_add_character(solver.s, session, &ch) != MOCAP_OK) {
        ADD_FAILURE() << mocap_last_error();
        return {};
    }
    if (tap) solver_set_input_tap(solver.s, tap, tap_user);
    EXPECT_EQ(mocap_solver_start(solver.s), MOCAP_OK);
    EXPECT_EQ(mocap_session_start(session), MOCAP_OK);
    std::vector<std::vector<mocap_pose>> poses;
    EXPECT_TRUE(drain_to_end(solver.s, 1, poses, 60));
    return poses.empty() ? std::vector<mocap_pose>{} : poses[0];
}

}  // namespace

// The chest reaches a contract-2 model: the fixture copies it into joint 9 and reports the mask
// and the chest's acceleration in root_velocity (make_onnx_fixtures.py, v2_chest).
TEST(SolverSensorSets, ContractTwoModelReceivesTheChestAndItsMask)
{
    REQUIRE_ORT();
    std::string dir = test_temp_dir();
    ASSERT_TRUE(write_onnx_fixtures(dir));
    Model model;
    ASSERT_EQ(open_model(dir + "/v2_chest.onnx", &model.m), MOCAP_OK) << mocap_last_error();
    mocap_model_info info;
    ASSERT_EQ(mocap_model_get_info(model.m, &info), MOCAP_OK);
    EXPECT_EQ(info.contract_version, 2);
    EXPECT_EQ(info.sensor_count, 7u);
    EXPECT_EQ(info.sensor_segments[6], MOCAP_SEGMENT_CHEST);
    EXPECT_EQ(info.sensor_required_mask, 0x3fu);

    std::string cap = dir + "/seven.cap";
    synth_config cfg = short_capture(71, 3.0, "turn", cap, true);
    Sessions sessions;
    sessions.list.push_back(open_replay_sensors(cap, cfg, 6, true));
    ASSERT_NE(sessions.list[0], nullptr);
    ChestTap tap;
    std::vector<mocap_pose> poses = solve_to_end(model.m, sessions.list[0], chest_tap, &tap);
    ASSERT_GT(poses.size(), (size_t)(cfg.motion_s * 60.0));
    EXPECT_EQ(tap.sensors, 7);
    size_t checked = 0;
    for (const mocap_pose &p : poses) {
        ASSERT_FLOAT_EQ(p.root_velocity[0], 7.0f) << p.frame_sequence;  // every sensor present
        ASSERT_FLOAT_EQ(p.root_velocity[1], 1.0f) << p.frame_sequence;  // the chest's mask
        auto it = tap.chest.find(p.frame_sequence);
        ASSERT_NE(it, tap.chest.end());
        // Joint 9 is the chest's calibrated orientation, as the frame carried it.
        double dot = 0;
        for (int k = 0; k < 4; ++k) dot += (double)p.joint_rotations[9][k] * it->second[k];
        ASSERT_GT(std::fabs(dot), 1.0 - 1e-5) << p.frame_sequence;
        ++checked;
    }
    EXPECT_EQ(checked, poses.size());
    // The chest turns with the body: the check above is not the identity's.
    double min_w = 1.0;
    for (const auto &kv : tap.chest) min_w = std::min(min_w, std::fabs((double)kv.second[0]));
    EXPECT_LT(min_w, 0.99);
}

// The same model on a session without a chest: the optional sensor is fed as missing (mask 0,
// zero inputs), and every pose still comes.
TEST(SolverSensorSets, ContractTwoModelRunsWithoutItsOptionalSensor)
{
    REQUIRE_ORT();
    std::string dir = test_temp_dir();
    ASSERT_TRUE(write_onnx_fixtures(dir));
    Model model;
    ASSERT_EQ(open_model(dir + "/v2_chest.onnx", &model.m), MOCAP_OK) << mocap_last_error();
    std::string cap = dir + "/seven.cap";
    synth_config cfg = short_capture(72, 2.0, "mixed", cap, true);
    Sessions sessions;
    sessions.list.push_back(open_replay_sensors(cap, cfg, 6, false));
    ASSERT_NE(sessions.list[0], nullptr);
    ChestTap tap;
    std::vector<mocap_pose> poses = solve_to_end(model.m, sessions.list[0], chest_tap, &tap);
    ASSERT_GT(poses.size(), (size_t)(cfg.motion_s * 60.0));
    for (const mocap_pose &p : poses) {
        ASSERT_FLOAT_EQ(p.root_velocity[0], 6.0f) << p.frame_sequence;
        ASSERT_FLOAT_EQ(p.root_velocity[1], 0.0f) << p.frame_sequence;
        ASSERT_FLOAT_EQ(p.root_velocity[2], 0.0f) << p.frame_sequence;  // zero chest input
        ASSERT_NEAR(std::fabs(p.joint_rotations[9][0]), 1.0f, 1e-6);   // identity for "missing"
        ASSERT_TRUE(p.flags & MOCAP_POSE_INCOMPLETE);  // a model sensor is missing
    }
    ASSERT_FALSE(tap.mask.empty());
    for (const auto &kv : tap.mask) {
        ASSERT_EQ(kv.second.size(), 7u);
        EXPECT_EQ(kv.second[6], 0.0f);
        for (int k = 0; k < 6; ++k) EXPECT_EQ(kv.second[k], 1.0f);
    }
}

// A session without a sensor the model requires is refused when the character is added, naming
// the segment; a contract-1 model requires all six.
TEST(SolverSensorSets, MissingRequiredSensorIsRefusedNamingIt)
{
    REQUIRE_ORT();
    std::string dir = test_temp_dir();
    ASSERT_TRUE(write_onnx_fixtures(dir));
    std::string cap = dir + "/seven.cap";
    synth_config cfg = short_capture(73, 0.5, "mixed", cap, true);
    for (const char *file : {"v2_chest.onnx", "valid.onnx"}) {
        Model model;
        ASSERT_EQ(open_model(dir + "/" + file, &model.m), MOCAP_OK) << mocap_last_error();
        Sessions sessions;
        sessions.list.push_back(open_replay_sensors(cap, cfg, 5, true));  // no head
        ASSERT_NE(sessions.list[0], nullptr);
        Solver solver;
        ASSERT_EQ(mocap_solver_open(model.m, nullptr, &solver.s), MOCAP_OK);
        int32_t ch = -1;
        EXPECT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_ERR_INVALID_ARGUMENT)
            << file;
        std::string err = mocap_last_error();
        EXPECT_NE(err.find("head"), std::string::npos) << err;
    }
}

// What the mask says for each sensor state, and that missing sensors feed zeros.
TEST(SolverSensorSets, MaskFollowsEachSensorsState)
{
    mocap_frame f = calibrated_six_frame();
    f.sensor_count = 7;
    f.sensors[6] = f.sensors[0];
    f.sensors[6].segment = MOCAP_SEGMENT_CHEST;
    for (uint32_t s = 0; s < 7; ++s) f.sensors[s].bone_acceleration[1] = 1.0f + s;
    const int8_t slots[7] = {0, 1, 2, 3, 4, 5, 6};
    float ori[63], acc[21], mask[7];
    struct Case {
        int32_t state;
        uint32_t flags;
        float expect;
    } cases[] = {
        {MOCAP_SENSOR_FRESH, MOCAP_SENSOR_VALID | MOCAP_SENSOR_CALIBRATED, 1.0f},
        {MOCAP_SENSOR_HOLDING, MOCAP_SENSOR_VALID | MOCAP_SENSOR_HELD | MOCAP_SENSOR_CALIBRATED, 1.0f},
        // silent: its held value, for the solver's stand-ins to replace
        {MOCAP_SENSOR_SILENT, MOCAP_SENSOR_VALID | MOCAP_SENSOR_HELD | MOCAP_SENSOR_STALE |
                                  MOCAP_SENSOR_CALIBRATED, 1.0f},
        {MOCAP_SENSOR_SILENT, MOCAP_SENSOR_VALID | MOCAP_SENSOR_HELD | MOCAP_SENSOR_STALE, 0.0f},
        {MOCAP_SENSOR_ABSENT, 0, 0.0f},
        {MOCAP_SENSOR_FRESH, MOCAP_SENSOR_VALID, 0.0f},  // not calibrated
    };
    for (const Case &c : cases) {
        f.sensors[6].state = c.state;
        f.sensors[6].flags = c.flags;
        ASSERT_EQ(solver_frame_input(&f, slots, 7, 1, ori, acc, mask), 0);
        EXPECT_EQ(mask[6], c.expect) << c.state;
        EXPECT_EQ(acc[6 * 3 + 1], c.expect ? 7.0f : 0.0f) << c.state;
        EXPECT_EQ(ori[6 * 9 + 0], c.expect ? 1.0f : 0.0f) << c.state;
        for (int k = 0; k < 6; ++k) EXPECT_EQ(mask[k], 1.0f);
    }
    // A missing sensor's NaN never counts: it is not fed.
    f.sensors[6].state = MOCAP_SENSOR_SILENT;
    f.sensors[6].bone_acceleration[0] = NAN;
    EXPECT_EQ(solver_frame_input(&f, slots, 7, 1, ori, acc, mask), 0);
    // A model sensor the session lacks (slot -1) is missing.
    const int8_t no_chest[7] = {0, 1, 2, 3, 4, 5, -1};
    ASSERT_EQ(solver_frame_input(&f, no_chest, 7, 1, ori, acc, mask), 0);
    EXPECT_EQ(mask[6], 0.0f);
    // A silent pelvis or wrist keeps its held value and mask 1, but never uncalibrated.
    f = calibrated_six_frame();
    f.sensors[0].bone_acceleration[2] = 3.0f;
    f.sensors[1].bone_acceleration[0] = 2.0f;
    for (int s : {0, 1}) {
        f.sensors[s].state = MOCAP_SENSOR_SILENT;
        f.sensors[s].flags |= MOCAP_SENSOR_HELD | MOCAP_SENSOR_STALE;
    }
    ASSERT_EQ(solver_frame_input(&f, slots, 6, 1, ori, acc, mask), 0);
    EXPECT_EQ(mask[0], 1.0f);
    EXPECT_EQ(acc[2], 3.0f);
    EXPECT_EQ(mask[1], 1.0f);
    EXPECT_EQ(ori[9], 1.0f);
    EXPECT_EQ(acc[3], 2.0f);
    f.sensors[0].flags &= ~(uint32_t)MOCAP_SENSOR_CALIBRATED;
    ASSERT_EQ(solver_frame_input(&f, slots, 6, 1, ori, acc, mask), 0);
    EXPECT_EQ(mask[0], 0.0f);
    EXPECT_EQ(ori[0], 0.0f);
}

// An extra sensor in the session changes nothing for a contract-1 model: the same capture solved
// with the six and with the six plus a chest gives identical poses.
TEST_F(SolverOnShippedModel, ExtraSensorLeavesAContractOneModelUntouched)
{
    std::string cap = test_temp_path("seven.cap");
    synth_config cfg = short_capture(74, 3.0, "mixed", cap, true);
    Sessions six, seven;
    six.list.push_back(open_replay_sensors(cap, cfg, 6, false));
    seven.list.push_back(open_replay_sensors(cap, cfg, 6, true));
    ASSERT_NE(six.list[0], nullptr);
    ASSERT_NE(seven.list[0], nullptr);
    std::vector<mocap_pose> a = solve_to_end(model.m, six.list[0], nullptr, nullptr);
    std::vector<mocap_pose> b = solve_to_end(model.m, seven.list[0], nullptr, nullptr);
    ASSERT_GT(a.size(), (size_t)(cfg.motion_s * 60.0));
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i].frame_sequence, b[i].frame_sequence) << i;
        ASSERT_EQ(0, memcmp(a[i].joint_rotations, b[i].joint_rotations, sizeof a[i].joint_rotations)) << i;
        ASSERT_EQ(0, memcmp(a[i].root_position, b[i].root_position, sizeof a[i].root_position)) << i;
        ASSERT_EQ(a[i].flags, b[i].flags) << i;
    }
}

namespace {

struct SilenceTap {
    struct Fed {
        int32_t state[MOCAP_MAX_SENSORS];
        float orientation[MOCAP_MAX_SENSORS][9];
        float acceleration[MOCAP_MAX_SENSORS][3];
        float measured[MOCAP_MAX_SENSORS][9];  // the frame's own (held) orientation
        float mask[MOCAP_MAX_SENSORS];         // -1: the model takes no mask
    };
    std::map<uint64_t, Fed> fed;  // frame sequence -> what the model was fed
};

void silence_tap(void *user, int32_t, const mocap_frame *frame, const float *ori, const float *acc,
                 const float *mask, int sensor_count)
{
    SilenceTap::Fed f{};
    for (int k = 0; k < sensor_count; ++k) {
        f.mask[k] = mask ? mask[k] : -1.0f;
        if (k >= (int)frame->sensor_count) {  // a model sensor the session lacks (after the six)
            f.state[k] = MOCAP_SENSOR_ABSENT;
            continue;
        }
        f.state[k] = frame->sensors[k].state;
        std::copy(ori + k * 9, ori + k * 9 + 9, f.orientation[k]);
        std::copy(acc + k * 3, acc + k * 3 + 3, f.acceleration[k]);
        double q[4], m[9];
        for (int i = 0; i < 4; ++i) q[i] = frame->sensors[k].bone_orientation[i];
        quat_normalize(q);
        quat_to_mat3(m, q);
        for (int i = 0; i < 9; ++i) f.measured[k][i] = (float)m[i];
    }
    static_cast<SilenceTap *>(user)->fed[frame->sequence] = f;
}

// The raw poses of one replay, every model input reported to tap.
std::vector<mocap_pose> solve_replay_tapped(mocap_model *model, const std::string &cap,
                                            const synth_config &cfg, SilenceTap &tap)
{
    Sessions sessions;
    sessions.list.push_back(open_replay(cap, cfg));
    if (!sessions.list[0]) return {};
    const mocap_solver_config sc = raw_output_config();
    Solver solver;
    EXPECT_EQ(mocap_solver_open(model, &sc, &solver.s), MOCAP_OK) << mocap_last_error();
    int32_t ch = -1;
    EXPECT_EQ(mocap_solver_add_character(solver.s, sessions.list[0], &ch), MOCAP_OK);
    solver_set_input_tap(solver.s, silence_tap, &tap);
    EXPECT_EQ(mocap_solver_start(solver.s), MOCAP_OK);
    EXPECT_EQ(mocap_session_start(sessions.list[0]), MOCAP_OK);
    std::vector<std::vector<mocap_pose>> poses;
    EXPECT_TRUE(drain_to_end(solver.s, 1, poses, 60));
    return poses.empty() ? std::vector<mocap_pose>{} : poses[0];
}

// The global rotation of joint j in a pose (joint 0 global, the others local).
void pose_global(const mocap_pose &p, int j, double out[9])
{
    double q[4], local[9], parent[9];
    for (int i = 0; i < 4; ++i) q[i] = p.joint_rotations[j][i];
    quat_to_mat3(local, q);
    if (j == 0) {
        std::copy(local, local + 9, out);
        return;
    }
    pose_global(p, smpl_joint_parent(j), parent);
    mat3_multiply(out, parent, local);
}

// A sensor back from a silence is fed its reading turned by the offset its stand-in had at the
// return, the offset fading out over solver.c's RETURN_EASE_S (0.15 s: 9 frames at 60 Hz).
struct EaseBack {
    static constexpr int kFrames = 9;
    bool stood_in = false, easing = false;
    int frames = 0;
    double stand_in[9] = {}, offset[4] = {1, 0, 0, 0};
    double largest_offset_deg = 0.0;

    void silent(const float *fed)
    {
        for (int i = 0; i < 9; ++i) stand_in[i] = fed[i];
        stood_in = true;
        easing = false;
    }
    // What a live frame whose own reading is `target` should be fed.
    void live(const double target[9], double want[9])
    {
        double qt[4];
        mat3_to_quat(qt, target);
        if (stood_in) {
            double qs[4], inverse[4];
            mat3_to_quat(qs, stand_in);
            quat_conjugate(inverse, qt);
            quat_multiply(offset, qs, inverse);
            largest_offset_deg = std::max(largest_offset_deg,
                                          2.0 * std::acos(std::min(1.0, std::fabs(offset[0]))) * 180.0 / 3.14159265358979);
            stood_in = false;
            easing = true;
            frames = 0;
        }
        if (easing && ++frames >= kFrames) easing = false;
        if (!easing) {
            std::copy(target, target + 9, want);
            return;
        }
        static const double identity[4] = {1, 0, 0, 0};
        double part[4], q[4];
        quat_slerp(part, identity, offset, 1.0 - (double)frames / kFrames);
        quat_multiply(q, part, qt);
        quat_to_mat3(want, q);
    }
};

}  // namespace

namespace {

// Every model is fed a stand-in for a silent sensor: a silent shin or head its bone as the model
// posed it in the frame before, at rest (zero acceleration); a silent wrist its held sample
// turned about the vertical as far as the pelvis turned since; a silent wrist or head then moves
// towards its bone's usual orientation over 4 s of silence; a held wrist sample is turned with
// the pelvis too; a sensor back from a silence eases from its stand-in to its readings
// (EaseBack); everything else live is fed as measured.
// A masked model (the shipped seven-sensor one, here on the six) gets them marked present; only
// its chest, which the session lacks, is missing.
void expect_silent_sensors_stood_in(mocap_model *model, bool masked)
{
    std::string cap = test_temp_path("silences.cap");
    // the wrist twice: its settling starts again from its own held sample the second time
    synth_config cfg = short_capture(91, 4.0, "turn", cap, false,
                                     {{MOCAP_SEGMENT_LEFT_SHIN, 1.0, 1.2},
                                      {MOCAP_SEGMENT_HEAD, 1.0, 1.2},
                                      {MOCAP_SEGMENT_RIGHT_WRIST, 1.0, 1.2},
                                      {MOCAP_SEGMENT_RIGHT_WRIST, 2.8, 0.8}});
    SilenceTap tap;
    std::vector<std::vector<mocap_pose>> poses(1, solve_replay_tapped(model, cap, cfg, tap));
    ASSERT_FALSE(poses[0].empty());
    std::map<uint64_t, const mocap_pose *> by_frame;
    for (const auto &p : poses[0]) by_frame[p.frame_sequence] = &p;

    const int shin = 3, wrist = 2, head = 5;  // the default set's order
    auto heading = [](const float *m) { return std::atan2(m[2] - m[5] * m[1], m[8] - m[5] * m[7]); };
    double pelvis_when_wrist_live = 0.0, wrist_turn = 0.0, max_share = 0.0;
    int silent_frames = 0, live_frames = 0, wrist_silent_frames = 0, head_silent_frames = 0;
    int eased_frames = 0;
    EaseBack ease[6];
    // solver.c's USUAL_RIGHT_WRIST and USUAL_HEAD (python3 -m training usual-orientation)
    static const double kRightWristUsual[9] = {-0.0721, -0.7129, 0.6976, 0.2907, 0.6540,
                                               0.6984,  -0.9541, 0.2531, 0.1600};
    static const double kHeadUsual[9] = {0.9984, -0.0092, -0.0555, 0.0001, 0.9871,
                                         -0.1602, 0.0563, 0.1599, 0.9855};
    for (const auto &kv : tap.fed) {
        const SilenceTap::Fed &f = kv.second;
        auto prev = by_frame.find(kv.first - 1);
        if (masked) {
            ASSERT_EQ(f.mask[6], 0.0f) << "the chest, which the session lacks";
            for (int k = 0; k < 6; ++k) ASSERT_EQ(f.mask[k], 1.0f) << "sensor " << k << " frame " << kv.first;
        } else {
            ASSERT_EQ(f.mask[0], -1.0f) << "a model without the mask was given one";
        }
        for (int k = 0; k < 6; ++k) {
            const bool silent = f.state[k] == MOCAP_SENSOR_SILENT;
            if (!silent) {
                ++live_frames;
                if (k == wrist) wrist_silent_frames = 0;
                if (k == wrist && f.state[k] == MOCAP_SENSOR_FRESH) pelvis_when_wrist_live = heading(f.orientation[0]);
                double target[9], want[9];
                for (int i = 0; i < 9; ++i) target[i] = f.measured[k][i];
                if (k == wrist && f.state[k] == MOCAP_SENSOR_HOLDING) {  // turned with the pelvis
                    double ry[9], measured[9];
                    std::copy(target, target + 9, measured);
                    mat3_rotation_y(ry, heading(f.orientation[0]) - pelvis_when_wrist_live);
                    mat3_multiply(target, ry, measured);
                }
                const bool was_easing = ease[k].easing || ease[k].stood_in;
                ease[k].live(target, want);
                eased_frames += was_easing && ease[k].easing;
                for (int i = 0; i < 9; ++i) ASSERT_NEAR(f.orientation[k][i], want[i], 2e-4) << k << " frame " << kv.first;
                continue;
            }
            ease[k].silent(f.orientation[k]);
            ASSERT_TRUE(k == shin || k == head || k == wrist) << "sensor " << k << " went silent";
            if (k == wrist) {
                // its held sample turned with the pelvis, on its way to the hand's usual
                // orientation (turned with the pelvis too) as its silence grows; acceleration held
                double ry[9], held[9], turned[9], usual[9], want[9];
                const double turn = heading(f.orientation[0]) - pelvis_when_wrist_live;
                wrist_turn = std::max(wrist_turn, std::fabs(std::remainder(turn, 2.0 * 3.14159265358979)));
                mat3_rotation_y(ry, turn);
                for (int i = 0; i < 9; ++i) held[i] = f.measured[k][i];
                mat3_multiply(turned, ry, held);
                mat3_rotation_y(ry, heading(f.orientation[0]));
                mat3_multiply(usual, ry, kRightWristUsual);
                const double share = ++wrist_silent_frames / 60.0 / 4.0;
                double qa[4], qb[4], q[4];
                mat3_to_quat(qa, turned);
                mat3_to_quat(qb, usual);
                quat_slerp(q, qa, qb, share);
                quat_to_mat3(want, q);
                for (int i = 0; i < 9; ++i) ASSERT_NEAR(f.orientation[k][i], want[i], 2e-4) << kv.first;
                max_share = std::max(max_share, share);
                continue;
            }
            ++silent_frames;
            ASSERT_NE(prev, by_frame.end()) << "frame " << kv.first;
            double g[9];
            pose_global(*prev->second, k == shin ? 4 : 15, g);  // left knee -> ankle bone, head
            if (k == head) {  // on its way to the head's usual orientation, turned with the pelvis
                double ry[9], usual[9], qa[4], qb[4], q[4];
                mat3_rotation_y(ry, heading(f.orientation[0]));
                mat3_multiply(usual, ry, kHeadUsual);
                mat3_to_quat(qa, g);
                mat3_to_quat(qb, usual);
                quat_slerp(q, qa, qb, ++head_silent_frames / 60.0 / 4.0);
                quat_to_mat3(g, q);
            }
            for (int i = 0; i < 9; ++i) ASSERT_NEAR(f.orientation[k][i], g[i], 1e-5) << "sensor " << k;
            for (int i = 0; i < 3; ++i) ASSERT_EQ(f.acceleration[k][i], 0.0f);
            // and not what it last measured: the body walked on
        }
    }
    EXPECT_GT(silent_frames, 2 * 50);  // both, most of 1.2 s at 60 Hz
    EXPECT_GT(wrist_turn, 10.0 * 3.14159265358979 / 180.0) << "the body turned while the wrist was silent";
    EXPECT_GT(max_share, 0.15) << "the wrist was silent long enough to move towards its usual orientation";
    EXPECT_GT(live_frames, 6 * 100);
    // three sensors came back, the wrist twice, each easing in over 8 frames
    EXPECT_EQ(eased_frames, 4 * (EaseBack::kFrames - 1));
    EXPECT_GT(ease[wrist].largest_offset_deg, 10.0) << "the settled wrist came back off its reading";
    // the wrist's held acceleration is its last sample, not zero
    bool wrist_accelerates = false;
    for (const auto &kv : tap.fed)
        if (kv.second.state[wrist] == MOCAP_SENSOR_SILENT)
            wrist_accelerates |= std::fabs(kv.second.acceleration[wrist][0]) + std::fabs(kv.second.acceleration[wrist][1]) +
                                     std::fabs(kv.second.acceleration[wrist][2]) > 0.0f;
    EXPECT_TRUE(wrist_accelerates);
}

}  // namespace

TEST_F(SolverOnShippedModel, SilentSensorsStandInFromThePoseAndSettle)
{
    expect_silent_sensors_stood_in(model.m, false);
}

TEST(SolverOnShippedChestModel, AMaskedModelGetsTheSameStandInsMarkedPresent)
{
    REQUIRE_ORT();
    Model model;
    ASSERT_EQ(open_model(kShippedChestModel, &model.m), MOCAP_OK) << mocap_last_error();
    mocap_model_info info;
    ASSERT_EQ(mocap_model_get_info(model.m, &info), MOCAP_OK);
    ASSERT_EQ(info.sensor_count, 7u);
    ASSERT_EQ(info.sensor_segments[6], MOCAP_SEGMENT_CHEST);
    expect_silent_sensors_stood_in(model.m, true);
}

// A silent pelvis is every model's frame of reference: it is fed its last sample turned about
// the vertical by the shins' mean heading change since its last fresh sample, at rest. The same
// capture without the silence (identical outside it) shows the turn follows the real pelvis.
TEST_F(SolverOnShippedModel, ASilentPelvisTurnsWithTheShins)
{
    std::string cap = test_temp_path("pelvis_silence.cap"), whole = test_temp_path("pelvis_whole.cap");
    synth_config cfg = short_capture(92, 4.0, "turn", cap, false, {{MOCAP_SEGMENT_PELVIS, 1.0, 2.0}});
    short_capture(92, 4.0, "turn", whole);
    SilenceTap tap, truth;
    ASSERT_FALSE(solve_replay_tapped(model.m, cap, cfg, tap).empty());
    ASSERT_FALSE(solve_replay_tapped(model.m, whole, cfg, truth).empty());

    auto hvec = [](const float *m, double h[2]) {
        h[0] = m[2] - m[5] * m[1];
        h[1] = m[8] - m[5] * m[7];
    };
    auto heading = [&](const float *m) {
        double h[2];
        hvec(m, h);
        return std::atan2(h[0], h[1]);
    };
    const int pelvis = 0, shins[2] = {3, 4};
    double ref[2][2] = {{0, 1}, {0, 1}};
    int silent = 0;
    double largest_turn = 0.0, off_truth = 0.0, off_held = 0.0;
    EaseBack ease;
    int held = 0;
    for (const auto &kv : tap.fed) {
        const SilenceTap::Fed &f = kv.second;
        if (f.state[pelvis] == MOCAP_SENSOR_FRESH) {
            double target[9], want[9];
            for (int i = 0; i < 9; ++i) target[i] = f.measured[pelvis][i];
            ease.live(target, want);
            for (int i = 0; i < 9; ++i) ASSERT_NEAR(f.orientation[pelvis][i], want[i], 2e-4) << kv.first;
            for (int s = 0; s < 2; ++s) hvec(f.orientation[shins[s]], ref[s]);
            continue;
        }
        // held (the first moments of the silence) or silent: turned with the shins
        ease.silent(f.orientation[pelvis]);
        if (f.state[pelvis] == MOCAP_SENSOR_HOLDING) {
            ++held;
        } else {
            ++silent;
            for (int i = 0; i < 3; ++i) ASSERT_EQ(f.acceleration[pelvis][i], 0.0f);
        }
        double sx = 0, cx = 0;
        for (int s = 0; s < 2; ++s) {
            double b[2];
            hvec(f.orientation[shins[s]], b);
            sx += b[0] * ref[s][1] - b[1] * ref[s][0];
            cx += ref[s][0] * b[0] + ref[s][1] * b[1];
        }
        const double d = std::atan2(sx, cx);
        largest_turn = std::max(largest_turn, std::fabs(d));
        double ry[9], held[9], want[9];
        mat3_rotation_y(ry, d);
        for (int i = 0; i < 9; ++i) held[i] = f.measured[pelvis][i];
        mat3_multiply(want, ry, held);
        for (int i = 0; i < 9; ++i) ASSERT_NEAR(f.orientation[pelvis][i], want[i], 2e-4) << kv.first;
        auto real = truth.fed.find(kv.first);
        ASSERT_NE(real, truth.fed.end());
        const double truth_heading = heading(real->second.measured[pelvis]);
        off_truth += std::fabs(std::remainder(heading(f.orientation[pelvis]) - truth_heading, 2 * 3.14159265358979));
        off_held += std::fabs(std::remainder(heading(f.measured[pelvis]) - truth_heading, 2 * 3.14159265358979));
    }
    EXPECT_GT(silent, 90);                   // most of 2 s at 60 Hz
    EXPECT_GT(held, 5);                      // the samples held before the silence is declared
    EXPECT_GT(largest_turn, 20.0 * 3.14159265358979 / 180.0) << "the performer turned while the pelvis was silent";
    const double deg = 180.0 / 3.14159265358979;
    std::printf("pelvis heading in the gap, mean error: turned %.1f deg, held %.1f deg\n",
                off_truth / (held + silent) * deg, off_held / (held + silent) * deg);
    EXPECT_LT(off_truth / (held + silent) * deg, 5.0);  // the real pelvis' heading, where holding was ~100 off
    EXPECT_GT(off_held / (held + silent) * deg, 30.0);
}


namespace {

// The raw poses of a replay of the six and, with_chest, the chest on node 6, with the given chest
// following, every model input reported to tap.
std::vector<mocap_pose> solve_chest_replay(mocap_model *model, const std::string &cap,
                                           const synth_config &cfg, bool with_chest,
                                           float chest_follow, SilenceTap &tap)
{
    Sessions sessions;
    sessions.list.push_back(open_replay_sensors(cap, cfg, 6, with_chest));
    if (!sessions.list[0]) return {};
    return solve_to_end(model, sessions.list[0], silence_tap, &tap, chest_follow);
}

}  // namespace

// Each pose is the model's own turned by chest_follow_apply towards the chest it was fed: the
// chest bone ends half as far from its sensor, and the root, contacts and velocity are the model's.
TEST(SolverOnShippedChestModel, ChestFollowingTurnsTheSpineTowardsTheChestSensor)
{
    REQUIRE_ORT();
    Model model;
    ASSERT_EQ(open_model(kShippedChestModel, &model.m), MOCAP_OK) << mocap_last_error();
    std::string cap = test_temp_path("chest_follow.cap");
    synth_config cfg = short_capture(31, 4.0, "mixed", cap, true);
    SilenceTap free_tap, follow_tap;
    std::vector<mocap_pose> free_pose = solve_chest_replay(model.m, cap, cfg, true, 0.0f, free_tap);
    std::vector<mocap_pose> followed = solve_chest_replay(model.m, cap, cfg, true, 0.5f, follow_tap);
    ASSERT_GT(free_pose.size(), 200u);
    ASSERT_EQ(free_pose.size(), followed.size());
    const int chest = 6;
    double off_before = 0.0, off_after = 0.0;
    for (size_t t = 0; t < followed.size(); ++t) {
        const auto fed = follow_tap.fed.find(followed[t].frame_sequence);
        ASSERT_NE(fed, follow_tap.fed.end());
        ASSERT_TRUE(fed->second.state[chest] == MOCAP_SENSOR_FRESH ||
                    fed->second.state[chest] == MOCAP_SENSOR_HOLDING) << t;
        double m[9], sensed[4], q[MOCAP_JOINT_COUNT][4];
        for (int i = 0; i < 9; ++i) m[i] = fed->second.orientation[chest][i];
        mat3_to_quat(sensed, m);
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
            for (int i = 0; i < 4; ++i) q[j][i] = free_pose[t].joint_rotations[j][i];
        double g_free[9], g_followed[9];
        pose_global(free_pose[t], CHEST_FOLLOW_SPINE3, g_free);
        pose_global(followed[t], CHEST_FOLLOW_SPINE3, g_followed);
        off_before += mat3_angle_deg(g_free, m);
        off_after += mat3_angle_deg(g_followed, m);
        ASSERT_EQ(chest_follow_apply(q, sensed, 0.5), 0);
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            double got[4];
            for (int i = 0; i < 4; ++i) got[i] = followed[t].joint_rotations[j][i];
            EXPECT_LT(quat_angle_deg(q[j], got), 0.005) << "pose " << t << " joint " << j;
        }
        for (int i = 0; i < 3; ++i) EXPECT_EQ(followed[t].root_velocity[i], free_pose[t].root_velocity[i]);
        EXPECT_EQ(followed[t].foot_contact[0], free_pose[t].foot_contact[0]);
    }
    off_before /= followed.size();
    off_after /= followed.size();
    EXPECT_GT(off_before, 1.0) << "the model leaves its chest away from the sensor";
    EXPECT_NEAR(off_after, 0.5 * off_before, 0.01 * off_before);
}

// Without a chest in the session the setting changes nothing: the model is told the chest is
// missing, and there is nothing to follow.
TEST(SolverOnShippedChestModel, ChestFollowingWithoutAChestLeavesThePose)
{
    REQUIRE_ORT();
    Model model;
    ASSERT_EQ(open_model(kShippedChestModel, &model.m), MOCAP_OK) << mocap_last_error();
    std::string cap = test_temp_path("chest_follow_six.cap");
    synth_config cfg = short_capture(32, 2.0, "mixed", cap, true);
    SilenceTap free_tap, follow_tap;
    std::vector<mocap_pose> free_pose = solve_chest_replay(model.m, cap, cfg, false, 0.0f, free_tap);
    std::vector<mocap_pose> followed = solve_chest_replay(model.m, cap, cfg, false, 1.0f, follow_tap);
    ASSERT_GT(free_pose.size(), 100u);
    ASSERT_EQ(free_pose.size(), followed.size());
    for (size_t t = 0; t < followed.size(); ++t)
        ASSERT_EQ(std::memcmp(followed[t].joint_rotations, free_pose[t].joint_rotations,
                              sizeof followed[t].joint_rotations), 0) << t;
}
