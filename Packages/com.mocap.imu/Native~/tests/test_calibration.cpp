// Calibration: heading + T-pose on synthetic sensors (NWU and ENU worlds, random per-sensor world
// headings and mountings), refusals, heading reset, apply flags/preview, progress, file format.
#include <gtest/gtest.h>

#include <filesystem>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "test_support.h"

#include <sys/stat.h>
#include <unistd.h>

extern "C" {
#include "calibration.h"
#include "error.h"
#include "mocap_math.h"
}

namespace {

// The default set: six sensors, sensor i on segment i.
constexpr int N = 6;
const int32_t SEGMENTS[N] = {0, 1, 2, 3, 4, 5};
constexpr uint32_t ALL = (1u << N) - 1u;
constexpr double G = MOCAP_STANDARD_GRAVITY;

void mat_from_quat_f(double m[9], const float qf[4])
{
    double q[4] = {qf[0], qf[1], qf[2], qf[3]};
    quat_normalize(q);
    quat_to_mat3(m, q);
}

// A body wearing six sensors in a sensor world (Z up, NWU or ENU), everything known exactly.
struct Rig {
    int world_frame = MOCAP_WORLD_NWU;
    double world_from_room[N][9]; // room: Z up, X = the user's forward at calibration
    double bone_from_sensor[N][9]; // mounting rotation
    double heading_tilt[N][9];     // how each sensor lies on the (not quite level) table
    mocap_rng rng;
    double quat_noise_deg = 0.2;   // per axis
    double force_noise = 0.05;     // m/s^2 per axis
    double gyro_noise_dps = 0.3;
    double t0 = 0.0;        // frame n is at t0 + n / 60 (exact, no accumulated rounding)
    uint64_t n = 0;
    uint64_t sequence = 0;
    void set_time(double t) { t0 = t; n = 0; }

    Rig(uint64_t seed, int frame) : world_frame(frame)
    {
        mocap_rng_seed(&rng, seed);
        // The user faces compass bearing beta; each sensor's yaw reference is arbitrary too
        // (6-axis fusion has no absolute heading), hence a random error per sensor.
        double beta = 2 * MOCAP_PI * mocap_rng_uniform(&rng);
        double forward_yaw = frame == MOCAP_WORLD_NWU ? -beta : 0.5 * MOCAP_PI - beta;
        for (int s = 0; s < N; s++) {
            double err = (2 * mocap_rng_uniform(&rng) - 1) * MOCAP_PI;
            mat3_rotation_z(world_from_room[s], forward_yaw + err);
            double q[4];
            mocap_rng_rotation(&rng, q);
            quat_to_mat3(bone_from_sensor[s], q);
            double rx[9], ry[9];
            mat3_rotation_x(rx, (2 * mocap_rng_uniform(&rng) - 1) * 4 * MOCAP_DEG2RAD);
            mat3_rotation_y(ry, (2 * mocap_rng_uniform(&rng) - 1) * 4 * MOCAP_DEG2RAD);
            mat3_multiply(heading_tilt[s], ry, rx); // sensor X still points forward
        }
    }

    void noise_rotation(double out[9], double sigma_deg)
    {
        double v[3];
        for (double &c : v)
            c = sigma_deg * MOCAP_DEG2RAD * mocap_rng_gaussian(&rng);
        double q[4];
        double n = vec3_norm(v);
        if (n > 0)
            quat_from_axis_angle(q, v, n);
        else
            quat_identity(q);
        quat_to_mat3(out, q);
    }

    // One frame from each sensor's orientation in the room and specific force in the room.
    raw_frame frame(const double room_from_sensor[N][9], const double force_room[N][3],
                    const double gyro_sensor[N][3], bool noisy, uint32_t fresh = ALL)
    {
        raw_frame f;
        std::memset(&f, 0, sizeof f);
        f.sequence = sequence++;
        f.t = t0 + (double)n++ / 60.0;
        f.fresh_mask = fresh;
        f.valid_mask = ALL;
        for (int s = 0; s < N; s++) {
            double r[9], q[4];
            mat3_multiply(r, world_from_room[s], room_from_sensor[s]);
            if (noisy) {
                double e[9];
                noise_rotation(e, quat_noise_deg);
                mat3_multiply(r, r, e);
            }
            mat3_to_quat(q, r);
            if (mocap_rng_uniform(&rng) < 0.5) // the sign of a quaternion carries no meaning
                for (double &c : q)
                    c = -c;
            std::memcpy(f.quat[s], q, sizeof q);
            mat3_apply(f.force_world[s], world_from_room[s], force_room[s]);
            for (int i = 0; i < 3; i++) {
                if (noisy)
                    f.force_world[s][i] += force_noise * mocap_rng_gaussian(&rng);
                f.gyr[s][i] = gyro_sensor[s][i] +
                              (noisy ? gyro_noise_dps * MOCAP_DEG2RAD * mocap_rng_gaussian(&rng) : 0);
            }
            f.age[s] = 0.004;
            f.node_id[s] = 20 + s;
        }
        return f;
    }

