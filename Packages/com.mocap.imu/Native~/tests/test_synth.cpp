// Synthetic capture generator: decoded streams against the truth and setup rotations, world
// frame conventions, determinism, faults, trajectory files, the built-in motions' kinematics,
// capture/truth files, and the corrupted-stream acceptance test (real decoder, no fakes).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "capture_file.h"
#include "hipnuc_decoder.h"
#include "mocap_math.h"
#include "synth.h"
#include "test_support.h"

namespace {

// The default sensor set: six sensors, sensor i on segment i.
constexpr int kSensors = 6;
// Every segment of the table (the built-in motions move them all; the chest is the seventh).
constexpr int kSegments = 7;

using Bytes = std::vector<uint8_t>;
constexpr double kG = MOCAP_STANDARD_GRAVITY;

struct Packet {
    synth_packet_info info;
    Bytes bytes;
    synth_pose truth;
};

struct Stream {
    std::vector<Packet> packets;
    Bytes bytes;
};

int collect_packet(void *user, const synth_packet_info *info, const uint8_t *bytes,
                   const synth_pose *truth)
{
    auto *s = static_cast<Stream *>(user);
    Packet p;
    p.info = *info;
    if (bytes) p.bytes.assign(bytes, bytes + info->length);
    p.truth = *truth;
    s->bytes.insert(s->bytes.end(), p.bytes.begin(), p.bytes.end());
    s->packets.push_back(std::move(p));
    return 0;
}

Stream generate(const synth_config &cfg, synth_motion_fn motion = nullptr, void *user = nullptr)
{
    Stream s;
    mocap_status st = synth_generate(&cfg, motion, user, collect_packet, &s);
    EXPECT_EQ(st, MOCAP_OK) << mocap_last_error();
    return s;
}

struct Decoded {
    uint8_t gateway_id;
    std::vector<hipnuc_sample> samples;
};

struct DecodeResult {
    std::vector<Decoded> frames;
    hipnuc_stats stats;
};

void on_frame(void *user, const hipnuc_frame *f)
{
    auto *out = static_cast<std::vector<Decoded> *>(user);
    Decoded d;
    d.gateway_id = f->gateway_id;
    d.samples.assign(f->samples, f->samples + f->sample_count);
    out->push_back(std::move(d));
}

// Feeds the bytes in random-sized chunks. pad_end appends zeros so that a candidate frame
// waiting for bytes at the very end (a corrupted length) is resolved, as more input would.
DecodeResult decode(const Bytes &bytes, uint32_t chunk_seed = 1, bool pad_end = false)
{
    DecodeResult r;
    auto dec = std::make_unique<hipnuc_decoder>();
    hipnuc_decoder_init(dec.get(), HIPNUC_LAYOUT_NODE_ID);
    std::mt19937 rng(chunk_seed);
    std::uniform_int_distribution<size_t> size(1, 700);
    size_t i = 0;
    while (i < bytes.size()) {
        size_t n = std::min(size(rng), bytes.size() - i);
        hipnuc_decoder_feed(dec.get(), bytes.data() + i, n, on_frame, &r.frames);
        i += n;
    }
    if (pad_end) {
        Bytes zeros(HIPNUC_HEADER_SIZE + HIPNUC_MAX_PAYLOAD, 0);
        hipnuc_decoder_feed(dec.get(), zeros.data(), zeros.size(), on_frame, &r.frames);
    }
    r.stats = dec->stats;
    return r;
}

synth_config short_config()
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.heading_s = 1.0;
    cfg.strap_s = 1.0;
    cfg.tpose_s = 1.0;
    cfg.motion_s = 4.0;
    const int ids[kSensors] = {7, 3, 12, 40, 41, 200};
    for (int i = 0; i < kSensors; i++) cfg.node_ids[i] = ids[i];
    cfg.gateway_id = 9;
    return cfg;
}

int popcount(uint32_t m)
{
    int n = 0;
    for (; m; m &= m - 1) n++;
    return n;
}

// Matrices and quaternions (double) through the engine's maths.
struct Mat { double m[9]; };

Mat mat_of_quat(const double q[4])
{
    Mat r;
    quat_to_mat3(r.m, q);
    return r;
}

Mat mul(const Mat &a, const Mat &b)
{
    Mat r;
    mat3_multiply(r.m, a.m, b.m);
    return r;
}

Mat mul_t(const Mat &a, const Mat &b)
{
    Mat r;
    mat3_multiply_transposed(r.m, a.m, b.m);
    return r;
}

void apply(double out[3], const Mat &m, const double v[3]) { mat3_apply(out, m.m, v); }

double dist3(const double a[3], const double b[3])
{
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                     (a[2] - b[2]) * (a[2] - b[2]));
}

double norm3(const double a[3]) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

void rotvec(double out[3], const double q[4])
{
    double w = q[0], v[3] = {q[1], q[2], q[3]};
    if (w < 0) { w = -w; for (double &x : v) x = -x; }
    double s = norm3(v);
    double k = s < 1e-15 ? 2.0 : 2.0 * std::atan2(s, w) / s;
    for (int i = 0; i < 3; i++) out[i] = v[i] * k;
}

// Model-frame angular velocity by a central difference of orientations.
void fd_omega(double out[3], const double qa[4], const double qb[4], double dt)
{
    double ac[4], d[4];
    quat_conjugate(ac, qa);
    quat_multiply(d, qb, ac);
    rotvec(out, d);
    for (int i = 0; i < 3; i++) out[i] /= dt;
}

// What a calibrated pipeline recovers from one decoded sample, given the true setup.
struct ModelSample {
    Mat model_sensor;
    Mat model_bone;
    double accel[3];   // linear acceleration, model frame, m/s^2
    double omega[3];   // angular velocity, model frame, rad/s
};

ModelSample to_model(const hipnuc_sample &s, const double w2m[9], const double s2b[9])
{
    ModelSample r;
    double q[4] = {s.quat[0], s.quat[1], s.quat[2], s.quat[3]};
    Mat ws = mat_of_quat(q), m2w, sb;
    std::memcpy(m2w.m, w2m, sizeof m2w.m);
    std::memcpy(sb.m, s2b, sizeof sb.m);
    r.model_sensor = mul(m2w, ws);
    r.model_bone = mul_t(r.model_sensor, sb);
    double f[3] = {s.acc_g[0] * kG, s.acc_g[1] * kG, s.acc_g[2] * kG}, fm[3];
    apply(fm, r.model_sensor, f);
    r.accel[0] = fm[0];
    r.accel[1] = fm[1] - kG; // model Y is up
    r.accel[2] = fm[2];
    double w[3] = {s.gyr_dps[0] * MOCAP_DEG2RAD, s.gyr_dps[1] * MOCAP_DEG2RAD,
                   s.gyr_dps[2] * MOCAP_DEG2RAD};
    apply(r.omega, r.model_sensor, w);
    return r;
}

double mat_angle_to_quat_deg(const Mat &m, const double q[4])
{
    Mat t = mat_of_quat(q);
    return mat3_angle_deg(m.m, t.m);
}

double motion_duration(synth_motion_fn fn, void *user = nullptr)
{
    synth_pose p;
    double lo = 0.0, hi = 0.0;
    while (fn(user, hi, &p) == 0) { lo = hi; hi += 0.5; if (hi > 1000) return -1; }
    for (int i = 0; i < 60; i++) {
        double mid = 0.5 * (lo + hi);
        if (fn(user, mid, &p) == 0) lo = mid; else hi = mid;
    }
    return lo;
}

const char *const kMotions[] = {"walk", "arms", "squat", "turn", "mixed"};

