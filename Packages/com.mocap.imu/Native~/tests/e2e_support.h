// Shared pieces of the end-to-end suites: generated streams, truth lookup, error statistics.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

extern "C" {
#include "mocap_imu.h"
#include "mocap_math.h"
#include "synth.h"
}

// One generated packet: its bytes, when it was "received", and the truth at that instant.
struct GeneratedPacket {
    synth_packet_info info;
    std::vector<uint8_t> bytes;
    synth_pose truth;
};

inline int collect_packet(void *user, const synth_packet_info *info, const uint8_t *bytes,
                          const synth_pose *truth)
{
    auto *out = static_cast<std::vector<GeneratedPacket> *>(user);
    GeneratedPacket p;
    p.info = *info;
    if (!info->dropped) p.bytes.assign(bytes, bytes + info->length);
    p.truth = *truth;
    out->push_back(std::move(p));
    return 0;
}

inline std::vector<GeneratedPacket> generate(const synth_config &cfg, const char *motion = "mixed")
{
    std::vector<GeneratedPacket> packets;
    synth_motion_fn fn = synth_builtin_motion(motion);
    if (!fn) return packets;
    if (synth_generate(&cfg, fn, nullptr, collect_packet, &packets) != MOCAP_OK) packets.clear();
    return packets;
}

// Realistic noise of a MEMS IMU after the device's own fusion, at 100 Hz.
inline void add_realistic_noise(synth_config &cfg)
{
    cfg.acc_noise_g = 0.01;
    cfg.gyr_noise_dps = 0.3;
    cfg.quat_noise_deg = 0.3;
    cfg.acc_bias_g = 0.01;
    cfg.still_tremor_deg = 0.2;
}

// Truth of every segment (indexed by segment) at session time t, interpolated between packets; phase of the nearer.
struct TruthTrack {
    std::vector<double> times;
    std::vector<int> phases;
    std::vector<synth_pose> poses;

    TruthTrack(const synth_config &cfg, const std::vector<GeneratedPacket> &packets)
    {
        for (const auto &p : packets) {
            times.push_back(synth_session_time(&cfg, p.info.t));
            phases.push_back(p.info.phase);
            poses.push_back(p.truth);
        }
    }

    bool at(double t, synth_pose &out, int &phase) const
    {
        if (times.size() < 2 || t < times.front() || t > times.back()) return false;
        size_t hi = std::lower_bound(times.begin(), times.end(), t) - times.begin();
        if (hi == 0) hi = 1;
        size_t lo = hi - 1;
        double u = (t - times[lo]) / (times[hi] - times[lo]);
        phase = u < 0.5 ? phases[lo] : phases[hi];
        out.segment_mask = poses[lo].segment_mask & poses[hi].segment_mask;
        for (int s = 0; s < MOCAP_MAX_SENSORS; ++s) {
            quat_slerp(out.bone_quat[s], poses[lo].bone_quat[s], poses[hi].bone_quat[s], u);
            for (int k = 0; k < 3; ++k)
                out.accel[s][k] = poses[lo].accel[s][k] + u * (poses[hi].accel[s][k] - poses[lo].accel[s][k]);
        }
        return true;
    }
};

// Per sensor of the session (config order).
struct ErrorStats {
    std::vector<double> angles[MOCAP_MAX_SENSORS];
    double acc_sq[MOCAP_MAX_SENSORS] = {};
    double acc_truth_sq[MOCAP_MAX_SENSORS] = {};

    void add(int s, double angle_deg, const float acc[3], const double truth_acc[3])
    {
        angles[s].push_back(angle_deg);
        for (int k = 0; k < 3; ++k) {
            double d = acc[k] - truth_acc[k];
            acc_sq[s] += d * d;
            acc_truth_sq[s] += truth_acc[k] * truth_acc[k];
        }
    }
    size_t count(int s) const { return angles[s].size(); }
    double mean(int s) const
    {
        double sum = 0;
        for (double a : angles[s]) sum += a;
        return angles[s].empty() ? NAN : sum / angles[s].size();
    }
    double max(int s) const
    {
        return angles[s].empty() ? NAN : *std::max_element(angles[s].begin(), angles[s].end());
    }
    double acc_rms(int s) const { return std::sqrt(acc_sq[s] / std::max<size_t>(1, count(s))); }
    double acc_truth_rms(int s) const
    {
        return std::sqrt(acc_truth_sq[s] / std::max<size_t>(1, count(s)));
    }
};

// Compares a frame's calibrated bones with the truth of their segments during the motion phase.
inline void score_frame(const TruthTrack &truth, const mocap_frame &f, ErrorStats &stats)
{
    if (!(f.flags & MOCAP_FRAME_CALIBRATED)) return;
    synth_pose pose;
    int phase = -1;
    if (!truth.at(f.time_s, pose, phase) || phase != 3) return;
    for (uint32_t s = 0; s < f.sensor_count && s < MOCAP_MAX_SENSORS; ++s) {
        if (!(f.fresh_mask & (1u << s))) continue;
        if (!(f.sensors[s].flags & MOCAP_SENSOR_CALIBRATED)) continue;
        const int seg = f.sensors[s].segment;
        const float *q = f.sensors[s].bone_orientation;
        double qd[4] = {q[0], q[1], q[2], q[3]};
        stats.add((int)s, quat_angle_deg(qd, pose.bone_quat[seg]), f.sensors[s].bone_acceleration,
                  pose.accel[seg]);
    }
}