    // Sensors on the body: bones given in the model frame, accelerations in the model frame.
    raw_frame body_frame(const double model_from_bone[N][9], const double accel_model[N][3],
                         bool noisy, uint32_t fresh = ALL)
    {
        double a[9], room_from_sensor[N][9], force_room[N][3], gyro[N][3] = {};
        mocap_world_zup_to_model(a);
        for (int s = 0; s < N; s++) {
            double tmp[9];
            mat3_multiply(tmp, model_from_bone[s], bone_from_sensor[s]);
            // room_from_model = A^T
            double at[9];
            mat3_transpose(at, a);
            mat3_multiply(room_from_sensor[s], at, tmp);
            double am[3];
            mat3_apply(am, at, accel_model[s]);
            force_room[s][0] = am[0];
            force_room[s][1] = am[1];
            force_room[s][2] = am[2] + G; // specific force = a - g, g pointing down
        }
        return frame(room_from_sensor, force_room, gyro, noisy, fresh);
    }
};

struct WindowSpec {
    int step = MOCAP_CALIBRATION_HEADING;
    int frames = 180;       // 3 s at 60 Hz
    int spin_sensor = -1;   // rotates about world up at spin_dps
    double spin_dps = 30.0;
    int units_sensor = -1;  // reports force in g instead of m/s^2
    int tilt_sensor = -1;   // lies tilted by tilt_deg during the heading step
    double tilt_deg = 45.0;
    int missing_sensor = -1;
    int sparse_sensor = -1; // fresh in only one frame in three
    const double (*bones)[9] = nullptr; // body pose for T-pose / reset (identity if null)
};

struct WindowResult {
    mocap_status status;
    mocap_calibration_report report;
};

WindowResult run_window(Rig &rig, mocap_calibration &cal, const WindowSpec &spec)
{
    static calib_accumulator acc; // large: keep it off the stack
    calib_init(&acc, N, SEGMENTS, 0);
    calib_begin(&acc, spec.step, -1.0, (spec.frames - 1) / 60.0);
    double identity[N][9];
    for (auto &m : identity)
        mat3_identity(m);
    const double (*bones)[9] = spec.bones ? spec.bones : identity;
    double zero_acc[N][3] = {};
    for (int i = 0; i < spec.frames + 5; i++) {
        uint32_t fresh = ALL;
        if (spec.missing_sensor >= 0)
            fresh &= ~(1u << spec.missing_sensor);
        if (spec.sparse_sensor >= 0 && i % 3 != 0)
            fresh &= ~(1u << spec.sparse_sensor);
        raw_frame f;
        double time_in = i / 60.0;
        if (spec.step == MOCAP_CALIBRATION_HEADING) {
            double room_from_sensor[N][9], force[N][3], gyro[N][3] = {};
            for (int s = 0; s < N; s++) {
                std::memcpy(room_from_sensor[s], rig.heading_tilt[s], sizeof room_from_sensor[s]);
                if (s == spec.tilt_sensor)
                    mat3_rotation_x(room_from_sensor[s], spec.tilt_deg * MOCAP_DEG2RAD);
                if (s == spec.spin_sensor) {
                    double rz[9];
                    mat3_rotation_z(rz, spec.spin_dps * MOCAP_DEG2RAD * time_in);
                    mat3_multiply(room_from_sensor[s], rz, room_from_sensor[s]);
                    double w_room[3] = {0, 0, spec.spin_dps * MOCAP_DEG2RAD}, rt[9];
                    mat3_transpose(rt, room_from_sensor[s]);
                    mat3_apply(gyro[s], rt, w_room);
                }
                force[s][0] = force[s][1] = 0;
                force[s][2] = s == spec.units_sensor ? 1.0 : G;
            }
            f = rig.frame(room_from_sensor, force, gyro, true, fresh);
        } else {
            f = rig.body_frame(bones, zero_acc, true, fresh);
            if (spec.units_sensor >= 0)
                for (double &c : f.force_world[spec.units_sensor])
                    c /= G;
        }
        if (calib_add_frame(&acc, &f)) {
            WindowResult r;
            r.status = calib_finish(&acc, &cal, &r.report);
            return r;
        }
    }
    ADD_FAILURE() << "window never closed";
    return {MOCAP_ERR_STATE, {}};
}

void calibrate(Rig &rig, mocap_calibration &cal)
{
    calib_identity(&cal, N, SEGMENTS);
    WindowSpec heading;
    WindowResult h = run_window(rig, cal, heading);
    ASSERT_EQ(h.status, MOCAP_OK) << h.report.reason;
    EXPECT_EQ(cal.heading_mask, ALL);
    WindowSpec tpose;
    tpose.step = MOCAP_CALIBRATION_TPOSE;
    WindowResult t = run_window(rig, cal, tpose);
    ASSERT_EQ(t.status, MOCAP_OK) << t.report.reason;
    EXPECT_EQ(cal.valid_mask, ALL);
    EXPECT_EQ(t.report.state, MOCAP_CALIBRATION_ACCEPTED);
}

// Worst bone orientation (deg) and acceleration (m/s^2) error over random poses, noise-free
// frames, so that only the calibration's own error is measured.
void evaluate(Rig &rig, const mocap_calibration &cal, double &worst_deg, double &worst_acc,
              int only_sensor = -1)
{
    worst_deg = worst_acc = 0;
    static mocap_frame out;
    for (int k = 0; k < 200; k++) {
        double bones[N][9], acc[N][3];
        for (int s = 0; s < N; s++) {
            double q[4];
            mocap_rng_rotation(&rig.rng, q);
            quat_to_mat3(bones[s], q);
            for (double &c : acc[s])
                c = 3.0 * mocap_rng_gaussian(&rig.rng);
        }
        raw_frame f = rig.body_frame(bones, acc, false);
        calib_apply(&cal, rig.world_frame, 0, &f, &out);
        for (int s = 0; s < N; s++) {
            if (only_sensor >= 0 && s != only_sensor)
                continue;
            double got[9];
            mat_from_quat_f(got, out.sensors[s].bone_orientation);
            worst_deg = std::fmax(worst_deg, mat3_angle_deg(got, bones[s]));
            for (int i = 0; i < 3; i++)
                worst_acc = std::fmax(worst_acc,
                                      std::fabs(out.sensors[s].bone_acceleration[i] - acc[s][i]));
        }
    }
}

bool contains(const char *text, const char *needle)
{
    return std::strstr(text, needle) != nullptr;
}

} // namespace

// The segment table as the header's enum and the default set see it: names, SMPL joints, default
// node ids (the chest is in the table but not in the default set).
TEST(Calibration, SegmentNames)
{
    const char *expect[] = {"pelvis", "left_wrist", "right_wrist", "left_shin", "right_shin", "head",
                            "chest"};
    const int joints[] = {0, 20, 21, 4, 5, 15, 9};
    const int nodes[] = {0, 1, 2, 3, 4, 5, -1};
    ASSERT_EQ(mocap_segment_count(), 7);
    for (int s = 0; s < 7; s++) {
        EXPECT_STREQ(mocap_segment_name(s), expect[s]);
        EXPECT_EQ(mocap_segment_find(expect[s]), s);
        EXPECT_EQ(mocap_segment_joint(s), joints[s]) << expect[s];
        EXPECT_EQ(mocap_segment_default_node(s), nodes[s]) << expect[s];
    }
    EXPECT_EQ(MOCAP_SEGMENT_CHEST, 6);
    EXPECT_EQ(mocap_segment_name(-1), nullptr);
    EXPECT_EQ(mocap_segment_name(mocap_segment_count()), nullptr);
    EXPECT_EQ(mocap_segment_find("Chest"), -1); // exact, lower case
    EXPECT_EQ(mocap_segment_find("spine"), -1);
    EXPECT_EQ(mocap_segment_joint(7), -1);
}