// ------------------------------------------------------------------------------------------
TEST(Synth, StreamDecodesToEveryPacketWithTheConfiguredNodes)
{
    synth_config cfg = short_config();
    cfg.start_sensor_ms = 0xFFFFFFFFu - 2500u; // the sensor clock wraps mid-stream
    Stream s = generate(cfg);
    ASSERT_EQ(s.packets.size(), 701u); // 0 .. 7 s at 100 Hz, both ends included
    DecodeResult d = decode(s.bytes);
    ASSERT_EQ(d.frames.size(), s.packets.size());
    EXPECT_EQ(d.stats.crc_failures, 0u);
    EXPECT_EQ(d.stats.bytes_skipped, 0u);
    EXPECT_EQ(d.stats.bytes_in, s.bytes.size());

    size_t offset = 0;
    bool wrapped = false;
    for (size_t k = 0; k < s.packets.size(); k++) {
        const Packet &p = s.packets[k];
        EXPECT_EQ(p.info.index, k);
        EXPECT_EQ(p.info.offset, offset);
        EXPECT_EQ(p.info.length, p.bytes.size());
        EXPECT_EQ(p.info.length, HIPNUC_HEADER_SIZE + HIPNUC_GWSOL_HEADER_SIZE +
                                     kSensors * HIPNUC_IMUSOL_SIZE);
        EXPECT_EQ(p.info.intact, 1);
        EXPECT_EQ(p.info.dropped, 0);
        EXPECT_EQ(p.info.node_mask, 0x3Fu);
        EXPECT_DOUBLE_EQ(p.info.t, k / 100.0);
        EXPECT_EQ(p.info.receive_ns, cfg.start_receive_ns + (int64_t)llround(k * 1e7));
        int phase = p.info.t < 1.0 ? 0 : p.info.t < 2.0 ? 1 : p.info.t < 3.0 ? 2 : 3;
        EXPECT_EQ(p.info.phase, phase) << "t=" << p.info.t;
        offset += p.info.length;

        const Decoded &f = d.frames[k];
        EXPECT_EQ(f.gateway_id, 9);
        ASSERT_EQ(f.samples.size(), 6u);
        uint32_t expect_ms = cfg.start_sensor_ms + (uint32_t)(k * 10);
        for (int i = 0; i < kSensors; i++) {
            EXPECT_EQ(f.samples[i].node_id, (uint32_t)cfg.node_ids[i]);
            EXPECT_EQ(f.samples[i].time_ms, expect_ms);
        }
        wrapped |= expect_ms < cfg.start_sensor_ms;
    }
    EXPECT_TRUE(wrapped);
}

// Noise-free, so decoded values must equal the truth up to float rounding. With tremor the
// T-pose sways (and its truth with it), and the sensors lying for the heading step sway too.
void check_decoded_against_truth(double tremor_deg)
{
    synth_config cfg = short_config();
    cfg.motion_s = 30.0; // the whole mixed motion
    cfg.still_tremor_deg = tremor_deg;
    Stream s = generate(cfg);
    double w2m[MOCAP_MAX_SENSORS][9], s2b[MOCAP_MAX_SENSORS][9], a[9];
    synth_setup_rotations(&cfg, w2m, s2b);
    mocap_world_zup_to_model(a);
    Mat heading;
    std::memcpy(heading.m, a, sizeof a);
    DecodeResult d = decode(s.bytes, 7);
    ASSERT_EQ(d.frames.size(), s.packets.size());

    double worst_bone = 0, worst_acc = 0, worst_gyr = 0, max_acc = 0, max_gyr = 0;
    int phases_seen = 0;
    double max_tpose_sway = 0;
    const double identity[4] = {1, 0, 0, 0};
    for (size_t k = 0; k < s.packets.size(); k++) {
        const Packet &p = s.packets[k];
        phases_seen |= 1 << p.info.phase;
        for (int i = 0; i < kSensors; i++) {
            const hipnuc_sample &smp = d.frames[k].samples[i];
            ModelSample m = to_model(smp, w2m[i], s2b[i]);
            // Euler angles and magnetic field are consistent with the quaternion.
            double qe[4], qs[4] = {smp.quat[0], smp.quat[1], smp.quat[2], smp.quat[3]};
            quat_from_euler_zyx(qe, smp.euler_deg[0] * MOCAP_DEG2RAD,
                                smp.euler_deg[1] * MOCAP_DEG2RAD, smp.euler_deg[2] * MOCAP_DEG2RAD);
            EXPECT_LT(quat_angle_deg(qe, qs), 1e-3);
            double mag[3] = {smp.mag_ut[0], smp.mag_ut[1], smp.mag_ut[2]};
            EXPECT_NEAR(norm3(mag), std::sqrt(20.0 * 20.0 + 44.0 * 44.0), 1e-4);

            if (p.info.phase == 2)
                max_tpose_sway = std::max(max_tpose_sway, quat_angle_deg(p.truth.bone_quat[i], identity));
            if (p.info.phase == 0 && tremor_deg == 0) {
                // Lying still, X forward, Z up: the sensor frame is the heading frame.
                EXPECT_LT(mat3_angle_deg(m.model_sensor.m, heading.m), 1e-4);
                EXPECT_NEAR(smp.acc_g[2], 1.0, 1e-6);
                EXPECT_NEAR(std::hypot(smp.acc_g[0], smp.acc_g[1]), 0.0, 1e-6);
                EXPECT_NEAR(norm3(m.omega), 0.0, 1e-6);
            }
            if (p.info.phase < 2) continue;
            worst_bone = std::max(worst_bone, mat_angle_to_quat_deg(m.model_bone, p.truth.bone_quat[i]));
            double acc_tol = 2e-6 * (norm3(p.truth.accel[i]) + kG);
            double e = dist3(m.accel, p.truth.accel[i]);
            EXPECT_LT(e, acc_tol) << "packet " << k << " segment " << i;
            worst_acc = std::max(worst_acc, e);
            max_acc = std::max(max_acc, norm3(p.truth.accel[i]));
            double g = dist3(m.omega, p.truth.angular_velocity[i]);
            EXPECT_LT(g, 1e-6 * (1.0 + norm3(p.truth.angular_velocity[i])));
            worst_gyr = std::max(worst_gyr, g);
            max_gyr = std::max(max_gyr, norm3(p.truth.angular_velocity[i]));
        }
    }
    EXPECT_EQ(phases_seen, 0xF);
    EXPECT_LT(worst_bone, 1e-4); // float quaternions: ~1e-7 rad
    // The comparison is only meaningful if the motion really moves.
    EXPECT_GT(max_acc, 5.0);
    EXPECT_GT(max_gyr, 3.0);
    if (tremor_deg == 0) {
        EXPECT_EQ(max_tpose_sway, 0.0);
    } else {
        EXPECT_GT(max_tpose_sway, 0.3 * tremor_deg);
        EXPECT_LT(max_tpose_sway, 2.0 * tremor_deg);
    }
    ::testing::Test::RecordProperty("worst_acc_error", std::to_string(worst_acc));
    ::testing::Test::RecordProperty("worst_gyr_error", std::to_string(worst_gyr));
}

TEST(Synth, DecodedValuesMatchTruthThroughTheSetupRotations) { check_decoded_against_truth(0.0); }
TEST(Synth, DecodedValuesMatchTruthWithTremor) { check_decoded_against_truth(0.5); }


