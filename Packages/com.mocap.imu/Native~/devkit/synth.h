/* Synthetic HiPNUC captures from a known motion of the body: the project's own test tooling (no
 * recorded data needed). The sensor set is configurable (any segments of the engine's table, by
 * default its default set of six). For each sensor tick it writes a 0x62 gateway frame with one
 * 0x91 block per node, exactly as the wireless receiver would, including
 *  - a calibration prelude: sensors lying still with X forward (heading step), then strapped on
 *    and held in a T-pose, then the motion;
 *  - a per-sensor world frame (NWU or ENU, Z up) with an arbitrary heading, as 6-axis sensors
 *    have; an arbitrary fixed mounting rotation of each sensor on its bone;
 *  - accelerations as specific force in g in the sensor frame, angular rate in deg/s;
 *  - optional noise, bias, dropped nodes, dropped packets and corrupted bytes;
 *  - optional silences: a sensor that sends nothing for a window of the motion (a sensor out of
 *    radio range or with a flat battery, back afterwards).
 * Model frame: right-handed, Y up, character facing +Z, X = character's left. */
#ifndef MOCAP_SYNTH_H
#define MOCAP_SYNTH_H

#include <stddef.h>
#include <stdint.h>
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Truth for one instant, in the model frame, indexed by segment (mocap_segment): a motion fills
 * every segment it knows and says which in segment_mask. */
typedef struct synth_pose {
    double bone_quat[MOCAP_MAX_SENSORS][4];   /* bone -> model */
    double accel[MOCAP_MAX_SENSORS][3];       /* linear acceleration of the sensor, m/s^2 */
    double angular_velocity[MOCAP_MAX_SENSORS][3]; /* of the bone, model frame, rad/s */
    uint32_t segment_mask;                    /* bit s: segment s is filled */
} synth_pose;

/* A motion: fills the pose at time t (seconds since the motion started). Returns 0, or -1 when
 * t is past the end of the motion. */
typedef int (*synth_motion_fn)(void *user, double t, synth_pose *out);

/* Built-in procedural motions of every segment of the table (bones identity at rest = T-pose;
 * exact angular velocity and analytic accelerations). name: "walk", "arms", "squat", "turn",
 * "mixed" (all four in sequence, the default). Returns NULL for an unknown name. */
synth_motion_fn synth_builtin_motion(const char *name);
/* How long a motion lasts, s (to 1 ms; at most `limit`): the first time it reports its end. */
double synth_motion_duration(synth_motion_fn motion, void *user, double limit);
/* Motion from a trajectory file (see docs/synth-trajectory.md): text lines
 * "t qw qx qy qz ax ay az" x its segments, in the model frame: the six of the default set, or
 * those a "segments NAME..." line names. Loaded into memory once. */
typedef struct synth_trajectory synth_trajectory;
mocap_status synth_trajectory_load(const char *path, synth_trajectory **out);
void synth_trajectory_free(synth_trajectory *traj);
double synth_trajectory_duration(const synth_trajectory *traj);
uint32_t synth_trajectory_segment_mask(const synth_trajectory *traj); /* bit s: segment s */
int synth_trajectory_motion(void *traj, double t, synth_pose *out); /* a synth_motion_fn */

/* Most silence windows a config holds. */
#define SYNTH_MAX_SILENCES 16

/* One sensor sends nothing from start_s for length_s seconds of motion time (seconds since the
 * motion started, after the prelude): its blocks are left out of the 0x62 frames of that window.
 * Its samples are still generated (and their random draws made), so every frame outside the
 * window is the one the config without it writes (unless bytes are corrupted: those draws
 * follow the frame lengths). */
typedef struct synth_silence {
    int32_t segment;   /* mocap_segment of a configured sensor */
    double start_s;    /* >= 0 */
    double length_s;   /* > 0 */
} synth_silence;