// Bound: each calibration window averages 180 frames of 0.2 deg (per axis) orientation noise, so
// each step's estimate is off by about 0.2 * sqrt(3) / sqrt(180) ~ 0.03 deg; heading and T-pose
// errors add, and the test takes the worst of 36 sensor calibrations over 200 poses (measured
// 0.04..0.09 deg). 0.25 deg leaves margin for that tail while staying far below anything visible;
// a wrong formula (a transposed matrix, a wrong yaw sign) errs by tens of degrees.
// Accelerations: the offset averages 0.05 m/s^2 noise over 180 frames (~0.004), the heading error
// tilts ~20 m/s^2 forces by ~0.03 deg (~0.01); measured <= 0.011, bound 0.05 m/s^2.
TEST(Calibration, RecoversBonesInNwuAndEnuWorlds)
{
    for (int world : {MOCAP_WORLD_NWU, MOCAP_WORLD_ENU}) {
        for (uint64_t seed : {11u, 12u, 13u}) {
            Rig rig(seed * 7 + (uint64_t)world, world);
            static mocap_calibration cal;
            calibrate(rig, cal);
            double deg, acc;
            evaluate(rig, cal, deg, acc);
            EXPECT_LT(deg, 0.25) << "world " << world << " seed " << seed;
            EXPECT_LT(acc, 0.05) << "world " << world << " seed " << seed;

            // Offsets hold gravity (up = model +Y) and the frame is flagged calibrated.
            for (int s = 0; s < N; s++) {
                EXPECT_NEAR(cal.acceleration_offset[s][1], G, 0.05);
                EXPECT_NEAR(cal.acceleration_offset[s][0], 0.0, 0.05);
            }
            static mocap_frame out;
            double id[N][9], zero[N][3] = {};
            for (auto &m : id)
                mat3_identity(m);
            raw_frame f = rig.body_frame(id, zero, false);
            calib_apply(&cal, world, 0, &f, &out);
            EXPECT_EQ(out.flags, (uint32_t)(MOCAP_FRAME_CALIBRATED | MOCAP_FRAME_COMPLETE));
            for (int s = 0; s < N; s++) {
                EXPECT_EQ(out.sensors[s].flags,
                          (uint32_t)(MOCAP_SENSOR_VALID | MOCAP_SENSOR_CALIBRATED));
                EXPECT_EQ(out.sensors[s].node_id, (uint32_t)(20 + s));
            }
        }
    }
}

namespace {

void expect_unchanged(const mocap_calibration &before, const mocap_calibration &after)
{
    EXPECT_EQ(std::memcmp(&before, &after, sizeof before), 0) << "calibration was modified";
}

} // namespace

TEST(Calibration, RefusesSpinningSensorNamingIt)
{
    Rig rig(21, MOCAP_WORLD_NWU);
    static mocap_calibration cal, before;
    calibrate(rig, cal);
    before = cal;
    WindowSpec spec;
    spec.spin_sensor = MOCAP_SEGMENT_LEFT_WRIST;
    WindowResult r = run_window(rig, cal, spec);
    EXPECT_EQ(r.status, MOCAP_ERR_BAD_CALIBRATION);
    EXPECT_EQ(r.report.state, MOCAP_CALIBRATION_REFUSED);
    EXPECT_TRUE(contains(r.report.reason, "left_wrist: gyro 30.")) << r.report.reason;
    EXPECT_TRUE(contains(r.report.reason, "> 10")) << r.report.reason;
    EXPECT_TRUE(contains(r.report.reason, "orientation spread")) << r.report.reason;
    EXPECT_FALSE(contains(r.report.reason, "pelvis")) << r.report.reason;
    EXPECT_NEAR(r.report.sensors[1].gyro_rms_dps, 30.0, 1.0);
    // 90 degrees swept uniformly: RMS about the middle is 90/sqrt(12) = 26 deg.
    EXPECT_NEAR(r.report.sensors[1].orientation_spread_deg, 26.0, 1.5);
    for (int s = 0; s < N; s++)
        EXPECT_EQ(r.report.sensors[s].ok, s == 1 ? 0 : 1) << s;
    EXPECT_TRUE(contains(mocap_last_error(), "left_wrist"));
    expect_unchanged(before, cal);
}

TEST(Calibration, RefusesUnitMixUp)
{
    for (int step : {MOCAP_CALIBRATION_HEADING, MOCAP_CALIBRATION_TPOSE}) {
        Rig rig(22, MOCAP_WORLD_ENU);
        static mocap_calibration cal, before;
        calibrate(rig, cal);
        before = cal;
        WindowSpec spec;
        spec.step = step;
        spec.units_sensor = MOCAP_SEGMENT_RIGHT_SHIN;
        WindowResult r = run_window(rig, cal, spec);
        EXPECT_EQ(r.status, MOCAP_ERR_BAD_CALIBRATION);
        EXPECT_TRUE(contains(r.report.reason, "right_shin: |force| 1.0")) << r.report.reason;
        EXPECT_TRUE(contains(r.report.reason, "> 1.5")) << r.report.reason;
        EXPECT_NEAR(r.report.sensors[4].accel_norm_error, G - 1.0, 0.05);
        EXPECT_EQ(r.report.sensors[4].ok, 0);
        expect_unchanged(before, cal);
    }
}

TEST(Calibration, RefusesTiltedHeadingStep)
{
    Rig rig(23, MOCAP_WORLD_NWU);
    static mocap_calibration cal, before;
    calibrate(rig, cal);
    before = cal;
    WindowSpec spec;
    spec.tilt_sensor = MOCAP_SEGMENT_HEAD;
    WindowResult r = run_window(rig, cal, spec);
    EXPECT_EQ(r.status, MOCAP_ERR_BAD_CALIBRATION);
    EXPECT_TRUE(contains(r.report.reason, "head: tilt 45.")) << r.report.reason;
    EXPECT_TRUE(contains(r.report.reason, "> 30")) << r.report.reason;
    EXPECT_NEAR(r.report.sensors[5].tilt_deg, 45.0, 0.2);
    EXPECT_LT(r.report.sensors[0].tilt_deg, 6.0); // the others lie within 4+4 deg of level
    expect_unchanged(before, cal);
}