TEST(Synth, NwuAndEnuGiveTheSameModelFrameTruth)
{
    synth_config nwu = short_config();
    nwu.heading_spread_deg = 0.0;
    nwu.facing_azimuth_deg = 30.0;
    synth_config enu = nwu;
    enu.world_frame = MOCAP_WORLD_ENU;

    double w2m_n[MOCAP_MAX_SENSORS][9], w2m_e[MOCAP_MAX_SENSORS][9];
    double s2b_n[MOCAP_MAX_SENSORS][9], s2b_e[MOCAP_MAX_SENSORS][9];
    synth_setup_rotations(&nwu, w2m_n, s2b_n);
    synth_setup_rotations(&enu, w2m_e, s2b_e);
    const double fwd[3] = {0, 0, 1}, up[3] = {0, 1, 0};
    const double s30 = std::sin(30 * MOCAP_DEG2RAD), c30 = std::cos(30 * MOCAP_DEG2RAD);
    for (int i = 0; i < kSensors; i++) {
        Mat wn, we;
        mat3_transpose(wn.m, w2m_n[i]);
        mat3_transpose(we.m, w2m_e[i]);
        double fn[3], fe[3], un[3], ue[3];
        apply(fn, wn, fwd);
        apply(fe, we, fwd);
        apply(un, wn, up);
        // Forward is 30 deg east of north: NWU (north, west, up), ENU (east, north, up).
        EXPECT_NEAR(fn[0], c30, 1e-12);
        EXPECT_NEAR(fn[1], -s30, 1e-12);
        EXPECT_NEAR(fe[0], s30, 1e-12);
        EXPECT_NEAR(fe[1], c30, 1e-12);
        EXPECT_NEAR(un[2], 1.0, 1e-12);
        apply(ue, we, up);
        EXPECT_NEAR(ue[2], 1.0, 1e-12);
        for (int k = 0; k < 9; k++) EXPECT_EQ(s2b_n[i][k], s2b_e[i][k]);
    }

    // With a random per-sensor heading, both streams still describe the same motion.
    nwu.heading_spread_deg = enu.heading_spread_deg = 180.0;
    synth_setup_rotations(&nwu, w2m_n, s2b_n);
    synth_setup_rotations(&enu, w2m_e, s2b_e);
    Stream sn = generate(nwu), se = generate(enu);
    ASSERT_EQ(sn.packets.size(), se.packets.size());
    EXPECT_NE(sn.bytes, se.bytes);
    DecodeResult dn = decode(sn.bytes), de = decode(se.bytes);
    ASSERT_EQ(dn.frames.size(), sn.packets.size());
    ASSERT_EQ(de.frames.size(), se.packets.size());
    for (size_t k = 0; k < sn.packets.size(); k++) {
        for (int i = 0; i < kSensors; i++) {
            for (int c = 0; c < 4; c++)
                ASSERT_EQ(sn.packets[k].truth.bone_quat[i][c], se.packets[k].truth.bone_quat[i][c]);
            ModelSample a = to_model(dn.frames[k].samples[i], w2m_n[i], s2b_n[i]);
            ModelSample b = to_model(de.frames[k].samples[i], w2m_e[i], s2b_e[i]);
            EXPECT_LT(mat3_angle_deg(a.model_bone.m, b.model_bone.m), 1e-4);
            EXPECT_LT(dist3(a.accel, b.accel), 1e-4);
        }
    }
}

TEST(Synth, SameSeedSameBytesOtherSeedOtherSetup)
{
    synth_config cfg = short_config();
    cfg.acc_noise_g = 0.01;
    cfg.gyr_noise_dps = 0.5;
    cfg.quat_noise_deg = 0.2;
    cfg.acc_bias_g = 0.02;
    cfg.still_tremor_deg = 0.5;
    cfg.node_dropout_prob = 0.05;
    Stream a = generate(cfg), b = generate(cfg);
    EXPECT_EQ(a.bytes, b.bytes);
    ASSERT_FALSE(a.bytes.empty());

    synth_config other = cfg;
    other.seed = cfg.seed + 1;
    Stream c = generate(other);
    EXPECT_NE(a.bytes, c.bytes);
    double s2b_a[MOCAP_MAX_SENSORS][9], s2b_c[MOCAP_MAX_SENSORS][9];
    double w2m_a[MOCAP_MAX_SENSORS][9], w2m_c[MOCAP_MAX_SENSORS][9];
    synth_setup_rotations(&cfg, w2m_a, s2b_a);
    synth_setup_rotations(&other, w2m_c, s2b_c);
    for (int i = 0; i < kSensors; i++) {
        EXPECT_GT(mat3_angle_deg(s2b_a[i], s2b_c[i]), 1.0) << "segment " << i;
        EXPECT_GT(mat3_angle_deg(w2m_a[i], w2m_c[i]), 0.01) << "segment " << i;
    }
    // Noise settings use their own random stream: the setup does not move with them.
    synth_config quiet = cfg;
    quiet.acc_noise_g = quiet.gyr_noise_dps = quiet.quat_noise_deg = 0.0;
    double s2b_q[MOCAP_MAX_SENSORS][9];
    synth_setup_rotations(&quiet, nullptr, s2b_q);
    for (int i = 0; i < kSensors; i++)
        for (int k = 0; k < 9; k++) EXPECT_EQ(s2b_q[i][k], s2b_a[i][k]);

    synth_config fixed = cfg;
    fixed.random_mounting = 0;
    double s2b_f[MOCAP_MAX_SENSORS][9], id[9];
    mat3_identity(id);
    synth_setup_rotations(&fixed, nullptr, s2b_f);
    for (int i = 0; i < kSensors; i++) EXPECT_LT(mat3_angle_deg(s2b_f[i], id), 1e-9);
}

TEST(Synth, NodeAndPacketDropoutsAreReportedAndDecodedAsSuch)
{
    synth_config cfg = short_config();
    cfg.node_dropout_prob = 0.1;
    Stream s = generate(cfg);
    DecodeResult d = decode(s.bytes);
    ASSERT_EQ(d.frames.size(), s.packets.size());
    int five = 0;
    for (size_t k = 0; k < s.packets.size(); k++) {
        uint32_t mask = s.packets[k].info.node_mask;
        ASSERT_EQ(d.frames[k].samples.size(), (size_t)popcount(mask));
        five += popcount(mask) == 5;
        size_t j = 0;
        for (int i = 0; i < kSensors; i++)
            if (mask & (1u << i)) { EXPECT_EQ(d.frames[k].samples[j++].node_id, (uint32_t)cfg.node_ids[i]); }
    }
    EXPECT_GT(five, 100); // ~35% of 801 packets miss exactly one node

    cfg.node_dropout_prob = 0.0;
    cfg.packet_dropout_prob = 0.05;
    s = generate(cfg);
    d = decode(s.bytes);
    std::vector<uint32_t> expect_ms;
    size_t dropped = 0;
    for (const Packet &p : s.packets) {
        if (p.info.dropped) {
            dropped++;
            EXPECT_EQ(p.info.length, 0u);
            EXPECT_TRUE(p.bytes.empty());
            continue;
        }
        expect_ms.push_back(cfg.start_sensor_ms + (uint32_t)llround(p.info.t * 1000));
    }
    EXPECT_GT(dropped, 10u);
    EXPECT_LT(dropped, 80u);
    ASSERT_EQ(d.frames.size(), expect_ms.size());
    for (size_t k = 0; k < expect_ms.size(); k++) {
        ASSERT_EQ(d.frames[k].samples.size(), 6u);
        EXPECT_EQ(d.frames[k].samples[0].time_ms, expect_ms[k]);
    }
}

