/* Finding and opening the pose model (pose_model.h). */
#include "pose_model.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <direct.h>
#define getcwd _getcwd
#else
#include <unistd.h>
#endif

#include "output_file.h"

/* Looks for the shipped model in dir and its parents (up to 8 levels). */
static int find_upwards(const char *dir, char *out, size_t cap)
{
    char base[2048];
    snprintf(base, sizeof base, "%.2000s", dir);
    for (int level = 0; level < 8 && base[0]; ++level) {
        snprintf(out, cap, "%s/%s", base, MOCAPCTL_SHIPPED_MODEL);
        if (file_exists(out)) return 1;
        char *slash = strrchr(base, '/');
        if (!slash) break;
        if (slash == base) {
            base[1] = 0;
            if (level > 0 && strcmp(base, "/") == 0) break;
        } else {
            *slash = 0;
        }
    }
    return 0;
}

int pose_model_default_path(char *out, size_t cap)
{
    const char *env = getenv("MOCAP_MODEL");
    if (env && env[0]) {
        snprintf(out, cap, "%s", env);
        return 0;
    }
    char exe[4096] = "";
#if defined(__linux__)
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) exe[n] = 0;
    else exe[0] = 0;
#endif
    if (exe[0]) {
        char *slash = strrchr(exe, '/');
        if (slash) *slash = 0;
        if (find_upwards(exe, out, cap)) return 0;
    }
    char cwd[4096];
    if (getcwd(cwd, sizeof cwd) && find_upwards(cwd, out, cap)) return 0;
#if defined(MOCAP_SHIPPED_MODEL)
    if (file_exists(MOCAP_SHIPPED_MODEL)) {
        snprintf(out, cap, "%s", MOCAP_SHIPPED_MODEL);
        return 0;
    }
#endif
    snprintf(out, cap, "%s above %s or the current directory (set --model or MOCAP_MODEL)",
             MOCAPCTL_SHIPPED_MODEL, exe[0] ? exe : "the executable");
    return -1;
}

int pose_model_open(const char *model_arg, mocap_model **model, mocap_model_info *info)
{
    char path[4096];
    if (model_arg) {
        snprintf(path, sizeof path, "%s", model_arg);
    } else if (pose_model_default_path(path, sizeof path) != 0) {
        fprintf(stderr, "mocapctl: no --model given and the shipped model was not found: %s\n", path);
        return 1;
    }
    mocap_status s = mocap_model_open(path, NULL, model);
    if (s != MOCAP_OK) {
        fprintf(stderr, "mocapctl: loading model %s: %s (%s)\n", path, mocap_last_error(),
                mocap_status_name(s));
        return 1;
    }
    mocap_model_get_info(*model, info);
    printf("model %s: %s, %s, %.0f Hz, state %d x %d\n", path, info->model_name, info->precision,
           info->frame_rate, info->state_layers, info->state_size);
    return 0;
}