TEST(Calibration, RefusesMissingAndSparseSensors)
{
    Rig rig(24, MOCAP_WORLD_NWU);
    static mocap_calibration cal, before;
    calibrate(rig, cal);
    before = cal;
    WindowSpec spec;
    spec.step = MOCAP_CALIBRATION_TPOSE;
    spec.missing_sensor = MOCAP_SEGMENT_RIGHT_WRIST;
    spec.sparse_sensor = MOCAP_SEGMENT_PELVIS;
    WindowResult r = run_window(rig, cal, spec);
    EXPECT_EQ(r.status, MOCAP_ERR_BAD_CALIBRATION);
    EXPECT_TRUE(contains(r.report.reason, "right_wrist: no samples")) << r.report.reason;
    EXPECT_TRUE(contains(r.report.reason, "pelvis: 60 samples in 180 frames < 50%"))
        << r.report.reason;
    EXPECT_EQ(r.report.sensors[2].samples, 0u);
    EXPECT_EQ(r.report.sensors[0].samples, 60u);
    EXPECT_EQ(r.report.sensors[3].ok, 1);
    expect_unchanged(before, cal);
}

TEST(Calibration, RefusesTposeWithoutHeading)
{
    Rig rig(25, MOCAP_WORLD_NWU);
    static mocap_calibration cal, before;
    calib_identity(&cal, N, SEGMENTS);
    cal.heading_mask = ALL & ~(1u << MOCAP_SEGMENT_LEFT_SHIN);
    before = cal;
    WindowSpec spec;
    spec.step = MOCAP_CALIBRATION_TPOSE;
    WindowResult r = run_window(rig, cal, spec);
    EXPECT_EQ(r.status, MOCAP_ERR_BAD_CALIBRATION);
    EXPECT_TRUE(contains(r.report.reason, "left_shin: no heading")) << r.report.reason;
    EXPECT_FALSE(contains(r.report.reason, "right_shin")) << r.report.reason;
    expect_unchanged(before, cal);
}

TEST(Calibration, RefusesHeadingResetBeforeCalibrationAndEmptyWindow)
{
    Rig rig(26, MOCAP_WORLD_NWU);
    static mocap_calibration cal;
    calib_identity(&cal, N, SEGMENTS);
    WindowSpec spec;
    spec.step = MOCAP_CALIBRATION_HEADING_RESET;
    WindowResult r = run_window(rig, cal, spec);
    EXPECT_EQ(r.status, MOCAP_ERR_BAD_CALIBRATION);
    EXPECT_TRUE(contains(r.report.reason, "no sensor is calibrated")) << r.report.reason;

    // A window scheduled entirely in the past closes at the first frame with nothing in it.
    static calib_accumulator acc;
    calib_init(&acc, N, SEGMENTS, 0);
    calib_begin(&acc, MOCAP_CALIBRATION_HEADING, 0.0, 1.0);
    rig.set_time(5.0);
    double id[N][9], zero[N][3] = {};
    for (auto &m : id)
        mat3_identity(m);
    raw_frame f = rig.body_frame(id, zero, false);
    ASSERT_EQ(calib_add_frame(&acc, &f), 1);
    mocap_calibration_report report;
    EXPECT_EQ(calib_finish(&acc, &cal, &report), MOCAP_ERR_BAD_CALIBRATION);
    EXPECT_TRUE(contains(report.reason, "no frames")) << report.reason;
}

TEST(Calibration, LongWindowSpreadUsesWholeWindow)
{
    // 15 s at 60 Hz is 900 frames per sensor... use 2400 frames to overflow the 1024 kept
    // orientations: the spread must still describe the whole window, not its first part.
    Rig rig(27, MOCAP_WORLD_NWU);
    static mocap_calibration cal;
    calib_identity(&cal, N, SEGMENTS);
    WindowSpec spec;
    spec.frames = 2400;
    spec.spin_sensor = MOCAP_SEGMENT_HEAD;
    spec.spin_dps = 0.5; // 20 deg over 40 s: below the gyro limit, above the spread limit
    WindowResult r = run_window(rig, cal, spec);
    EXPECT_EQ(r.status, MOCAP_ERR_BAD_CALIBRATION);
    double sweep = 0.5 * (spec.frames - 1) / 60.0;
    EXPECT_NEAR(r.report.sensors[5].orientation_spread_deg, sweep / std::sqrt(12.0), 0.2);
    EXPECT_TRUE(contains(r.report.reason, "head: orientation spread 5.")) << r.report.reason;
    EXPECT_FALSE(contains(r.report.reason, "gyro")) << r.report.reason;
}