TEST(Synth, RejectsBadConfigs)
{
    synth_config cfg = short_config();
    Stream s;
    cfg.rate_hz = 0;
    EXPECT_EQ(synth_generate(&cfg, nullptr, nullptr, collect_packet, &s), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("rate_hz"), std::string::npos);
    cfg = short_config();
    cfg.node_ids[4] = cfg.node_ids[1];
    EXPECT_EQ(synth_generate(&cfg, nullptr, nullptr, collect_packet, &s), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("node id 3"), std::string::npos);
    cfg = short_config();
    cfg.corrupt_byte_prob = 1.5;
    EXPECT_EQ(synth_generate(&cfg, nullptr, nullptr, collect_packet, &s), MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_TRUE(s.packets.empty());
    EXPECT_EQ(synth_builtin_motion("moonwalk"), nullptr);
    EXPECT_DOUBLE_EQ(synth_session_time(&cfg, 2.5), cfg.start_receive_ns / 1e9 + 2.5);
}

// ------------------------------------------------------------------------------------------
// Built-in motions

TEST(SynthMotions, StartAndEndInTPoseAtRest)
{
    for (const char *name : kMotions) {
        synth_motion_fn fn = synth_builtin_motion(name);
        ASSERT_NE(fn, nullptr) << name;
        double end = motion_duration(fn);
        EXPECT_GT(end, 4.0) << name;
        synth_pose p0, p1, past;
        ASSERT_EQ(fn(nullptr, 0.0, &p0), 0);
        ASSERT_EQ(fn(nullptr, end, &p1), 0);
        EXPECT_EQ(fn(nullptr, end + 0.01, &past), -1);
        const double id[4] = {1, 0, 0, 0};
        for (int i = 0; i < kSegments; i++) {
            for (const synth_pose *p : {&p0, &p1}) {
                EXPECT_LT(quat_angle_deg(p->bone_quat[i], id), 1e-6) << name << " segment " << i;
                EXPECT_LT(norm3(p->accel[i]), 1e-9) << name;
                EXPECT_LT(norm3(p->angular_velocity[i]), 1e-9) << name;
            }
        }
    }
    EXPECT_EQ(synth_builtin_motion(nullptr), synth_builtin_motion("mixed"));
}

TEST(SynthMotions, AngularVelocityIsTheDerivativeOfOrientation)
{
    const double h = 1e-5;
    for (const char *name : kMotions) {
        synth_motion_fn fn = synth_builtin_motion(name);
        double end = motion_duration(fn);
        double max_omega = 0;
        for (double t = h; t < end - h; t += 0.037) {
            synth_pose a, b, c;
            ASSERT_EQ(fn(nullptr, t - h, &a), 0);
            ASSERT_EQ(fn(nullptr, t, &b), 0);
            ASSERT_EQ(fn(nullptr, t + h, &c), 0);
            for (int i = 0; i < kSegments; i++) {
                double w[3];
                fd_omega(w, a.bone_quat[i], c.bone_quat[i], 2 * h);
                double scale = 1.0 + norm3(b.angular_velocity[i]);
                EXPECT_LT(dist3(w, b.angular_velocity[i]), 1e-5 * scale)
                    << name << " t=" << t << " segment " << i;
                max_omega = std::max(max_omega, norm3(b.angular_velocity[i]));
            }
        }
        EXPECT_GT(max_omega, 1.0) << name;
        EXPECT_LT(max_omega, 20.0) << name; // human, not a propeller
    }
}

// The motion is not exposed as positions, but starting and ending at rest in a T-pose pins down
// what the accelerations must integrate to: zero velocity at the end, and every sensor carried
// by the same rigid translation (x(T) - x(0) = integral of (T - s) a(s) ds, with v(0) = 0).
// Trapezoid sums at steps h and 2h, Richardson-combined: the fades make the jerk kink, which
// limits a plain trapezoid rule to O(h^2).
TEST(SynthMotions, AccelerationsIntegrateToOneRigidDisplacement)
{
    for (const char *name : kMotions) {
        synth_motion_fn fn = synth_builtin_motion(name);
        double end = motion_duration(fn);
        const int n = 2 * (int)std::ceil(end / 0.002);
        const double h = end / n;
        double vel[2][kSegments][3] = {}, disp[2][kSegments][3] = {}, prev[kSegments][3] = {};
        double max_jump = 0, peak = 0;
        for (int k = 0; k <= n; k++) {
            double t = k * h;
            double w1 = (k == 0 || k == n) ? 0.5 * h : h;
            double w2 = (k % 2) ? 0.0 : 2.0 * w1;
            synth_pose p;
            ASSERT_EQ(fn(nullptr, t, &p), 0);
            for (int i = 0; i < kSegments; i++) {
                for (int c = 0; c < 3; c++) {
                    ASSERT_TRUE(std::isfinite(p.accel[i][c]));
                    vel[0][i][c] += w1 * p.accel[i][c];
                    vel[1][i][c] += w2 * p.accel[i][c];
                    disp[0][i][c] += w1 * (end - t) * p.accel[i][c];
                    disp[1][i][c] += w2 * (end - t) * p.accel[i][c];
                }
                if (k > 0) max_jump = std::max(max_jump, dist3(p.accel[i], prev[i]));
                peak = std::max(peak, norm3(p.accel[i]));
                std::memcpy(prev[i], p.accel[i], sizeof prev[i]);
            }
        }
        double v[kSegments][3], d[kSegments][3];
        for (int i = 0; i < kSegments; i++)
            for (int c = 0; c < 3; c++) {
                v[i][c] = (4.0 * vel[0][i][c] - vel[1][i][c]) / 3.0;
                d[i][c] = (4.0 * disp[0][i][c] - disp[1][i][c]) / 3.0;
            }
        EXPECT_GT(peak, 1.0) << name;
        EXPECT_LT(peak, 60.0) << name;
        // Smooth: over 1 ms no sensor's acceleration changes by more than 0.5 m/s^2 (500 m/s^3).
        EXPECT_LT(max_jump, 0.5) << name;
        for (int i = 0; i < kSegments; i++) {
            EXPECT_LT(norm3(v[i]), 1e-6) << name << " segment " << i;
            EXPECT_LT(dist3(d[i], d[0]), 1e-5) << name << " segment " << i;
            EXPECT_NEAR(d[i][1], 0.0, 1e-5) << name << " segment " << i;
        }
        if (std::string(name) == "walk") { EXPECT_GT(d[0][2], 4.0); } // walked forward
        if (std::string(name) == "turn") { EXPECT_LT(norm3(d[0]), 1e-5); } // turned in place
        RecordProperty(std::string(name) + "_max_jump", std::to_string(max_jump));
    }
}

TEST(SynthMotions, WalkVerticalAccelerationHasZeroMeanOverACycle)
{
    synth_motion_fn fn = synth_builtin_motion("walk");
    // Steady walking lies between the fades (1 s in, 1 s out of a 6 s walk); a stride lasts
    // 1 / 0.9 s (checked below: the pose repeats one stride later).
    const double t0 = 1.5, cycle = 1.0 / 0.9;
    const int n = 2000;
    double sum[kSegments] = {}, sq[kSegments] = {};
    for (int k = 0; k <= n; k++) {
        synth_pose p;
        double t = t0 + cycle * k / n, wgt = (k == 0 || k == n) ? 0.5 : 1.0;
        ASSERT_EQ(fn(nullptr, t, &p), 0);
        for (int i = 0; i < kSegments; i++) {
            sum[i] += wgt * p.accel[i][1] / n;
            sq[i] += wgt * p.accel[i][1] * p.accel[i][1] / n;
        }
    }
    for (int i = 0; i < kSegments; i++) {
        EXPECT_NEAR(sum[i], 0.0, 1e-6) << "segment " << i;
        EXPECT_GT(std::sqrt(sq[i]), 0.1) << "segment " << i; // there is vertical motion
    }
    // And the cycle really is periodic: the pose repeats one stride later.
    synth_pose a, b;
    fn(nullptr, 2.0, &a);
    fn(nullptr, 2.0 + cycle, &b);
    for (int i = 0; i < kSegments; i++) {
        EXPECT_LT(quat_angle_deg(a.bone_quat[i], b.bone_quat[i]), 1e-6);
        EXPECT_LT(dist3(a.accel[i], b.accel[i]), 1e-9);
    }
}

// ------------------------------------------------------------------------------------------
// Trajectory files

void write_trajectory(const std::string &path, synth_motion_fn fn, double rate, double t_offset)
{
    std::ofstream out(path);
    out << "# synthetic walk\n\n";
    double end = motion_duration(fn);
    int n = (int)std::floor(end * rate);
    char buf[64];
    for (int k = 0; k <= n; k++) {
        synth_pose p;
        double t = k / rate;
        fn(nullptr, t, &p);
        std::snprintf(buf, sizeof buf, "%.17g", t + t_offset);
        out << buf;
        for (int i = 0; i < kSensors; i++) {
            for (int c = 0; c < 4; c++) { std::snprintf(buf, sizeof buf, " %.17g", p.bone_quat[i][c]); out << buf; }
            for (int c = 0; c < 3; c++) { std::snprintf(buf, sizeof buf, "\t%.17g", p.accel[i][c]); out << buf; }
        }
        out << (k % 50 == 0 ? "  # marker\n" : "\n");
    }
}

TEST(SynthTrajectory, RoundTripsTheProceduralMotion)
{
    synth_motion_fn walk = synth_builtin_motion("walk");
    std::string path = test_temp_path("walk.traj");
    write_trajectory(path, walk, 100.0, 5.0); // the file starts at t = 5 s
    synth_trajectory *traj = nullptr;
    ASSERT_EQ(synth_trajectory_load(path.c_str(), &traj), MOCAP_OK) << mocap_last_error();
    std::unique_ptr<synth_trajectory, void (*)(synth_trajectory *)> guard(traj, synth_trajectory_free);
    double end = motion_duration(walk);
    double dur = synth_trajectory_duration(traj);
    EXPECT_NEAR(dur, std::floor(end * 100) / 100, 1e-9);
    EXPECT_NEAR(motion_duration(synth_trajectory_motion, traj), dur, 1e-9);

    double worst_q_sample = 0, worst_a_sample = 0, worst_q_mid = 0, worst_a_mid = 0, worst_w = 0;
    for (int k = 0; k + 1 < (int)(dur * 100); k++) {
        for (double frac : {0.0, 0.5}) {
            double t = (k + frac) / 100.0;
            synth_pose want, got;
            ASSERT_EQ(walk(nullptr, t, &want), 0);
            ASSERT_EQ(synth_trajectory_motion(traj, t, &got), 0);
            for (int i = 0; i < kSensors; i++) {
                double qa = quat_angle_deg(want.bone_quat[i], got.bone_quat[i]);
                double ae = dist3(want.accel[i], got.accel[i]);
                if (frac == 0.0) {
                    worst_q_sample = std::max(worst_q_sample, qa);
                    worst_a_sample = std::max(worst_a_sample, ae);
                } else {
                    worst_q_mid = std::max(worst_q_mid, qa);
                    worst_a_mid = std::max(worst_a_mid, ae);
                }
                worst_w = std::max(worst_w, dist3(want.angular_velocity[i], got.angular_velocity[i]));
            }
        }
    }
    EXPECT_LT(worst_q_sample, 1e-5); // exact up to the text round trip
    EXPECT_LT(worst_a_sample, 1e-9);
    EXPECT_LT(worst_q_mid, 0.05);    // slerp between 10 ms samples
    EXPECT_LT(worst_a_mid, 0.05);
    EXPECT_LT(worst_w, 0.05);        // differenced angular velocity, rad/s
    RecordProperty("worst_mid_deg", std::to_string(worst_q_mid));
    RecordProperty("worst_mid_accel", std::to_string(worst_a_mid));
    RecordProperty("worst_omega", std::to_string(worst_w));
    synth_pose p;
    EXPECT_EQ(synth_trajectory_motion(traj, dur + 0.001, &p), -1);

    // A trajectory drives the generator like a built-in motion.
    synth_config cfg = short_config();
    cfg.motion_s = 100.0;
    Stream s = generate(cfg, synth_trajectory_motion, traj);
    ASSERT_FALSE(s.packets.empty());
    EXPECT_NEAR(s.packets.back().info.t, 3.0 + dur, 0.011);
    EXPECT_EQ(decode(s.bytes).frames.size(), s.packets.size());
}

void expect_load_error(const std::string &name, const std::string &text, mocap_status status,
                       const std::string &needle)
{
    std::string path = test_temp_path(name);
    { std::ofstream(path) << text; }
    synth_trajectory *traj = reinterpret_cast<synth_trajectory *>(&traj); // must be reset
    EXPECT_EQ(synth_trajectory_load(path.c_str(), &traj), status) << name;
    EXPECT_EQ(traj, nullptr) << name;
    std::string msg = mocap_last_error();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(needle), std::string::npos) << msg;
}

