/* mocapctl synth: a capture of a known motion (built-in, or a trajectory file:
 * docs/synth-trajectory.md) with its calibration prelude and, with --truth, the truth CSV. */
#include <stdio.h>
#include <string.h>

#include "cli_args.h"
#include "commands.h"
#include "report.h"
#include "sensor_set.h"
#include "synth.h"

int cmd_synth(int argc, char **argv)
{
    const char *out = cli_value(argc, argv, "--out");
    if (!out) return mocapctl_usage_error("synth");
    const char *truth = cli_value(argc, argv, "--truth");
    static const char *const synth_outputs[] = {"--out", "--truth", NULL};
    cli_refuse_overwriting(cli_value(argc, argv, "--trajectory"), "trajectory", argc, argv, synth_outputs);
    const char *motion_name = cli_value(argc, argv, "--motion");
    const char *world = cli_value(argc, argv, "--world");
    const char *noise = cli_value(argc, argv, "--noise");

    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = cli_u64(argc, argv, "--seed", cfg.seed);
    cfg.motion_s = cli_number(argc, argv, "--seconds", cfg.motion_s, 0.0, 86400.0);
    if (world && strcmp(world, "enu") == 0) cfg.world_frame = MOCAP_WORLD_ENU;
    else if (world && strcmp(world, "nwu") != 0) {
        fprintf(stderr, "mocapctl: --world must be nwu or enu\n");
        return 2;
    }
    if (!noise || strcmp(noise, "realistic") == 0) {
        /* Typical of a MEMS IMU at 100 Hz after the device's own fusion. */
        cfg.acc_noise_g = 0.01;
        cfg.gyr_noise_dps = 0.3;
        cfg.quat_noise_deg = 0.3;
        cfg.acc_bias_g = 0.01;
        cfg.still_tremor_deg = 0.2;
    } else if (strcmp(noise, "none") != 0) {
        fprintf(stderr, "mocapctl: --noise must be none or realistic\n");
        return 2;
    }
    cfg.corrupt_byte_prob = cli_number(argc, argv, "--corrupt", cfg.corrupt_byte_prob, 0.0, 1.0);
    cfg.node_dropout_prob = cli_number(argc, argv, "--dropout", cfg.node_dropout_prob, 0.0, 1.0);
    /* The capture's sensors: the session's set (its '?' marks only matter to sessions). */
    mocap_session_config set;
    mocap_config_defaults(&set);
    if (sensor_set_from_args(argc, argv, &set) != 0) return 2;
    cfg.sensor_count = set.sensor_count;
    for (uint32_t i = 0; i < set.sensor_count; ++i) {
        cfg.segments[i] = set.sensor_segments[i];
        cfg.node_ids[i] = set.node_ids[i];
    }
    set.optional_mask = 0;
    char described[512];
    sensor_set_describe(&set, described, sizeof described);

    synth_trajectory *traj = NULL;
    synth_motion_fn motion = NULL;
    void *motion_user = NULL;
    const char *traj_path = cli_value(argc, argv, "--trajectory");
    if (traj_path) {
        mocap_status st = synth_trajectory_load(traj_path, &traj);
        if (st != MOCAP_OK) return report_failure(st, "loading trajectory");
        motion = synth_trajectory_motion;
        motion_user = traj;
        if (!cli_value(argc, argv, "--seconds")) cfg.motion_s = synth_trajectory_duration(traj);
    } else {
        motion = synth_builtin_motion(motion_name ? motion_name : "mixed");
        if (!motion) {
            fprintf(stderr, "mocapctl: unknown motion '%s'\n", motion_name);
            return 2;
        }
    }
    /* A motion ends where it ends: --seconds can shorten it, not lengthen it. */
    const double motion_length = synth_motion_duration(motion, motion_user, 86400.0);
    const int clipped = cli_value(argc, argv, "--seconds") && cfg.motion_s > motion_length + 1e-3;
    mocap_status st = synth_write_capture(&cfg, motion, motion_user, out, truth);
    synth_trajectory_free(traj);
    if (st != MOCAP_OK) return report_failure(st, "writing capture");
    printf("wrote %s: %u sensors (%s), %.1f s prelude (heading %.1f s, strap %.1f s, T-pose %.1f s) "
           "then %.1f s of %s, %s world, seed %llu%s%s\n",
           out, (unsigned)cfg.sensor_count, described, cfg.heading_s + cfg.strap_s + cfg.tpose_s, cfg.heading_s, cfg.strap_s, cfg.tpose_s,
           cfg.motion_s < motion_length ? cfg.motion_s : motion_length,
           traj_path ? "the trajectory" : motion_name ? motion_name : "mixed",
           cfg.world_frame == MOCAP_WORLD_ENU ? "ENU" : "NWU",
           (unsigned long long)cfg.seed, truth ? ", truth " : "", truth ? truth : "");
    if (clipped)
        fprintf(stderr, "mocapctl: note: the motion ends after %.1f s, so the capture is shorter "
                        "than --seconds %s\n", motion_length, cli_value(argc, argv, "--seconds"));
    return 0;
}