TEST(Calibration, HeadingResetUndoesYawDriftWithoutTouchingMounting)
{
    Rig rig(31, MOCAP_WORLD_ENU);
    static mocap_calibration cal;
    calibrate(rig, cal);
    static mocap_calibration before;
    before = cal;

    // The right shin's fusion drifts 25 deg in yaw: its world frame turns about up.
    const int drifted = MOCAP_SEGMENT_RIGHT_SHIN;
    double rz[9];
    mat3_rotation_z(rz, 25.0 * MOCAP_DEG2RAD);
    mat3_multiply(rig.world_from_room[drifted], rz, rig.world_from_room[drifted]);
    double deg, acc;
    evaluate(rig, cal, deg, acc, drifted);
    EXPECT_GT(deg, 20.0); // the drift is visible

    // Reset while standing facing forward; the head looks steeply down (its forward axis is
    // within 10 deg of vertical) to exercise the side-axis fallback.
    double pose[N][9];
    for (auto &m : pose)
        mat3_identity(m);
    mat3_rotation_x(pose[MOCAP_SEGMENT_HEAD], 80.0 * MOCAP_DEG2RAD);
    WindowSpec spec;
    spec.step = MOCAP_CALIBRATION_HEADING_RESET;
    spec.bones = pose;
    WindowResult r = run_window(rig, cal, spec);
    ASSERT_EQ(r.status, MOCAP_OK) << r.report.reason;

    evaluate(rig, cal, deg, acc);
    EXPECT_LT(deg, 0.25); // same bound as the full calibration: a reset adds one more mean
    EXPECT_LT(acc, 0.05);
    EXPECT_EQ(std::memcmp(cal.sensor_to_bone, before.sensor_to_bone, sizeof cal.sensor_to_bone), 0);
    EXPECT_EQ(std::memcmp(cal.acceleration_offset, before.acceleration_offset,
                          sizeof cal.acceleration_offset), 0);
    EXPECT_EQ(cal.valid_mask, before.valid_mask);
    // Only a yaw about model up changed: -25 deg on the drifted sensor, ~0 on the others.
    for (int s = 0; s < N; s++) {
        double a[9], b[9], rel[9];
        for (int i = 0; i < 9; i++) {
            a[i] = cal.world_to_model[s][i];
            b[i] = before.world_to_model[s][i];
        }
        mat3_multiply_transposed(rel, a, b); // a b^T: the pre-multiplied correction
        EXPECT_NEAR(rel[4], 1.0, 1e-5) << s; // leaves model Y alone
        double yaw = std::atan2(rel[2], rel[8]) * MOCAP_RAD2DEG;
        EXPECT_NEAR(yaw, s == drifted ? -25.0 : 0.0, 0.1) << s;
    }
}

TEST(Calibration, HeadingStepInvalidatesOldMounting)
{
    Rig rig(32, MOCAP_WORLD_NWU);
    static mocap_calibration cal;
    calibrate(rig, cal);
    WindowResult r = run_window(rig, cal, WindowSpec{});
    ASSERT_EQ(r.status, MOCAP_OK);
    EXPECT_EQ(cal.heading_mask, ALL);
    EXPECT_EQ(cal.valid_mask, 0u); // a T-pose is needed again
}

TEST(Calibration, ApplyFlagsAndUncalibratedPreview)
{
    for (int world : {MOCAP_WORLD_NWU, MOCAP_WORLD_ENU}) {
        static mocap_calibration cal;
        calib_identity(&cal, N, SEGMENTS);
        raw_frame f;
        std::memset(&f, 0, sizeof f);
        f.t = 1.5;
        f.sequence = 9;
        f.valid_mask = ALL & ~(1u << 5);       // head never produced data
        f.fresh_mask = ALL & ~(1u << 5) & ~(1u << 2); // right wrist held
        f.stale_mask = 1u << 5;
        for (int s = 0; s < N; s++) {
            // Lying flat, X pointing north: NWU north is +X, ENU north is +Y.
            double rz[9];
            mat3_rotation_z(rz, world == MOCAP_WORLD_ENU ? 0.5 * MOCAP_PI : 0.0);
            mat3_to_quat(f.quat[s], rz);
            f.force_world[s][2] = G;
            f.gyr[s][0] = 0.1 * s;
            f.age[s] = 0.01 * s;
            f.node_id[s] = 40 + s;
        }
        static mocap_frame out;
        calib_apply(&cal, world, 0, &f, &out);
        EXPECT_EQ(out.flags, 0u);
        EXPECT_EQ(out.fresh_mask, f.fresh_mask);
        EXPECT_EQ(out.sensors[0].flags, (uint32_t)MOCAP_SENSOR_VALID);
        EXPECT_EQ(out.sensors[2].flags, (uint32_t)(MOCAP_SENSOR_VALID | MOCAP_SENSOR_HELD));
        EXPECT_EQ(out.sensors[5].flags, (uint32_t)MOCAP_SENSOR_STALE);
        EXPECT_FLOAT_EQ(out.sensors[3].angular_rate[0], 0.3f);
        EXPECT_FLOAT_EQ(out.sensors[4].age_s, 0.04f);
        EXPECT_EQ(out.sensors[1].node_id, 41u);
        EXPECT_FLOAT_EQ(out.sensors[1].world_specific_force[2], (float)G);
        EXPECT_FLOAT_EQ(std::fabs(out.sensors[1].sensor_orientation[0]),
                        (float)std::fabs(f.quat[1][0]));
        for (int s = 0; s < 5; s++) {
            // Upright preview: sensor up -> model up, sensor X (north) -> model forward.
            double m[9];
            mat_from_quat_f(m, out.sensors[s].bone_orientation);
            EXPECT_NEAR(m[1], 1.0, 1e-6) << "sensor Y (west) -> model X (left), world " << world;
            EXPECT_NEAR(m[5], 1.0, 1e-6) << "sensor Z -> model Y, world " << world;
            EXPECT_NEAR(m[6], 1.0, 1e-6) << "sensor X -> model Z, world " << world;
            for (int i = 0; i < 3; i++)
                EXPECT_EQ(out.sensors[s].bone_acceleration[i], 0.0f);
        }
        // No data at all: identity.
        EXPECT_EQ(out.sensors[5].bone_orientation[0], 1.0f);
        EXPECT_EQ(out.sensors[5].bone_orientation[3], 0.0f);
        // Fresh and complete: the COMPLETE flag.
        f.valid_mask = f.fresh_mask = ALL;
        calib_apply(&cal, world, 0, &f, &out);
        EXPECT_EQ(out.flags, (uint32_t)MOCAP_FRAME_COMPLETE);
    }
}