std::string traj_line(double t, double qw = 1.0)
{
    std::ostringstream s;
    s << t;
    for (int i = 0; i < kSensors; i++) s << " " << qw << " 0 0 0 0.1 0.2 0.3";
    return s.str() + "\n";
}

TEST(SynthTrajectory, MalformedFilesNameTheFileAndLine)
{
    std::string ok = "# header\n" + traj_line(0) + traj_line(0.01);
    expect_load_error("short.traj", ok + "0.02 1 0 0 0\n", MOCAP_ERR_FORMAT, "line 4");
    expect_load_error("word.traj", ok + "\n" + traj_line(0.02) + "0.03 1 0 0 zero\n",
                      MOCAP_ERR_FORMAT, "line 6");
    expect_load_error("order.traj", ok + traj_line(0.01), MOCAP_ERR_FORMAT, "line 4");
    expect_load_error("zeroq.traj", ok + traj_line(0.02, 0.0), MOCAP_ERR_FORMAT, "line 4");
    expect_load_error("long.traj", traj_line(0).substr(0, traj_line(0).size() - 1) + " 7\n",
                      MOCAP_ERR_FORMAT, "line 1");
    expect_load_error("empty.traj", "# nothing\n\n", MOCAP_ERR_FORMAT, "no samples");
    synth_trajectory *traj = nullptr;
    std::string missing = test_temp_path("missing.traj");
    EXPECT_EQ(synth_trajectory_load(missing.c_str(), &traj), MOCAP_ERR_NOT_FOUND);
    EXPECT_NE(std::string(mocap_last_error()).find(missing), std::string::npos);

    // Comments, blank lines, CRLF and tabs are fine; quaternions are normalised on load.
    std::string path = test_temp_path("fine.traj");
    { std::ofstream(path) << "# t ...\r\n" << traj_line(0, 1.01) << "\r\n\t\n" << traj_line(0.5); }
    ASSERT_EQ(synth_trajectory_load(path.c_str(), &traj), MOCAP_OK) << mocap_last_error();
    EXPECT_DOUBLE_EQ(synth_trajectory_duration(traj), 0.5);
    synth_pose p;
    ASSERT_EQ(synth_trajectory_motion(traj, 0.25, &p), 0);
    EXPECT_NEAR(p.bone_quat[3][0], 1.0, 1e-12);
    EXPECT_DOUBLE_EQ(p.accel[5][2], 0.3);
    synth_trajectory_free(traj);
}

// ------------------------------------------------------------------------------------------
TEST(Synth, WritesACaptureAndATruthCsv)
{
    synth_config cfg = short_config();
    cfg.packet_dropout_prob = 0.05;
    std::string cap = test_temp_path("synth.cap"), truth = test_temp_path("truth.csv");
    ASSERT_EQ(synth_write_capture(&cfg, nullptr, nullptr, cap.c_str(), truth.c_str()), MOCAP_OK)
        << mocap_last_error();
    Stream s = generate(cfg);

    capture_reader *r = nullptr;
    ASSERT_EQ(capture_reader_open(cap.c_str(), &r), MOCAP_OK) << mocap_last_error();
    size_t k = 0, records = 0;
    int64_t ns;
    const uint8_t *data;
    size_t len;
    while (capture_reader_next(r, &ns, &data, &len) == MOCAP_OK) {
        while (k < s.packets.size() && s.packets[k].info.dropped) k++;
        ASSERT_LT(k, s.packets.size());
        EXPECT_EQ(ns, s.packets[k].info.receive_ns);
        ASSERT_EQ(Bytes(data, data + len), s.packets[k].bytes);
        k++;
        records++;
    }
    EXPECT_EQ(capture_reader_tail(r), 0);
    capture_reader_close(r);
    size_t kept = std::count_if(s.packets.begin(), s.packets.end(),
                                [](const Packet &p) { return !p.info.dropped; });
    EXPECT_EQ(records, kept);
    EXPECT_LT(kept, s.packets.size());

    std::ifstream in(truth);
    std::string line;
    ASSERT_TRUE(std::getline(in, line));
    EXPECT_EQ(line.rfind("t_session,phase,pelvis_qw,", 0), 0u);
    size_t rows = 0;
    while (std::getline(in, line)) {
        std::vector<double> v;
        std::stringstream ss(line);
        std::string cell;
        while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
        ASSERT_EQ(v.size(), 2u + 7u * kSensors);
        ASSERT_LT(rows, s.packets.size());
        const Packet &p = s.packets[rows];
        EXPECT_NEAR(v[0], synth_session_time(&cfg, p.info.t), 1e-8);
        EXPECT_EQ(v[1], p.info.phase);
        for (int i = 0; i < kSensors; i++) {
            for (int c = 0; c < 4; c++) EXPECT_NEAR(v[2 + 7 * i + c], p.truth.bone_quat[i][c], 1e-8);
            for (int c = 0; c < 3; c++)
                EXPECT_NEAR(v[6 + 7 * i + c], p.truth.accel[i][c], 1e-8 * (1 + std::fabs(p.truth.accel[i][c])));
        }
        rows++;
    }
    EXPECT_EQ(rows, s.packets.size());

    std::string bad = test_temp_path("no/such/dir/x.cap");
    EXPECT_NE(synth_write_capture(&cfg, nullptr, nullptr, bad.c_str(), nullptr), MOCAP_OK);
}

// ------------------------------------------------------------------------------------------
// Acceptance: 6-node stream with 1% of bytes corrupted (~60 s at 100 Hz): zero crashes and every
// intact frame decoded.