typedef struct synth_config {
    uint64_t seed;
    int32_t world_frame;          /* mocap_world_frame for every sensor */
    double facing_azimuth_deg;    /* user's facing, degrees east of north */
    double heading_spread_deg;    /* each sensor's world yaw additionally off by U(-s, s) */
    int32_t random_mounting;      /* 1: each sensor mounted with a random rotation */
    double rate_hz;               /* sensor rate (100) */
    double heading_s;             /* heading step length (3) */
    double strap_s;               /* moving from heading step to T-pose (2) */
    double tpose_s;               /* T-pose hold (3) */
    double motion_s;              /* motion length (clipped to the motion's end) */
    /* The sensor set: sensor i rides on segment segments[i] and sends as node node_ids[i]
     * (-1: it sends nothing). Blocks, truth columns and setup rotations follow this order.
     * Default: the engine's default set (mocap_config_defaults). */
    uint32_t sensor_count;        /* 1 .. MOCAP_MAX_SENSORS */
    int32_t segments[MOCAP_MAX_SENSORS];
    int32_t node_ids[MOCAP_MAX_SENSORS];
    uint8_t gateway_id;
    int32_t imusol_layout;        /* HIPNUC_LAYOUT_NODE_ID (0x62 always carries node ids) */
    int64_t start_receive_ns;     /* receive time of the first packet */
    uint32_t start_sensor_ms;     /* sensor clock at the first packet (can be near 2^32) */
    /* Noise (standard deviations), constant biases (max magnitude, random per sensor). */
    double acc_noise_g;
    double gyr_noise_dps;
    double quat_noise_deg;
    double acc_bias_g;
    double still_tremor_deg;      /* small sway during the prelude (0 = perfectly still) */
    /* Faults. */
    double node_dropout_prob;     /* a node missing from one packet */
    double packet_dropout_prob;   /* a whole packet lost */
    double corrupt_byte_prob;     /* each byte flipped to a random value with this probability */
    uint32_t silence_count;       /* 0 .. SYNTH_MAX_SILENCES */
    synth_silence silences[SYNTH_MAX_SILENCES];
} synth_config;

void synth_config_defaults(synth_config *cfg); /* noise-free, no faults, random heading/mounting */

/* What the generator reports for every packet it writes. */
typedef struct synth_packet_info {
    uint64_t index;            /* packet number, 0-based, counting dropped ones */
    int64_t receive_ns;
    double t;                  /* seconds since the start of the stream */
    int32_t phase;             /* 0 heading, 1 strapping, 2 T-pose, 3 motion */
    uint32_t node_mask;        /* bit i: sensor i (config order) is present in the packet */
    uint32_t silent_mask;      /* bit i: sensor i is in one of its silence windows */
    int32_t intact;            /* no byte of this frame was corrupted */
    int32_t dropped;           /* the whole packet was lost (no bytes written) */
    size_t offset;             /* byte offset of the frame in the stream */
    size_t length;
} synth_packet_info;

/* Receives the byte stream packet by packet (already corrupted where configured) and the truth
 * for that packet's instant. Return non-zero to stop. */
typedef int (*synth_packet_fn)(void *user, const synth_packet_info *info, const uint8_t *bytes,
                               const synth_pose *truth);

/* Generate the whole stream. The truth of the prelude is the T-pose/heading layout the sensors
 * were held in (bones identity). */
mocap_status synth_generate(const synth_config *cfg, synth_motion_fn motion, void *motion_user,
                            synth_packet_fn on_packet, void *user);

/* Convenience: generate straight into a capture file, and optionally a truth CSV with one line
 * per packet: "t_session phase q(w,x,y,z) a(x,y,z)" per configured sensor (config order, the
 * header names each column by segment: pelvis_qw ...), t on the session clock. */
mocap_status synth_write_capture(const synth_config *cfg, synth_motion_fn motion,
                                 void *motion_user, const char *capture_path,
                                 const char *truth_path);

/* Session-clock time (s) of stream time t for a capture made with cfg. */
double synth_session_time(const synth_config *cfg, double t);

/* The truth rotations of the generated setup (for tests): sensor world -> model frame and
 * sensor -> bone (mounting) for each configured sensor (config order; the rest are zero). */
void synth_setup_rotations(const synth_config *cfg, double world_to_model[MOCAP_MAX_SENSORS][9],
                           double sensor_to_bone[MOCAP_MAX_SENSORS][9]);

#ifdef __cplusplus
}
#endif
#endif