TEST(Calibration, ProgressReport)
{
    static calib_accumulator acc;
    calib_init(&acc, N, SEGMENTS, 0);
    Rig rig(41, MOCAP_WORLD_NWU);
    calib_begin(&acc, MOCAP_CALIBRATION_TPOSE, 1.0, 2.0);
    mocap_calibration_report report;
    std::memset(&report, 0, sizeof report);
    calib_progress(&acc, 0.5, &report);
    EXPECT_EQ(report.state, MOCAP_CALIBRATION_WAITING);
    EXPECT_EQ(report.step, MOCAP_CALIBRATION_TPOSE);
    EXPECT_FLOAT_EQ(report.progress, 0.0f);
    EXPECT_NEAR(report.seconds_remaining, 2.5, 1e-6);

    double id[N][9], zero[N][3] = {};
    for (auto &m : id)
        mat3_identity(m);
    rig.set_time(0.0);
    int closed = 0;
    double t_half_checked = 0;
    for (int i = 0; !closed && i < 300; i++) {
        raw_frame f = rig.body_frame(id, zero, true);
        closed = calib_add_frame(&acc, &f);
        if (!closed) {
            calib_progress(&acc, f.t, &report);
            if (f.t >= 2.0 && t_half_checked == 0) {
                t_half_checked = f.t;
                EXPECT_EQ(report.state, MOCAP_CALIBRATION_COLLECTING);
                EXPECT_NEAR(report.progress, (f.t - 1.0) / 2.0, 1e-5);
                EXPECT_NEAR(report.seconds_remaining, 3.0 - f.t, 1e-5);
                EXPECT_GT(report.sensors[0].samples, 50u);
            }
        } else {
            EXPECT_NEAR(f.t, 3.0, 1.0 / 60.0 + 1e-9);
        }
    }
    EXPECT_TRUE(closed);
    EXPECT_GT(t_half_checked, 0.0);
    EXPECT_EQ(acc.frames, 121u); // frames from t = 1.0 to 3.0 at 60 Hz, both ends inside
    static mocap_calibration cal;
    calib_identity(&cal, N, SEGMENTS);
    calib_finish(&acc, &cal, &report); // refused: no heading
    mocap_calibration_report after = report;
    calib_progress(&acc, 10.0, &after);
    EXPECT_EQ(std::memcmp(&after, &report, sizeof report), 0); // the final report stands
    EXPECT_EQ(acc.step, -1);
}