struct Looped { synth_motion_fn fn; double period; };

int looped_motion(void *user, double t, synth_pose *out)
{
    auto *l = static_cast<Looped *>(user);
    return l->fn(nullptr, std::fmod(t, l->period), out);
}

TEST(SynthAcceptance, OnePercentCorruptedBytesEveryIntactFrameDecoded)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = 2024;
    cfg.motion_s = 52.0; // 8 s prelude + 52 s motion = 60 s
    cfg.acc_noise_g = 0.002;
    cfg.gyr_noise_dps = 0.1;
    cfg.corrupt_byte_prob = 0.01;
    Looped loop{synth_builtin_motion("mixed"), 0};
    loop.period = motion_duration(loop.fn);
    Stream s = generate(cfg, looped_motion, &loop);
    ASSERT_EQ(s.packets.size(), 6001u);

    // Expected: every sample of every intact packet, keyed by (sensor time, node id), with its
    // exact 76 encoded bytes.
    struct Expect { size_t packet; Bytes block; bool seen = false; };
    std::map<std::pair<uint32_t, uint32_t>, size_t> index;
    std::vector<Expect> expect;
    size_t intact = 0, corrupted = 0, corrupted_with_valid_header = 0;
    std::vector<bool> intact_start(s.bytes.size() + 1, false);
    for (const Packet &p : s.packets) {
        ASSERT_FALSE(p.info.dropped);
        if (!p.info.intact) {
            corrupted++;
            // Sync and length untouched: the decoder must check this frame's CRC and fail it.
            const Bytes clean_prefix = {HIPNUC_SYNC0, HIPNUC_SYNC1,
                                        (uint8_t)((p.info.length - HIPNUC_HEADER_SIZE) & 0xFF),
                                        (uint8_t)((p.info.length - HIPNUC_HEADER_SIZE) >> 8)};
            corrupted_with_valid_header += std::equal(clean_prefix.begin(), clean_prefix.end(),
                                                      p.bytes.begin());
            continue;
        }
        intact++;
        intact_start[p.info.offset] = true;
        ASSERT_EQ(p.bytes[2] | p.bytes[3] << 8, HIPNUC_GWSOL_HEADER_SIZE + 6 * HIPNUC_IMUSOL_SIZE);
        for (int j = 0; j < 6; j++) {
            const uint8_t *b = p.bytes.data() + HIPNUC_HEADER_SIZE + HIPNUC_GWSOL_HEADER_SIZE +
                               j * HIPNUC_IMUSOL_SIZE;
            uint32_t ms = b[8] | b[9] << 8 | b[10] << 16 | (uint32_t)b[11] << 24;
            ASSERT_EQ(b[1], cfg.node_ids[j]);
            index[{ms, b[1]}] = expect.size();
            expect.push_back({p.info.index, Bytes(b, b + HIPNUC_IMUSOL_SIZE)});
        }
    }
    ASSERT_GT(intact, 10u);     // 0.99^470: about 0.9% of frames survive
    ASSERT_GT(corrupted, 5000u);
    ASSERT_EQ(expect.size(), 6 * intact);

    DecodeResult d = decode(s.bytes, 99, true);
    size_t next = 0, unexpected_frames = 0;
    for (const Decoded &f : d.frames) {
        bool matched_any = false;
        for (const hipnuc_sample &smp : f.samples) {
            auto it = index.find({smp.time_ms, smp.node_id});
            if (it == index.end()) continue;
            matched_any = true;
            Expect &e = expect[it->second];
            EXPECT_FALSE(e.seen);
            EXPECT_GE(it->second, next) << "decoded out of order";
            next = it->second + 1;
            e.seen = true;
            uint8_t block[HIPNUC_IMUSOL_SIZE];
            hipnuc_encode_imusol(&smp, HIPNUC_LAYOUT_NODE_ID, block);
            EXPECT_EQ(Bytes(block, block + HIPNUC_IMUSOL_SIZE), e.block)
                << "packet " << e.packet << " node " << smp.node_id;
        }
        unexpected_frames += !matched_any;
    }
    for (const Expect &e : expect) EXPECT_TRUE(e.seen) << "intact packet " << e.packet << " lost";

    // Counters: every CRC-valid frame is an intact one (a CRC-16 collision could add one in a
    // blue moon); every intact-header corrupted frame costs a CRC failure; and every rejected
    // candidate (CRC failure or impossible length) sits on a 5A A5 pair that is not the start
    // of an intact frame.
    size_t false_syncs = 0;
    for (size_t i = 0; i + 1 < s.bytes.size(); i++)
        false_syncs += s.bytes[i] == HIPNUC_SYNC0 && s.bytes[i + 1] == HIPNUC_SYNC1 && !intact_start[i];
    EXPECT_EQ(d.stats.bytes_in, s.bytes.size() + HIPNUC_HEADER_SIZE + HIPNUC_MAX_PAYLOAD);
    EXPECT_EQ(d.stats.frames_ok, intact + unexpected_frames);
    EXPECT_LE(unexpected_frames, 1u);
    EXPECT_GE(d.stats.crc_failures, corrupted_with_valid_header);
    EXPECT_LE(d.stats.crc_failures + d.stats.bad_lengths, false_syncs);
    EXPECT_GT(corrupted_with_valid_header, corrupted / 2);
    RecordProperty("intact_frames", (int)intact);
    RecordProperty("crc_failures", std::to_string(d.stats.crc_failures));
}

// ------------------------------------------------------------------------------------------
// Sensor sets

// The default set plus a chest sensor on node 6.
synth_config seven_sensor_config()
{
    synth_config cfg = short_config();
    cfg.sensor_count = 7;
    cfg.segments[6] = MOCAP_SEGMENT_CHEST;
    cfg.node_ids[6] = 6;
    return cfg;
}

// Generation of cfg is refused before any packet, with a message containing needle.
void expect_generation_refused(const synth_config &cfg, const char *needle)
{
    Stream s;
    EXPECT_EQ(synth_generate(&cfg, nullptr, nullptr, collect_packet, &s), MOCAP_ERR_INVALID_ARGUMENT)
        << needle;
    EXPECT_TRUE(s.packets.empty());
    EXPECT_NE(std::string(mocap_last_error()).find(needle), std::string::npos)
        << needle << ": " << mocap_last_error();
}

TEST(SynthSensorSet, DefaultsAreTheEngineDefaultSet)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    mocap_session_config engine;
    mocap_config_defaults(&engine);
    ASSERT_EQ(cfg.sensor_count, engine.sensor_count);
    EXPECT_EQ(cfg.sensor_count, 6u);
    for (uint32_t i = 0; i < cfg.sensor_count; i++) {
        EXPECT_EQ(cfg.segments[i], engine.sensor_segments[i]) << i;
        EXPECT_EQ(cfg.node_ids[i], engine.node_ids[i]) << i;
    }
}

