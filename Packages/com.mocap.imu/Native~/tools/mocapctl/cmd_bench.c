/* mocapctl bench decode | pipeline|latency|scaling|tip|all: figures, not tests (bench.c runs
 * them; this file turns the command line into its options). */
#include <stdio.h>
#include <string.h>

#include "bench.h"
#include "cli_args.h"
#include "commands.h"
#include "mocap_imu.h"
#include "pose_model.h"
#include "sensor_set.h"

int cmd_bench_decode(int argc, char **argv)
{
    double mb_per_s = 0;
    return mocapctl_bench_decode(cli_number(argc, argv, "--seconds", 3.0, 0.1, 86400.0), &mb_per_s);
}

int cmd_bench(int argc, char **argv)
{
    if (argc < 1) return mocapctl_usage_error("bench");
    const char *which = argv[0];
    --argc;
    ++argv;
    static char model[4096], shipped[4096], root[4096];
    const char *model_arg = cli_value(argc, argv, "--model");
    int have_shipped = pose_model_default_path(shipped, sizeof shipped) == 0;
    if (model_arg) {
        snprintf(model, sizeof model, "%s", model_arg);
    } else if (have_shipped) {
        snprintf(model, sizeof model, "%s", shipped);
    } else {
        fprintf(stderr, "mocapctl: no --model given and the shipped model was not found: %s\n", shipped);
        return 1;
    }
    mocapctl_bench_options o;
    memset(&o, 0, sizeof o);
    o.model_path = model;
    o.tip_model_path = cli_value(argc, argv, "--tip-model");
    /* The repository above the shipped model runs `python3 -m training tip-model`. */
    if (have_shipped) {
        snprintf(root, sizeof root, "%s", shipped);
        char *cut = strstr(root, "/Packages/com.mocap.imu/");
        if (cut) {
            *cut = 0;
            o.repo_root = root;
        }
    }
    o.seconds = cli_number(argc, argv, "--seconds", 30.0, 0.1, 86400.0);
    o.latency_seconds = cli_number(argc, argv, "--latency-seconds", 10.0, 0.1, 86400.0);
    o.tip_seconds = cli_number(argc, argv, "--tip-seconds", 3.0, 0.1, 86400.0);
    o.threads = (int)cli_integer(argc, argv, "--threads", 1, 1, 256);
    o.max_characters = (int)cli_integer(argc, argv, "--max-characters", 32, 1, MOCAP_MAX_CHARACTERS);
    mocap_session_config set;
    mocap_config_defaults(&set);
    if (sensor_set_from_args(argc, argv, &set) != 0) return 2;
    o.sensor_count = set.sensor_count;
    for (uint32_t i = 0; i < set.sensor_count; ++i) {
        o.sensor_segments[i] = set.sensor_segments[i];
        o.node_ids[i] = set.node_ids[i];
    }
    o.optional_mask = set.optional_mask;
    return mocapctl_bench_model(which, &o);
}