namespace {

std::string read_text(const std::string &path)
{
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

void write_text(const std::string &path, const std::string &text)
{
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << text;
}

// Replace the first line starting with prefix by replacement ("" deletes it).
std::string replace_line(const std::string &text, const std::string &prefix,
                         const std::string &replacement, int *line_no = nullptr)
{
    std::istringstream in(text);
    std::string line, out;
    int n = 0;
    bool done = false;
    while (std::getline(in, line)) {
        n++;
        if (!done && line.compare(0, prefix.size(), prefix) == 0) {
            done = true;
            if (line_no)
                *line_no = n;
            if (!replacement.empty())
                out += replacement + "\n";
            continue;
        }
        out += line + "\n";
    }
    EXPECT_TRUE(done) << "no line starts with " << prefix;
    return out;
}

} // namespace


// Temporary files a save left in dir (saves write NAME.<pid>-<n>.tmp, then rename it).
static int temporaries_in(const std::filesystem::path &dir)
{
    int n = 0;
    for (const auto &e : std::filesystem::directory_iterator(dir))
        if (e.path().extension() == ".tmp") ++n;
    return n;
}

// The API allows saves from any thread: two threads saving to one path at once each replace
// the file with a complete calibration of their own, never a mix, and leave no temporary.
TEST(CalibrationFile, ConcurrentSavesToOnePathEachLandWhole)
{
    Rig rig_a(61, MOCAP_WORLD_ENU), rig_b(62, MOCAP_WORLD_NWU);
    static mocap_calibration a, b;
    calibrate(rig_a, a);
    calibrate(rig_b, b);
    ASSERT_NE(std::memcmp(a.world_to_model, b.world_to_model, sizeof a.world_to_model), 0);
    const std::string dir = test_temp_dir();
    const std::string path = dir + "/shared.calibration";
    std::atomic<int> failures{0};
    auto saver = [&](const mocap_calibration *cal) {
        for (int i = 0; i < 100; i++)
            if (calib_save(cal, path.c_str()) != MOCAP_OK) failures++;
    };
    std::thread ta(saver, &a), tb(saver, &b);
    ta.join();
    tb.join();
    EXPECT_EQ(failures.load(), 0);
    static mocap_calibration loaded;
    ASSERT_EQ(calib_load(path.c_str(), &loaded), MOCAP_OK) << mocap_last_error();
    const bool is_a = std::memcmp(loaded.world_to_model, a.world_to_model, sizeof a.world_to_model) == 0 &&
                      std::memcmp(loaded.sensor_to_bone, a.sensor_to_bone, sizeof a.sensor_to_bone) == 0;
    const bool is_b = std::memcmp(loaded.world_to_model, b.world_to_model, sizeof b.world_to_model) == 0 &&
                      std::memcmp(loaded.sensor_to_bone, b.sensor_to_bone, sizeof b.sensor_to_bone) == 0;
    EXPECT_TRUE(is_a || is_b);
    EXPECT_EQ(temporaries_in(dir), 0);
}

TEST(CalibrationFile, SaveLoadRoundTrip)
{
    Rig rig(51, MOCAP_WORLD_ENU);
    static mocap_calibration cal, loaded;
    calibrate(rig, cal);
    cal.valid_mask &= ~(1u << 3); // a partial calibration round-trips too
    std::string path = test_temp_path("cal.txt");
    ASSERT_EQ(calib_save(&cal, path.c_str()), MOCAP_OK) << mocap_last_error();
    std::memset(&loaded, 0xab, sizeof loaded);
    ASSERT_EQ(calib_load(path.c_str(), &loaded), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(loaded.struct_size, (uint32_t)sizeof loaded);
    EXPECT_EQ(loaded.valid_mask, cal.valid_mask);
    EXPECT_EQ(loaded.heading_mask, cal.heading_mask);
    for (int s = 0; s < N; s++) {
        for (int i = 0; i < 9; i++) {
            EXPECT_NEAR(loaded.world_to_model[s][i], cal.world_to_model[s][i], 1e-6);
            EXPECT_NEAR(loaded.sensor_to_bone[s][i], cal.sensor_to_bone[s][i], 1e-6);
        }
        for (int i = 0; i < 3; i++)
            EXPECT_NEAR(loaded.acceleration_offset[s][i], cal.acceleration_offset[s][i], 1e-6);
    }
    // %.9g round-trips floats bit for bit.
    EXPECT_EQ(std::memcmp(loaded.world_to_model, cal.world_to_model, sizeof cal.world_to_model), 0);
    EXPECT_EQ(loaded.sensor_count, (uint32_t)N);
    for (int s = 0; s < N; s++) EXPECT_EQ(loaded.segments[s], SEGMENTS[s]);
    std::string text = read_text(path);
    EXPECT_EQ(text.rfind("mocap-calibration 2\n", 0), 0u);
    EXPECT_NE(text.find("\nsensors pelvis left_wrist right_wrist left_shin right_shin head\n"),
              std::string::npos) << text;
    EXPECT_EQ(temporaries_in(std::filesystem::path(path).parent_path()), 0); // none left behind

    // Windows line endings, comments and blank lines are accepted.
    std::string crlf;
    for (char c : text) {
        if (c == '\n')
            crlf += "\r\n\r\n# note\r\n";
        else
            crlf += c;
    }
    write_text(path, crlf);
    static mocap_calibration again;
    ASSERT_EQ(calib_load(path.c_str(), &again), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(std::memcmp(&again, &loaded, sizeof again), 0);

    // Saving an identity calibration (what a fresh session holds) works as well.
    calib_identity(&cal, N, SEGMENTS);
    EXPECT_EQ(calib_save(&cal, path.c_str()), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(calib_load(path.c_str(), &again), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(again.valid_mask, 0u);
}

// A version-1 file (before sensor sets: no sensors line) still loads, as the six of the default
// set in segment order, with every value it holds.
TEST(CalibrationFile, VersionOneLoadsAsTheSix)
{
    Rig rig(54, MOCAP_WORLD_NWU);
    static mocap_calibration cal, loaded;
    calibrate(rig, cal);
    std::string path = test_temp_path("cal.txt");
    ASSERT_EQ(calib_save(&cal, path.c_str()), MOCAP_OK) << mocap_last_error();
    std::string v1 = replace_line(read_text(path), "mocap-calibration", "mocap-calibration 1");
    v1 = replace_line(v1, "sensors ", "");
    ASSERT_EQ(v1.find("sensors"), std::string::npos);
    std::string old = test_temp_path("old.txt");
    write_text(old, v1);
    std::memset(&loaded, 0x5c, sizeof loaded);
    ASSERT_EQ(calib_load(old.c_str(), &loaded), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(loaded.sensor_count, 6u);
    for (int s = 0; s < 6; s++) EXPECT_EQ(loaded.segments[s], s);
    EXPECT_EQ(loaded.valid_mask, 0x3fu);
    EXPECT_EQ(loaded.heading_mask, 0x3fu);
    EXPECT_EQ(std::memcmp(loaded.world_to_model, cal.world_to_model, 6 * sizeof cal.world_to_model[0]), 0);
    EXPECT_EQ(std::memcmp(loaded.sensor_to_bone, cal.sensor_to_bone, 6 * sizeof cal.sensor_to_bone[0]), 0);
    EXPECT_EQ(std::memcmp(loaded.acceleration_offset, cal.acceleration_offset,
                          6 * sizeof cal.acceleration_offset[0]), 0);
    // A version-1 file has no sensors line: one there is not a key it knows.
    std::string mixed = replace_line(read_text(path), "mocap-calibration", "mocap-calibration 1");
    write_text(old, mixed);
    EXPECT_EQ(calib_load(old.c_str(), &loaded), MOCAP_ERR_FORMAT);
    EXPECT_TRUE(contains(mocap_last_error(), "old.txt")) << mocap_last_error();
}

// Paths are UTF-8 (a user folder such as "Jürgen"); a save that cannot replace its target
// fails with a message naming it and leaves no temporary file behind.
TEST(CalibrationFile, Utf8PathsAndAFailedReplaceIsReported)
{
    Rig rig(52, MOCAP_WORLD_ENU);
    static mocap_calibration cal, loaded;
    calibrate(rig, cal);
    std::filesystem::path dir = std::filesystem::u8path(test_temp_path("J\xc3\xbcrgen M\xc3\xbcller"));
    std::filesystem::create_directories(dir);
    std::string path = (dir / "kalibrierung.txt").u8string();
    ASSERT_EQ(calib_save(&cal, path.c_str()), MOCAP_OK) << mocap_last_error();
    ASSERT_EQ(calib_load(path.c_str(), &loaded), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(std::memcmp(loaded.sensor_to_bone, cal.sensor_to_bone, sizeof cal.sensor_to_bone), 0);

    // The target is a folder: refused before anything is written, not written around.
    std::string blocked = (dir / "blocked").u8string();
    std::filesystem::create_directories(std::filesystem::u8path(blocked + "/inside"));
    EXPECT_EQ(calib_save(&cal, blocked.c_str()), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("not a regular file"), std::string::npos) << mocap_last_error();
    EXPECT_NE(std::string(mocap_last_error()).find("blocked"), std::string::npos) << mocap_last_error();
    EXPECT_EQ(temporaries_in(dir), 0);
    EXPECT_TRUE(std::filesystem::is_directory(std::filesystem::u8path(blocked + "/inside")));
}

#if !defined(_WIN32) // Windows: POSIX symlinks, FIFOs and /dev/null
// A save renames a temporary over its target: through a symbolic link it must replace the file
// the link points to (the link stays), and it must never replace a device or a pipe (as root,
// `--save-calibration /dev/full` turned /dev/full into a regular file).
TEST(CalibrationFile, SaveFollowsLinksAndNeverReplacesDevicesOrPipes)
{
    Rig rig(53, MOCAP_WORLD_NWU);
    static mocap_calibration cal, loaded;
    calibrate(rig, cal);
    const std::filesystem::path dir = test_temp_dir();
    const std::filesystem::path target = dir / "real.cal", link = dir / "link.cal";
    std::filesystem::create_symlink("real.cal", link);        // relative, dangling until saved
    EXPECT_NE(calib_save(&cal, link.c_str()), MOCAP_OK);       // a dangling link: nothing to resolve
    std::ofstream(target) << "old\n";
    ASSERT_EQ(calib_save(&cal, link.c_str()), MOCAP_OK) << mocap_last_error();
    EXPECT_TRUE(std::filesystem::is_symlink(link)) << "the link was replaced by a file";
    ASSERT_EQ(calib_load(target.c_str(), &loaded), MOCAP_OK) << mocap_last_error();
    EXPECT_EQ(std::memcmp(loaded.sensor_to_bone, cal.sensor_to_bone, sizeof cal.sensor_to_bone), 0);
    EXPECT_EQ(temporaries_in(dir), 0);

    const std::filesystem::path fifo = dir / "pipe.cal";
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    EXPECT_EQ(calib_save(&cal, fifo.c_str()), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("not a regular file"), std::string::npos) << mocap_last_error();
    EXPECT_TRUE(std::filesystem::is_fifo(fifo));
    if (access("/dev/full", W_OK) == 0) {
        EXPECT_EQ(calib_save(&cal, "/dev/full"), MOCAP_ERR_INVALID_ARGUMENT);
        EXPECT_TRUE(std::filesystem::is_character_file("/dev/full"));
    }
    EXPECT_EQ(temporaries_in(dir), 0);
}
#endif

TEST(CalibrationFile, CorruptFilesRejectedWithLineNumbers)
{
    Rig rig(52, MOCAP_WORLD_NWU);
    static mocap_calibration cal;
    calibrate(rig, cal);
    std::string path = test_temp_path("cal.txt");
    ASSERT_EQ(calib_save(&cal, path.c_str()), MOCAP_OK);
    const std::string good = read_text(path);
    std::string bad_path = test_temp_path("bad.txt");

    struct Case {
        std::string text;
        std::string expect1, expect2;
    };
    std::vector<Case> cases;
    cases.push_back({replace_line(good, "mocap-calibration", "mocap-calibration 3"), "line 1",
                     "version"});
    int sensors_line = 0;
    std::string t = replace_line(good, "sensors", "sensors pelvis left_wrist spine left_shin right_shin head",
                                 &sensors_line);
    cases.push_back({t, "line " + std::to_string(sensors_line), "spine"});
    t = replace_line(good, "sensors", "sensors pelvis left_wrist pelvis left_shin right_shin head");
    cases.push_back({t, "line " + std::to_string(sensors_line), "twice"});
    t = replace_line(good, "sensors", "");
    cases.push_back({t, "line " + std::to_string(sensors_line), "sensors"});
    cases.push_back({replace_line(good, "mocap-calibration", "hello world"), "line 1",
                     "not a calibration file"});
    int ln = 0;
    t = replace_line(good, "left_wrist.sensor_to_bone",
                                 "left_wrist.sensor_to_bone 1 0 0 0 nan 0 0 0 1", &ln);
    cases.push_back({t, "line " + std::to_string(ln), "left_wrist.sensor_to_bone"});
    t = replace_line(good, "head.acceleration_offset", "", &ln);
    cases.push_back({t, "missing", "head.acceleration_offset"});
    t = replace_line(good, "pelvis.world_to_model", "pelvis.world_to_model 1.1 0 0 0 1 0 0 0 1", &ln);
    cases.push_back({t, "line " + std::to_string(ln), "not a rotation"});
    t = replace_line(good, "pelvis.world_to_model", "pelvis.world_to_model -1 0 0 0 1 0 0 0 1", &ln);
    cases.push_back({t, "line " + std::to_string(ln), "not a rotation"}); // a reflection
    t = replace_line(good, "pelvis.world_to_model", "pelvis.world_to_model 1 0 0 0 1 0 0 0 1 5", &ln);
    cases.push_back({t, "line " + std::to_string(ln), "9 finite numbers"});
    t = replace_line(good, "pelvis.world_to_model", "pelvis.world_to_model 1 0 0 0 1 0 0 0", &ln);
    cases.push_back({t, "line " + std::to_string(ln), "9 finite numbers"});
    // Finite as a double, infinite as the float it is stored in (found by the fuzzer).
    t = replace_line(good, "right_wrist.acceleration_offset",
                     "right_wrist.acceleration_offset -7.7e39 9.8 0", &ln);
    cases.push_back({t, "line " + std::to_string(ln), "3 finite numbers"});
    t = replace_line(good, "valid_mask", "valid_mask 64", &ln);
    cases.push_back({t, "line " + std::to_string(ln), "valid_mask"});
    t = replace_line(good, "heading_mask", "heading_mask 63\nwhatever 1", &ln);
    cases.push_back({t, "line " + std::to_string(ln + 1), "unknown key"});
    t = replace_line(good, "heading_mask", "heading_mask 63\nheading_mask 63", &ln);
    cases.push_back({t, "line " + std::to_string(ln + 1), "repeated"});
    t = replace_line(good, "heading_mask", "heading_mask 1", &ln);
    cases.push_back({t, "valid_mask", "without a heading"});
    cases.push_back({"", "line 1", "empty"});

    for (size_t i = 0; i < cases.size(); i++) {
        write_text(bad_path, cases[i].text);
        static mocap_calibration out;
        std::memset(&out, 0x5c, sizeof out);
        static mocap_calibration sentinel;
        sentinel = out;
        mocap_clear_error();
        EXPECT_EQ(calib_load(bad_path.c_str(), &out), MOCAP_ERR_FORMAT) << "case " << i;
        const char *msg = mocap_last_error();
        EXPECT_TRUE(contains(msg, cases[i].expect1.c_str())) << "case " << i << ": " << msg;
        EXPECT_TRUE(contains(msg, cases[i].expect2.c_str())) << "case " << i << ": " << msg;
        EXPECT_TRUE(contains(msg, "bad.txt")) << "case " << i << ": " << msg;
        EXPECT_EQ(std::memcmp(&out, &sentinel, sizeof out), 0) << "case " << i;
    }

    static mocap_calibration out;
    EXPECT_EQ(calib_load(test_temp_path("does-not-exist.txt").c_str(), &out), MOCAP_ERR_NOT_FOUND);
    EXPECT_TRUE(contains(mocap_last_error(), "does-not-exist.txt"));
    // Saving into a missing directory fails cleanly too.
    EXPECT_EQ(calib_save(&cal, (test_temp_path("no-dir") + "/x/cal.txt").c_str()),
              MOCAP_ERR_NOT_FOUND);
    // A calibration that is not made of rotations is not written.
    cal.sensor_to_bone[2][0] = 3.0f;
    EXPECT_EQ(calib_save(&cal, path.c_str()), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_TRUE(contains(mocap_last_error(), "right_wrist.sensor_to_bone"));
}
