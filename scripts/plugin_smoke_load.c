/* Loads the built plugin the way Unity does (dlopen of the file, every function looked up by
 * name) and runs it end to end: a replay of a capture through the session's threads and the
 * pose model in ONNX Runtime, loaded from an explicit path. With RTLD_NOW every symbol the plugin
 * needs from glibc is bound at load, so on an older glibc a too-new symbol fails right here.
 *
 * Usage: plugin_smoke_load PLUGIN.so MODEL.onnx LIBONNXRUNTIME.so CAPTURE.cap
 * Prints one line naming glibc, engine, model and how many poses were solved; exit 0 when the
 * replay produced finite unit-quaternion poses, 1 (with the reason on stderr) otherwise. */
#include <dlfcn.h>
#include <gnu/libc-version.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "mocap_imu.h"

#define POSE_BATCH 64
#define REPLAY_TIMEOUT_S 120.0

static void *plugin;

static int fail(const char *what) {
    fprintf(stderr, "plugin_smoke_load: %s\n", what);
    return 1;
}

/* Looks a function of the plugin up by name into a pointer of the header's type. */
#define BIND(name)                                                                        \
    __typeof__(&name) p_##name = (__typeof__(&name))dlsym(plugin, #name);                 \
    if (!p_##name) return fail("the plugin does not export " #name);

static double seconds_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static int pose_is_sane(const mocap_pose *pose) {
    for (int j = 0; j < MOCAP_JOINT_COUNT; j++) {
        const float *q = pose->joint_rotations[j];
        double norm = sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] +
                           (double)q[3] * q[3]);
        if (!isfinite(norm) || fabs(norm - 1.0) > 1e-3) return 0;
        for (int k = 0; k < 3; k++)
            if (!isfinite(pose->joint_positions[j][k])) return 0;
    }
    return 1;
}

int main(int argc, char **argv) {
    static mocap_pose poses[POSE_BATCH];
    char message[512];
    if (argc != 5)
        return fail("usage: plugin_smoke_load PLUGIN.so MODEL.onnx LIBONNXRUNTIME.so CAPTURE.cap");

    plugin = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!plugin) {
        snprintf(message, sizeof message, "dlopen failed: %s", dlerror());
        return fail(message);
    }
    BIND(mocap_api_version) BIND(mocap_version_string) BIND(mocap_last_error)
    BIND(mocap_model_options_defaults) BIND(mocap_model_open) BIND(mocap_model_get_info)
    BIND(mocap_model_close) BIND(mocap_config_defaults) BIND(mocap_session_open)
    BIND(mocap_session_start) BIND(mocap_session_close) BIND(mocap_solver_config_defaults)
    BIND(mocap_solver_open) BIND(mocap_solver_add_character) BIND(mocap_solver_start)
    BIND(mocap_solver_drain) BIND(mocap_solver_close)

    if (p_mocap_api_version() != MOCAP_API_VERSION) {
        snprintf(message, sizeof message, "API version %d, the header says %d",
                 (int)p_mocap_api_version(), MOCAP_API_VERSION);
        return fail(message);
    }

    mocap_model_options options;
    p_mocap_model_options_defaults(&options);
    snprintf(options.onnxruntime_path, sizeof options.onnxruntime_path, "%s", argv[3]);
    mocap_model *model = NULL;
    mocap_model_info info;
    if (p_mocap_model_open(argv[2], &options, &model) != MOCAP_OK ||
        p_mocap_model_get_info(model, &info) != MOCAP_OK) {
        snprintf(message, sizeof message, "model: %s", p_mocap_last_error());
        return fail(message);
    }

    mocap_session_config config;
    p_mocap_config_defaults(&config);
    config.source_kind = MOCAP_SOURCE_REPLAY;
    snprintf(config.path, sizeof config.path, "%s", argv[4]);
    config.output_rate_hz = info.frame_rate;
    mocap_session *session = NULL;
    if (p_mocap_session_open(&config, &session) != MOCAP_OK) {
        snprintf(message, sizeof message, "session: %s", p_mocap_last_error());
        return fail(message);
    }

    /* Uncalibrated frames are solved too: the point is that inference runs, not the pose. */
    mocap_solver_config solver_config;
    p_mocap_solver_config_defaults(&solver_config);
    solver_config.require_calibration = 0;
    mocap_solver *solver = NULL;
    int32_t character = -1;
    if (p_mocap_solver_open(model, &solver_config, &solver) != MOCAP_OK ||
        p_mocap_solver_add_character(solver, session, &character) != MOCAP_OK ||
        p_mocap_solver_start(solver) != MOCAP_OK || p_mocap_session_start(session) != MOCAP_OK) {
        snprintf(message, sizeof message, "solver: %s", p_mocap_last_error());
        return fail(message);
    }

    unsigned long solved = 0, insane = 0;
    mocap_status status = MOCAP_OK;
    double deadline = seconds_now() + REPLAY_TIMEOUT_S;
    while (seconds_now() < deadline) {
        uint32_t count = 0;
        status = p_mocap_solver_drain(solver, character, poses, POSE_BATCH, &count);
        for (uint32_t i = 0; i < count; i++) insane += !pose_is_sane(&poses[i]);
        solved += count;
        if (status == MOCAP_ERR_END_OF_STREAM) break;
        if (status == MOCAP_ERR_NO_DATA) {
            struct timespec pause = {0, 2000000};
            nanosleep(&pause, NULL);
        } else if (status != MOCAP_OK) {
            break;
        }
    }
    p_mocap_solver_close(solver);
    p_mocap_session_close(session);
    p_mocap_model_close(model);

    if (status != MOCAP_ERR_END_OF_STREAM) {
        snprintf(message, sizeof message, "the replay did not finish (status %d after %lu poses)",
                 (int)status, solved);
        return fail(message);
    }
    if (solved == 0) return fail("the replay produced no pose");
    if (insane > 0) {
        snprintf(message, sizeof message, "%lu of %lu poses have non-finite or non-unit joints",
                 insane, solved);
        return fail(message);
    }
    printf("plugin_smoke_load: glibc %s: engine %s (API %d) solved %lu poses of %s with model %s\n",
           gnu_get_libc_version(), p_mocap_version_string(), (int)p_mocap_api_version(), solved,
           argv[4], info.model_name);
    dlclose(plugin);
    return 0;
}
