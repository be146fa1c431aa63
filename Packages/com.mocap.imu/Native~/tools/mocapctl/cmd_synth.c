/* mocapctl synth: a capture of a known motion (built-in, or a trajectory file:
 * docs/synth-trajectory.md) with its calibration prelude and, with --truth, the truth CSV. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_args.h"
#include "commands.h"
#include "report.h"
#include "sensor_set.h"
#include "synth.h"

#define SILENCE_FORMAT "SEGMENT@START+LENGTH (seconds of motion time, e.g. left_wrist@10+5)"

/* "SEGMENT@START+LENGTH" into out (the segment by name, whether or not it has a sensor). 0, or
 * -1 after printing why. */
static int parse_silence(const char *text, synth_silence *out)
{
    const char *at = strchr(text, '@');
    char name[64];
    if (!at || at == text || (size_t)(at - text) >= sizeof name) {
        fprintf(stderr, "mocapctl: --silence wants " SILENCE_FORMAT ", got '%s'\n", text);
        return -1;
    }
    memcpy(name, text, (size_t)(at - text));
    name[at - text] = '\0';
    out->segment = mocap_segment_find(name);
    if (out->segment < 0) {
        fprintf(stderr, "mocapctl: --silence %s: no segment '%s' (", text, name);
        for (int32_t s = 0; s < mocap_segment_count(); ++s)
            fprintf(stderr, "%s%s", s ? ", " : "", mocap_segment_name(s));
        fputs(")\n", stderr);
        return -1;
    }
    char *end = NULL;
    errno = 0;
    out->start_s = strtod(at + 1, &end);
    int bad = end == at + 1 || *end != '+' || errno == ERANGE;
    if (!bad) {
        const char *length = end + 1;
        out->length_s = strtod(length, &end);
        bad = end == length || *end != '\0' || errno == ERANGE;
    }
    if (bad) {
        fprintf(stderr, "mocapctl: --silence wants " SILENCE_FORMAT ", got '%s'\n", text);
        return -1;
    }
    if (!(isfinite(out->start_s) && out->start_s >= 0.0 && isfinite(out->length_s) &&
          out->length_s > 0.0 && out->start_s + out->length_s <= 86400.0)) {
        fprintf(stderr, "mocapctl: --silence %s: the start must be >= 0 s and the length > 0 s, "
                        "within a day\n", text);
        return -1;
    }
    return 0;
}

/* Every --silence of the command line into cfg, each checked against the sensor set. 0, or 2
 * after printing the usage error. */
static int silences_from_args(int argc, char **argv, synth_config *cfg)
{
    cfg->silence_count = 0;
    for (int i = 0; i < argc; ++i) {
        if (strcmp(argv[i], "--silence") != 0) continue;
        const char *text = cli_value(argc - i, argv + i, "--silence");
        if (cfg->silence_count == SYNTH_MAX_SILENCES) {
            fprintf(stderr, "mocapctl: more than %d --silence windows\n", SYNTH_MAX_SILENCES);
            return 2;
        }
        synth_silence *sl = &cfg->silences[cfg->silence_count];
        if (parse_silence(text, sl) != 0) return 2;
        int in_set = 0;
        for (uint32_t k = 0; k < cfg->sensor_count; ++k) in_set |= cfg->segments[k] == sl->segment;
        if (!in_set) {
            fprintf(stderr, "mocapctl: --silence %s: %s has no sensor in the set (--sensors)\n",
                    text, mocap_segment_name(sl->segment));
            return 2;
        }
        cfg->silence_count++;
    }
    return 0;
}

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
    if (silences_from_args(argc, argv, &cfg) != 0) return 2;
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
    for (uint32_t w = 0; w < cfg.silence_count; ++w) {
        const synth_silence *sl = &cfg.silences[w];
        const double shown_length = cfg.motion_s < motion_length ? cfg.motion_s : motion_length;
        printf("  %s silent from %.3f s to %.3f s of the motion\n", mocap_segment_name(sl->segment),
               sl->start_s, sl->start_s + sl->length_s);
        if (sl->start_s >= shown_length)
            fprintf(stderr, "mocapctl: note: the %s silence starts after the motion's end (%.1f s)\n",
                    mocap_segment_name(sl->segment), shown_length);
    }
    if (clipped)
        fprintf(stderr, "mocapctl: note: the motion ends after %.1f s, so the capture is shorter "
                        "than --seconds %s\n", motion_length, cli_value(argc, argv, "--seconds"));
    return 0;
}
