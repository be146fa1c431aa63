/* Loads the built mocap_imu.dll the way Unity does (by path, symbols looked up at run time) and
 * opens the shipped pose model with ONNX Runtime given by explicit path: the Windows plugin's
 * smoke test, run under Wine by scripts/build_windows_plugin.sh.
 * Usage: windows_plugin_smoke.exe PLUGIN.dll MODEL.onnx onnxruntime.dll */
#define WIN32_LEAN_AND_MEAN
#include <windows.h>

#include <stdio.h>
#include <string.h>

#include "mocap_imu.h"

typedef const char *(*text_fn)(void);
typedef mocap_status (*options_defaults_fn)(mocap_model_options *);
typedef mocap_status (*model_open_fn)(const char *, const mocap_model_options *, mocap_model **);
typedef mocap_status (*model_info_fn)(const mocap_model *, mocap_model_info *);
typedef void (*model_close_fn)(mocap_model *);

static FARPROC need(HMODULE plugin, const char *name)
{
    FARPROC f = GetProcAddress(plugin, name);
    if (!f) fprintf(stderr, "windows_plugin_smoke: the plugin does not export %s\n", name);
    return f;
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: windows_plugin_smoke PLUGIN.dll MODEL.onnx onnxruntime.dll\n");
        return 2;
    }
    HMODULE plugin = LoadLibraryA(argv[1]);
    if (!plugin) {
        fprintf(stderr, "windows_plugin_smoke: cannot load %s (Windows error %lu)\n", argv[1],
                (unsigned long)GetLastError());
        return 1;
    }
    text_fn version = (text_fn)(void (*)(void))need(plugin, "mocap_version_string");
    text_fn last_error = (text_fn)(void (*)(void))need(plugin, "mocap_last_error");
    options_defaults_fn defaults = (options_defaults_fn)(void (*)(void))need(plugin, "mocap_model_options_defaults");
    model_open_fn open_model = (model_open_fn)(void (*)(void))need(plugin, "mocap_model_open");
    model_info_fn get_info = (model_info_fn)(void (*)(void))need(plugin, "mocap_model_get_info");
    model_close_fn close_model = (model_close_fn)(void (*)(void))need(plugin, "mocap_model_close");
    if (!version || !last_error || !defaults || !open_model || !get_info || !close_model) return 1;

    mocap_model_options options;
    if (defaults(&options) != MOCAP_OK) return 1;
    if (strlen(argv[3]) >= sizeof options.onnxruntime_path) return 1;
    strcpy(options.onnxruntime_path, argv[3]);
    mocap_model *model = NULL;
    if (open_model(argv[2], &options, &model) != MOCAP_OK) {
        fprintf(stderr, "windows_plugin_smoke: mocap_model_open: %s\n", last_error());
        return 1;
    }
    mocap_model_info info;
    if (get_info(model, &info) != MOCAP_OK) {
        fprintf(stderr, "windows_plugin_smoke: mocap_model_get_info: %s\n", last_error());
        close_model(model);
        return 1;
    }
    printf("engine %s opened %s (%s, %.0f Hz) with ONNX Runtime from %s\n", version(),
           info.model_name, info.precision, info.frame_rate, argv[3]);
    close_model(model);
    return 0;
}