// A chest on node 6: seven blocks per packet in config order, and the chest's sample is its own
// bone's motion (not the pelvis's) through its own setup rotations, while the six others keep the
// setup draws they have without it.
TEST(SynthSensorSet, SevenSensorsCarryTheChestInConfigOrder)
{
    synth_config cfg = seven_sensor_config();
    cfg.motion_s = 30.0;
    Stream s = generate(cfg);
    ASSERT_FALSE(s.packets.empty());
    DecodeResult d = decode(s.bytes, 3);
    ASSERT_EQ(d.frames.size(), s.packets.size());
    double w2m[MOCAP_MAX_SENSORS][9], s2b[MOCAP_MAX_SENSORS][9];
    double w2m6[MOCAP_MAX_SENSORS][9], s2b6[MOCAP_MAX_SENSORS][9];
    synth_setup_rotations(&cfg, w2m, s2b);
    synth_config six = short_config();
    synth_setup_rotations(&six, w2m6, s2b6);
    for (int i = 0; i < kSensors; i++)
        for (int k = 0; k < 9; k++) {
            EXPECT_EQ(w2m[i][k], w2m6[i][k]) << "sensor " << i;
            EXPECT_EQ(s2b[i][k], s2b6[i][k]) << "sensor " << i;
        }
    EXPECT_GT(mat3_angle_deg(s2b[6], s2b[0]), 1.0); // the chest has a mounting of its own

    double worst_chest = 0, chest_vs_pelvis = 0;
    for (size_t k = 0; k < s.packets.size(); k++) {
        const Packet &p = s.packets[k];
        EXPECT_EQ(p.info.node_mask, 0x7Fu);
        EXPECT_EQ(p.info.length, HIPNUC_HEADER_SIZE + HIPNUC_GWSOL_HEADER_SIZE + 7 * HIPNUC_IMUSOL_SIZE);
        ASSERT_EQ(d.frames[k].samples.size(), 7u);
        for (int i = 0; i < 7; i++) EXPECT_EQ(d.frames[k].samples[i].node_id, (uint32_t)cfg.node_ids[i]);
        EXPECT_NE(p.truth.segment_mask & (1u << MOCAP_SEGMENT_CHEST), 0u);
        // Strapped on (T-pose and motion), the sensor reports its bone through its mounting.
        ModelSample chest = to_model(d.frames[k].samples[6], w2m[6], s2b[6]);
        if (p.info.phase >= 2)
            worst_chest = std::max(worst_chest, mat_angle_to_quat_deg(chest.model_bone,
                                                                      p.truth.bone_quat[MOCAP_SEGMENT_CHEST]));
        if (p.info.phase == 3)
            chest_vs_pelvis = std::max(chest_vs_pelvis, quat_angle_deg(p.truth.bone_quat[MOCAP_SEGMENT_CHEST],
                                                                       p.truth.bone_quat[MOCAP_SEGMENT_PELVIS]));
    }
    EXPECT_LT(worst_chest, 1e-3); // float rounding of the encoded quaternion only
    EXPECT_GT(chest_vs_pelvis, 5.0);  // it articulates on the spine
    EXPECT_LT(chest_vs_pelvis, 40.0); // a little, as a chest does
}

// The chest moves relative to the pelvis in each built-in motion, as an upper trunk would: a few
// degrees of twist or bend, never a tumble.
TEST(SynthMotions, ChestArticulatesOnThePelvis)
{
    for (const char *name : {"walk", "arms", "squat", "turn"}) {
        synth_motion_fn fn = synth_builtin_motion(name);
        double end = motion_duration(fn), most = 0;
        for (double t = 0; t < end; t += 0.02) {
            synth_pose p;
            ASSERT_EQ(fn(nullptr, t, &p), 0);
            EXPECT_EQ(p.segment_mask, 0x7Fu) << name;
            most = std::max(most, quat_angle_deg(p.bone_quat[MOCAP_SEGMENT_CHEST],
                                                 p.bone_quat[MOCAP_SEGMENT_PELVIS]));
        }
        EXPECT_GT(most, 2.0) << name;
        EXPECT_LT(most, 25.0) << name;
    }
}

// The truth CSV has one column group per configured sensor, named by its segment, in config
// order, and each group is that segment's truth.
TEST(SynthSensorSet, TruthCsvCoversTheConfiguredSensors)
{
    synth_config cfg = short_config();
    cfg.sensor_count = 3;
    cfg.segments[0] = MOCAP_SEGMENT_CHEST;
    cfg.segments[1] = MOCAP_SEGMENT_PELVIS;
    cfg.segments[2] = MOCAP_SEGMENT_HEAD;
    cfg.node_ids[0] = 12;
    cfg.node_ids[1] = 7;
    cfg.node_ids[2] = 30;
    std::string cap = test_temp_path("three.cap"), truth = test_temp_path("three.csv");
    ASSERT_EQ(synth_write_capture(&cfg, nullptr, nullptr, cap.c_str(), truth.c_str()), MOCAP_OK)
        << mocap_last_error();
    Stream s = generate(cfg);
    std::ifstream in(truth);
    std::string line;
    ASSERT_TRUE(std::getline(in, line));
    EXPECT_EQ(line, "t_session,phase,chest_qw,chest_qx,chest_qy,chest_qz,chest_ax,chest_ay,chest_az,"
                    "pelvis_qw,pelvis_qx,pelvis_qy,pelvis_qz,pelvis_ax,pelvis_ay,pelvis_az,"
                    "head_qw,head_qx,head_qy,head_qz,head_ax,head_ay,head_az");
    size_t rows = 0;
    while (std::getline(in, line)) {
        std::vector<double> v;
        std::stringstream ss(line);
        std::string cell;
        while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
        ASSERT_EQ(v.size(), 2u + 7u * 3u);
        ASSERT_LT(rows, s.packets.size());
        const synth_pose &t = s.packets[rows].truth;
        for (int i = 0; i < 3; i++)
            for (int c = 0; c < 4; c++)
                EXPECT_NEAR(v[2 + 7 * i + c], t.bone_quat[cfg.segments[i]][c], 1e-8) << "row " << rows;
        rows++;
    }
    EXPECT_EQ(rows, s.packets.size());
    EXPECT_EQ(s.packets.back().info.node_mask, 0x7u);
}

// A sensor with node id -1 is configured but never sends: its blocks are missing from every
// packet, the others are all there.
TEST(SynthSensorSet, ASilentSensorSendsNothing)
{
    synth_config cfg = seven_sensor_config();
    cfg.node_ids[6] = -1;
    Stream s = generate(cfg);
    ASSERT_FALSE(s.packets.empty());
    DecodeResult d = decode(s.bytes);
    ASSERT_EQ(d.frames.size(), s.packets.size());
    for (size_t k = 0; k < s.packets.size(); k++) {
        EXPECT_EQ(s.packets[k].info.node_mask, 0x3Fu);
        EXPECT_EQ(d.frames[k].samples.size(), 6u);
    }
}

// A silence window leaves one sensor out of exactly the packets whose motion time lies in
// [start, start + length): absent there (the packet info and the decoded frames agree), present
// in every packet around it, the other sensors untouched.
TEST(SynthSilence, ASensorIsAbsentExactlyInItsWindowAndPresentAroundIt)
{
    synth_config cfg = short_config();   // 3 s prelude, 4 s of motion at 100 Hz
    cfg.silence_count = 2;
    cfg.silences[0] = {MOCAP_SEGMENT_LEFT_WRIST, 1.0, 1.5};
    cfg.silences[1] = {MOCAP_SEGMENT_HEAD, 3.5, 10.0};   // to the end of the motion
    Stream s = generate(cfg);
    DecodeResult d = decode(s.bytes);
    ASSERT_EQ(d.frames.size(), s.packets.size());
    const double prelude = cfg.heading_s + cfg.strap_s + cfg.tpose_s;
    int wrist_silent = 0, head_silent = 0;
    for (size_t k = 0; k < s.packets.size(); k++) {
        const synth_packet_info &info = s.packets[k].info;
        // Tick k is at k / 100 s: the window's edges by the tick number, not by rounded times.
        const long tick = (long)k - (long)llround(prelude * cfg.rate_hz);
        const bool wrist_off = tick >= 100 && tick < 250;
        const bool head_off = tick >= 350;
        uint32_t expect = 0x3Fu & ~(wrist_off ? 1u << 1 : 0u) & ~(head_off ? 1u << 5 : 0u);
        ASSERT_EQ(info.node_mask, expect) << "packet " << k << " t " << info.t;
        ASSERT_EQ(info.silent_mask, (wrist_off ? 1u << 1 : 0u) | (head_off ? 1u << 5 : 0u))
            << "packet " << k;
        std::set<uint32_t> nodes;
        for (const hipnuc_sample &smp : d.frames[k].samples) nodes.insert(smp.node_id);
        EXPECT_EQ(nodes.count((uint32_t)cfg.node_ids[1]), wrist_off ? 0u : 1u) << "packet " << k;
        EXPECT_EQ(nodes.count((uint32_t)cfg.node_ids[5]), head_off ? 0u : 1u) << "packet " << k;
        EXPECT_EQ(nodes.size(), (size_t)popcount(expect)) << "packet " << k;
        wrist_silent += wrist_off;
        head_silent += head_off;
    }
    EXPECT_EQ(wrist_silent, 150);   // 1.5 s at 100 Hz
    EXPECT_EQ(head_silent, 51);     // 3.5 .. 4.0 s, both ends of the motion's ticks included
}

// The window changes nothing else: with noise on, every packet outside it carries the bytes of
// the capture made without it, and inside it the other sensors' blocks are the same samples.
TEST(SynthSilence, PacketsOutsideTheWindowAreThoseOfTheCaptureWithoutIt)
{
    synth_config cfg = short_config();
    cfg.acc_noise_g = 0.01;
    cfg.gyr_noise_dps = 0.3;
    cfg.quat_noise_deg = 0.3;
    cfg.acc_bias_g = 0.01;
    cfg.still_tremor_deg = 0.2;
    cfg.node_dropout_prob = 0.02;
    Stream plain = generate(cfg);
    cfg.silence_count = 1;
    cfg.silences[0] = {MOCAP_SEGMENT_RIGHT_SHIN, 0.5, 2.0};
    Stream silent = generate(cfg);
    ASSERT_EQ(plain.packets.size(), silent.packets.size());
    DecodeResult dp = decode(plain.bytes), ds = decode(silent.bytes);
    ASSERT_EQ(dp.frames.size(), ds.frames.size());
    int inside = 0;
    for (size_t k = 0; k < plain.packets.size(); k++) {
        if (silent.packets[k].info.silent_mask == 0) {
            EXPECT_EQ(silent.packets[k].bytes, plain.packets[k].bytes) << "packet " << k;
            continue;
        }
        inside++;
        EXPECT_EQ(silent.packets[k].info.node_mask, plain.packets[k].info.node_mask & ~(1u << 4));
        std::vector<const hipnuc_sample *> others;
        for (const hipnuc_sample &smp : dp.frames[k].samples)
            if (smp.node_id != (uint32_t)cfg.node_ids[4]) others.push_back(&smp);
        ASSERT_EQ(ds.frames[k].samples.size(), others.size()) << "packet " << k;
        for (size_t j = 0; j < others.size(); j++)
            EXPECT_EQ(std::memcmp(&ds.frames[k].samples[j], others[j], sizeof(hipnuc_sample)), 0)
                << "packet " << k << " block " << j;
    }
    EXPECT_EQ(inside, 200);
}

TEST(SynthSilence, BadWindowsAreRefusedNamingTheProblem)
{
    struct Case {
        std::function<void(synth_config &)> change;
        const char *needle;
    };
    const Case cases[] = {
        {[](synth_config &c) { c.silence_count = SYNTH_MAX_SILENCES + 1; }, "silence windows"},
        {[](synth_config &c) { c.silence_count = 1; c.silences[0] = {MOCAP_SEGMENT_CHEST, 1.0, 1.0}; },
         "chest has no sensor"},
        {[](synth_config &c) { c.silence_count = 1; c.silences[0] = {42, 1.0, 1.0}; },
         "(invalid) has no sensor"},
        {[](synth_config &c) { c.silence_count = 1; c.silences[0] = {MOCAP_SEGMENT_HEAD, -1.0, 1.0}; },
         "start -1 s"},
        {[](synth_config &c) { c.silence_count = 1; c.silences[0] = {MOCAP_SEGMENT_HEAD, 1.0, 0.0}; },
         "length 0 s"},
        {[](synth_config &c) { c.silence_count = 1; c.silences[0] = {MOCAP_SEGMENT_HEAD, NAN, 1.0}; },
         "silence window 0 of head"},
    };
    for (const Case &k : cases) {
        synth_config cfg = short_config();
        k.change(cfg);
        expect_generation_refused(cfg, k.needle);
    }
}

TEST(SynthSensorSet, BadSetsAreRefusedNamingTheProblem)
{
    struct Case {
        std::function<void(synth_config &)> change;
        const char *needle;
    };
    const Case cases[] = {
        {[](synth_config &c) { c.sensor_count = 0; }, "sensor_count 0"},
        {[](synth_config &c) { c.sensor_count = 17; }, "sensor_count 17"},
        {[](synth_config &c) { c.segments[4] = MOCAP_SEGMENT_LEFT_WRIST; }, "left_wrist"},
        {[](synth_config &c) { c.segments[2] = 7; }, "segment 7"},
        {[](synth_config &c) { c.segments[2] = -1; }, "segment -1"},
        {[](synth_config &c) { c.node_ids[6] = c.node_ids[0]; }, "node id 7"},
        {[](synth_config &c) { c.node_ids[6] = 256; }, "256"},
    };
    for (const Case &k : cases) {
        synth_config cfg = seven_sensor_config();
        k.change(cfg);
        expect_generation_refused(cfg, k.needle);
    }
}

// A trajectory file may name its segments; a capture of sensors on segments it lacks is refused
// naming the first one, one of its own segments works.
TEST(SynthTrajectory, ASegmentsLineNamesTheColumns)
{
    std::string path = test_temp_path("two.traj");
    {
        std::ofstream out(path);
        out.precision(17);
        out << "# pelvis still, chest turning\nsegments pelvis, chest\n";
        for (int k = 0; k <= 100; k++) {
            double a = 0.005 * k, t = 0.01 * k;
            out << t << "  1 0 0 0  0 0 0   " << std::cos(a) << " 0 " << std::sin(a) << " 0  0.5 0 0\n";
        }
    }
    synth_trajectory *traj = nullptr;
    ASSERT_EQ(synth_trajectory_load(path.c_str(), &traj), MOCAP_OK) << mocap_last_error();
    std::unique_ptr<synth_trajectory, void (*)(synth_trajectory *)> guard(traj, synth_trajectory_free);
    EXPECT_EQ(synth_trajectory_segment_mask(traj), (1u << MOCAP_SEGMENT_PELVIS) | (1u << MOCAP_SEGMENT_CHEST));
    synth_pose p;
    ASSERT_EQ(synth_trajectory_motion(traj, 0.5, &p), 0);
    EXPECT_EQ(p.segment_mask, (1u << MOCAP_SEGMENT_PELVIS) | (1u << MOCAP_SEGMENT_CHEST));
    EXPECT_NEAR(p.bone_quat[MOCAP_SEGMENT_CHEST][0], std::cos(0.25), 1e-9);
    EXPECT_NEAR(p.bone_quat[MOCAP_SEGMENT_CHEST][2], std::sin(0.25), 1e-9);
    EXPECT_NEAR(p.angular_velocity[MOCAP_SEGMENT_CHEST][1], 1.0, 1e-6); // 2 * 0.5 rad/s
    EXPECT_DOUBLE_EQ(p.accel[MOCAP_SEGMENT_CHEST][0], 0.5);

    synth_config six = short_config();
    Stream none;
    EXPECT_EQ(synth_generate(&six, synth_trajectory_motion, traj, collect_packet, &none),
              MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(mocap_last_error()).find("left_wrist"), std::string::npos) << mocap_last_error();
    EXPECT_TRUE(none.packets.empty()); // refused before the first packet
    const std::string cap = test_temp_path("refused.cap");
    EXPECT_EQ(synth_write_capture(&six, synth_trajectory_motion, traj, cap.c_str(), nullptr),
              MOCAP_ERR_INVALID_ARGUMENT);
    EXPECT_FALSE(std::ifstream(cap).good()) << "a refused capture was written";

    synth_config two = short_config();
    two.sensor_count = 2;
    two.segments[1] = MOCAP_SEGMENT_CHEST;
    Stream s = generate(two, synth_trajectory_motion, traj);
    ASSERT_FALSE(s.packets.empty());
    EXPECT_NEAR(quat_angle_deg(s.packets.back().truth.bone_quat[MOCAP_SEGMENT_CHEST], p.bone_quat[MOCAP_SEGMENT_PELVIS]),
                0.5 * 2 * MOCAP_RAD2DEG, 1e-6); // 1 rad of turn at the end (identity pelvis)

    std::string head = "segments pelvis chest\n0 1 0 0 0 0 0 0 1 0 0 0 0 0 0\n";
    expect_load_error("unknown.traj", "segments pelvis spine\n", MOCAP_ERR_FORMAT, "spine");
    expect_load_error("twice.traj", "segments chest chest\n", MOCAP_ERR_FORMAT, "chest");
    expect_load_error("late.traj", head + "segments pelvis\n", MOCAP_ERR_FORMAT, "line 3");
    expect_load_error("count.traj", head + "0.1 1 0 0 0 0 0 0\n", MOCAP_ERR_FORMAT, "2 segments");
}

} // namespace
