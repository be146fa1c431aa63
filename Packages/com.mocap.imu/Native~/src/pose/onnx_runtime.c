/* The pose model through ONNX Runtime, loaded at run time. See onnx_runtime.h and
 * docs/model-contract.md. */
#if !defined(_WIN32) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* RTLD_DEFAULT, dladdr */
#endif

#include "onnx_runtime.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "network_geometry.h"
#include "platform.h"
#include "smpl_skeleton.h"
#include "text_number.h"

void ort_options_defaults(ort_options *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    o->optimization_level = 3;
    o->provider = ORT_PROVIDER_CPU;
}

#if !defined(MOCAP_HAVE_ONNXRUNTIME)

/* ---------------------------------------------------------------------------------------- */
/* Built without the ONNX Runtime headers.                                                      */

#define ORT_MISSING                                                                             \
    mocap_fail(MOCAP_ERR_UNSUPPORTED,                                                           \
               "this engine was built without ONNX Runtime headers: run "                      \
               "scripts/fetch_onnxruntime.sh, then re-run cmake (MOCAP_ONNXRUNTIME_DIR)")

mocap_status ort_library_load(const char *library_path) { (void)library_path; return ORT_MISSING; }
int ort_library_available(const char *library_path) { (void)library_path; ORT_MISSING; return 0; }
const char *ort_library_version(void) { return ""; }
const char *ort_library_path(void) { return ""; }
mocap_status ort_model_open(const char *path, const ort_options *options, ort_model **out)
{
    (void)path; (void)options;
    if (out) *out = NULL;
    return ORT_MISSING;
}
void ort_model_close(ort_model *m) { (void)m; }
const ort_model_info *ort_model_get_info(const ort_model *m) { (void)m; return NULL; }
mocap_status ort_stream_create(ort_model *m, int batch, int frames, ort_stream **out)
{
    (void)m; (void)batch; (void)frames;
    if (out) *out = NULL;
    return ORT_MISSING;
}
void ort_stream_destroy(ort_stream *s) { (void)s; }
int ort_stream_batch(const ort_stream *s) { (void)s; return 0; }
int ort_stream_frames(const ort_stream *s) { (void)s; return 0; }
float *ort_stream_orientation(ort_stream *s) { (void)s; return NULL; }
float *ort_stream_acceleration(ort_stream *s) { (void)s; return NULL; }
float *ort_stream_mask(ort_stream *s) { (void)s; return NULL; }
const float *ort_stream_joint_rotations(const ort_stream *s) { (void)s; return NULL; }
const float *ort_stream_root_velocity(const ort_stream *s) { (void)s; return NULL; }
const float *ort_stream_foot_contact(const ort_stream *s) { (void)s; return NULL; }
float *ort_stream_state_h(ort_stream *s) { (void)s; return NULL; }
float *ort_stream_state_c(ort_stream *s) { (void)s; return NULL; }
size_t ort_stream_state_count(const ort_stream *s) { (void)s; return 0; }
void ort_stream_reset_state(ort_stream *s) { (void)s; }
mocap_status ort_stream_run(ort_stream *s) { (void)s; return ORT_MISSING; }

#else /* MOCAP_HAVE_ONNXRUNTIME */

#include "onnxruntime_c_api.h"


/* ONNX Runtime 1.29's CreateEnv leaks 14 bytes inside the library even after ReleaseEnv (a
 * ten-line dlopen + CreateEnv + ReleaseEnv program shows it under LeakSanitizer). Sanitizer builds
 * suppress leaks whose allocation comes from libonnxruntime so that ours still fail the tests. */
#if defined(__SANITIZE_ADDRESS__)
#define MOCAP_LSAN_HOOK 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MOCAP_LSAN_HOOK 1
#endif
#endif
#if defined(MOCAP_LSAN_HOOK)
__attribute__((visibility("default"))) const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void) { return "leak:libonnxruntime.so\n"; }
#endif

/* ---------------------------------------------------------------------------------------- */
/* The library: loaded once per process, never unloaded (sessions may outlive any owner).      */

static mocap_atomic_int g_lock;
static int g_loaded;              /* 1 after a successful load (read under g_lock) */
static const OrtApi *g_api;
static OrtEnv *g_env;
static char g_path[1024];
static char g_version[64];

static void lock_global(void)
{
    while (mocap_atomic_exchange_int(&g_lock, 1) != 0) mocap_sleep_ms(1);
}
static void unlock_global(void) { mocap_atomic_store_int(&g_lock, 0); }

/* Try one file: on success fills the globals. why receives the reason of a failure. */
static int try_library(const char *path, char *why, size_t why_cap)
{
    void *h = mocap_library_open(path, why, why_cap);
    if (!h) return 0;
    typedef const OrtApiBase *(ORT_API_CALL * get_base_fn)(void);
    get_base_fn get_base = (get_base_fn)mocap_library_symbol(h, "OrtGetApiBase");
    if (!get_base) {
        snprintf(why, why_cap, "%s has no OrtGetApiBase: not ONNX Runtime", path);
        mocap_library_close(h);
        return 0;
    }
    const OrtApiBase *base = get_base();
    const char *version = base && base->GetVersionString ? base->GetVersionString() : "?";
    const OrtApi *api = base ? base->GetApi(ORT_API_VERSION) : NULL;
    if (!api) {
        snprintf(why, why_cap,
                 "%s is ONNX Runtime %s, which lacks C API version %d (ONNX Runtime 1.%d or newer "
                 "is needed)", path, version, ORT_API_VERSION, ORT_API_VERSION);
        mocap_library_close(h);
        return 0;
    }
    OrtEnv *env = NULL;
    OrtStatus *st = api->CreateEnv(ORT_LOGGING_LEVEL_ERROR, "mocap", &env);
    if (st) {
        snprintf(why, why_cap, "%s: creating the ONNX Runtime environment failed: %s", path,
                 api->GetErrorMessage(st));
        api->ReleaseStatus(st);
        mocap_library_close(h);
        return 0;
    }
    g_api = api;
    g_env = env;
    snprintf(g_path, sizeof g_path, "%s", path);
    snprintf(g_version, sizeof g_version, "%s", version);
    return 1;
}

mocap_status ort_library_load(const char *library_path)
{
    lock_global();
    if (g_loaded) {
        unlock_global();
        return MOCAP_OK;
    }
    char tried[1536] = "";
    char why[512];
    const char *candidates[8];
    int n = 0;
    const char *env = getenv("MOCAP_ONNXRUNTIME_PATH");
    if (library_path && library_path[0]) {
        candidates[n++] = library_path; /* an explicit path is the only one tried */
    } else if (env && env[0]) {
        /* So is the variable: a typo in it must not quietly load another build (a CPU one in
         * place of the CUDA one asked for). */
        candidates[n++] = env;
    } else {
#if defined(MOCAP_ONNXRUNTIME_DEFAULT_LIB)
        candidates[n++] = MOCAP_ONNXRUNTIME_DEFAULT_LIB;
#endif
#if defined(_WIN32)
        candidates[n++] = "onnxruntime.dll";
#elif defined(__APPLE__)
        candidates[n++] = "libonnxruntime.dylib";
#else
        candidates[n++] = "libonnxruntime.so.1";
        candidates[n++] = "libonnxruntime.so";
#endif
    }
    for (int i = 0; i < n; ++i) {
        if (try_library(candidates[i], why, sizeof why)) {
            g_loaded = 1;
            unlock_global();
            return MOCAP_OK;
        }
        size_t len = strlen(tried);
        snprintf(tried + len, sizeof tried - len, "%s%s", len ? "; " : "", why);
    }
    unlock_global();
    return mocap_fail(MOCAP_ERR_UNSUPPORTED,
                      "ONNX Runtime could not be loaded (%s); run scripts/fetch_onnxruntime.sh or "
                      "set MOCAP_ONNXRUNTIME_PATH to libonnxruntime", tried);
}

int ort_library_available(const char *library_path)
{
    return ort_library_load(library_path) == MOCAP_OK;
}

const char *ort_library_version(void) { return g_loaded ? g_version : ""; }
const char *ort_library_path(void) { return g_loaded ? g_path : ""; }

/* ---------------------------------------------------------------------------------------- */
/* The contract                                                                                */

/* Contract 1 fixed the sensors to these six, in this order. */
static const char *const CONTRACT1_SENSORS = "pelvis,left_wrist,right_wrist,left_shin,right_shin,head";

enum { DIM_DYNAMIC = -1, DIM_LAYERS = -2, DIM_STATE = -3, DIM_SENSORS = -4, DIM_FEATURES = -5 };
typedef struct tensor_spec {
    const char *name;
    int rank;
    int64_t dims[5];
    const char *dim_names[5];
} tensor_spec;

/* The mask comes last: a contract-1 model has the first four inputs only. */
enum { IN_ORIENTATION, IN_ACCELERATION, IN_STATE_H, IN_STATE_C, IN_MASK, INPUT_COUNT };
enum { OUT_ROTATIONS, OUT_VELOCITY, OUT_CONTACT, OUT_STATE_H, OUT_STATE_C, OUTPUT_COUNT };

static const tensor_spec INPUT_SPECS[INPUT_COUNT] = {
    {"imu_orientation", 5, {DIM_DYNAMIC, DIM_DYNAMIC, DIM_SENSORS, 3, 3}, {"B", "T", "N", "3", "3"}},
    {"imu_acceleration", 4, {DIM_DYNAMIC, DIM_DYNAMIC, DIM_SENSORS, 3}, {"B", "T", "N", "3"}},
    {"state_in_h", 3, {DIM_LAYERS, DIM_DYNAMIC, DIM_STATE}, {"L", "B", "H"}},
    {"state_in_c", 3, {DIM_LAYERS, DIM_DYNAMIC, DIM_STATE}, {"L", "B", "H"}},
    {"imu_mask", 3, {DIM_DYNAMIC, DIM_DYNAMIC, DIM_SENSORS}, {"B", "T", "N"}},
};
static const tensor_spec OUTPUT_SPECS[OUTPUT_COUNT] = {
    {"joint_rotations", 5, {DIM_DYNAMIC, DIM_DYNAMIC, 24, 3, 3}, {"B", "T", "24", "3", "3"}},
    {"root_velocity", 3, {DIM_DYNAMIC, DIM_DYNAMIC, 3}, {"B", "T", "3"}},
    {"foot_contact", 3, {DIM_DYNAMIC, DIM_DYNAMIC, 2}, {"B", "T", "2"}},
    {"state_out_h", 3, {DIM_LAYERS, DIM_DYNAMIC, DIM_STATE}, {"L", "B", "H"}},
    {"state_out_c", 3, {DIM_LAYERS, DIM_DYNAMIC, DIM_STATE}, {"L", "B", "H"}},
};
static const char *const INPUT_NAMES[INPUT_COUNT] = {"imu_orientation", "imu_acceleration",
                                                     "state_in_h", "state_in_c", "imu_mask"};
static const char *const OUTPUT_NAMES[OUTPUT_COUNT] = {"joint_rotations", "root_velocity",
                                                       "foot_contact", "state_out_h",
                                                       "state_out_c"};

/* Contract 3: the learned network alone, the geometry done here (network_geometry.h). Its rows
 * are R = B x rows per character (2 with the mirror average, interleaved: a character's plain
 * row, then its mirrored one), so its state [L][R][H / rows] lies in memory exactly as the
 * [L][B][H] state of the stream. */
enum { IN3_FEATURES, IN3_STATE_H, IN3_STATE_C, INPUT3_COUNT };
enum { OUT3_NETWORK, OUT3_STATE_H, OUT3_STATE_C, OUTPUT3_COUNT };
static const tensor_spec INPUT3_SPECS[INPUT3_COUNT] = {
    {"network_input", 3, {DIM_DYNAMIC, DIM_DYNAMIC, DIM_FEATURES}, {"R", "T", "F"}},
    {"state_in_h", 3, {DIM_LAYERS, DIM_DYNAMIC, DIM_STATE}, {"L", "R", "H / rows"}},
    {"state_in_c", 3, {DIM_LAYERS, DIM_DYNAMIC, DIM_STATE}, {"L", "R", "H / rows"}},
};
static const tensor_spec OUTPUT3_SPECS[OUTPUT3_COUNT] = {
    {"network_output", 3, {DIM_DYNAMIC, DIM_DYNAMIC, GEOMETRY_OUTPUTS}, {"R", "T", "149"}},
    {"state_out_h", 3, {DIM_LAYERS, DIM_DYNAMIC, DIM_STATE}, {"L", "R", "H / rows"}},
    {"state_out_c", 3, {DIM_LAYERS, DIM_DYNAMIC, DIM_STATE}, {"L", "R", "H / rows"}},
};
static const char *const INPUT3_NAMES[INPUT3_COUNT] = {"network_input", "state_in_h", "state_in_c"};
static const char *const OUTPUT3_NAMES[OUTPUT3_COUNT] = {"network_output", "state_out_h",
                                                         "state_out_c"};

struct ort_model {
    OrtSession *session;
    OrtMemoryInfo *memory;
    ort_model_info info;
    network_geometry geometry; /* contract 3 */
    char path[1024];
};

struct ort_stream {
    ort_model *model;
    int batch, frames;
    size_t state_count;
    int parity; /* which state buffer pair feeds the next run */
    float *block; /* one allocation for every buffer below */
    float *orientation, *acceleration, *mask, *rotations, *velocity, *contact;
    float *state_h[2], *state_c[2];
    float *features, *network_output; /* contract 3: the graph's own input and output */
    geometry_row *rows;               /* contract 3: [B][T][rows] */
    OrtValue *v_orientation, *v_acceleration, *v_mask, *v_rotations, *v_velocity, *v_contact;
    OrtValue *v_features, *v_network_output;
    OrtValue *v_state_h[2], *v_state_c[2];
    const OrtValue *inputs[2][INPUT_COUNT];
    OrtValue *outputs[2][OUTPUT_COUNT];
};

/* Turn an OrtStatus into our status + message; releases it. */
static mocap_status ort_error(OrtStatus *st, mocap_status code, const char *what, const char *path)
{
    mocap_status r = mocap_fail(code, "%s%s%s: %s", path ? "model " : "", path ? path : "",
                                what, g_api->GetErrorMessage(st));
    g_api->ReleaseStatus(st);
    return r;
}

/* For calls whose failure changes nothing (frees). */
static void release(OrtStatus *st)
{
    if (st) g_api->ReleaseStatus(st);
}

/* ---------------------------------------------------------------------------------------- */
/* Metadata parsing                                                                            */

/* The value of key or NULL (malloc'd copy; caller frees). */
static char *metadata_value(OrtModelMetadata *md, OrtAllocator *alloc, const char *key)
{
    char *v = NULL;
    OrtStatus *st = g_api->ModelMetadataLookupCustomMetadataMap(md, alloc, key, &v);
    if (st) {
        g_api->ReleaseStatus(st);
        return NULL;
    }
    if (!v) return NULL;
    size_t len = strlen(v);
    char *copy = (char *)malloc(len + 1);
    if (copy) memcpy(copy, v, len + 1);
    release(g_api->AllocatorFree(alloc, v));
    return copy;
}

/* Split a comma-separated list in place; trims blanks. Returns the count (at most cap). */
static int split_list(char *s, char **items, int cap, int *overflow)
{
    int n = 0;
    *overflow = 0;
    char *p = s;
    for (;;) {
        char *comma = strchr(p, ',');
        if (comma) *comma = '\0';
        while (isspace((unsigned char)*p)) ++p;
        size_t len = strlen(p);
        while (len > 0 && isspace((unsigned char)p[len - 1])) p[--len] = '\0';
        if (n < cap) items[n] = p;
        else *overflow = 1;
        ++n;
        if (!comma) break;
        p = comma + 1;
    }
    return n;
}

static int parse_int(const char *s, long *out)
{
    char *end;
    if (!s || !*s) return 0;
    long v = strtol(s, &end, 10);
    while (isspace((unsigned char)*end)) ++end;
    if (*end) return 0;
    *out = v;
    return 1;
}

static int parse_double(const char *s, double *out)
{
    char *end;
    if (!s || !*s) return 0;
    double v = text_strtod(s, &end); /* written with '.', read in any locale */
    while (isspace((unsigned char)*end)) ++end;
    if (*end || !isfinite(v)) return 0;
    *out = v;
    return 1;
}

static const char *const REQUIRED_KEYS[] = {
    "mocap.contract_version", "mocap.frame_rate",   "mocap.sensor_order", "mocap.joint_names",
    "mocap.joint_parents",    "mocap.rest_offsets", "mocap.state_layers", "mocap.state_size",
    "mocap.precision",        "mocap.model_name"};
#define KEY_COUNT ((int)(sizeof REQUIRED_KEYS / sizeof REQUIRED_KEYS[0]))

/* Contract 2's sensor list: names from the segment table, each once, and which are required
 * (required_text NULL: all). Fills info's sensor fields; a message names what is wrong. */
static mocap_status parse_sensor_set(ort_model_info *info, const char *path, char *order_text,
                                     char *required_text)
{
    char *items[MOCAP_MAX_SENSORS + 1];
    int overflow = 0;
    int n = split_list(order_text, items, MOCAP_MAX_SENSORS + 1, &overflow);
    if (n < 1 || n > MOCAP_MAX_SENSORS || overflow)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.sensor_order lists %d sensors; the "
                          "engine carries 1..%d", path, n, MOCAP_MAX_SENSORS);
    for (int k = 0; k < n; ++k) {
        int32_t seg = mocap_segment_find(items[k]);
        if (seg < 0)
            return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.sensor_order[%d] '%s' is not a "
                              "segment this engine knows", path, k, items[k]);
        for (int o = 0; o < k; ++o)
            if (info->sensor_segments[o] == seg)
                return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.sensor_order names '%s' "
                                  "twice", path, items[k]);
        info->sensor_segments[k] = seg;
    }
    info->sensor_count = n;
    info->required_mask = (1u << n) - 1u;
    if (!required_text) return MOCAP_OK;
    char *flags[MOCAP_MAX_SENSORS + 1];
    int m = split_list(required_text, flags, MOCAP_MAX_SENSORS + 1, &overflow);
    if (m != n)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.sensor_required has %d entries for "
                          "the %d sensors of mocap.sensor_order", path, m, n);
    info->required_mask = 0;
    for (int k = 0; k < n; ++k) {
        if (strcmp(flags[k], "1") == 0) info->required_mask |= 1u << k;
        else if (strcmp(flags[k], "0") != 0)
            return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.sensor_required[%d] is '%s', "
                              "expected 1 (required) or 0 (optional)", path, k, flags[k]);
    }
    if (info->required_mask == 0)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.sensor_required makes every sensor "
                          "optional; at least one must be required", path);
    return MOCAP_OK;
}

/* The optional pair mocap.training_height / mocap.stride_exponent: both or neither. */
static mocap_status parse_stride_scaling(ort_model_info *info, const char *path,
                                         const char *height_text, const char *exponent_text)
{
    info->has_stride_scaling = 0;
    if (!height_text && !exponent_text) return MOCAP_OK;
    if (!height_text || !exponent_text)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.%s is given without mocap.%s (the "
                          "two come together)", path,
                          height_text ? "training_height" : "stride_exponent",
                          height_text ? "stride_exponent" : "training_height");
    double height, exponent;
    if (!parse_double(height_text, &height) || height < MOCAP_HEIGHT_MIN_M || height > MOCAP_HEIGHT_MAX_M)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.training_height '%s' is not a "
                          "standing height in metres (%g..%g)", path, height_text,
                          (double)MOCAP_HEIGHT_MIN_M, (double)MOCAP_HEIGHT_MAX_M);
    if (!parse_double(exponent_text, &exponent) || exponent < 0.0 || exponent > 2.0)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.stride_exponent '%s' is not a "
                          "number in 0..2", path, exponent_text);
    info->has_stride_scaling = 1;
    info->training_height = height;
    info->stride_exponent = exponent;
    return MOCAP_OK;
}

/* Contract 3's keys for the geometry the engine does (see docs/model-contract.md). */
enum { GEO_SCALE, GEO_ANCHORS, GEO_MASKED, GEO_MIRROR, GEO_MIRROR_SENSORS, GEO_MIRROR_JOINTS,
       GEO_KEY_COUNT };
static const char *const GEOMETRY_KEYS[GEO_KEY_COUNT] = {
    "mocap.acceleration_scale", "mocap.anchor_joints", "mocap.masked_features",
    "mocap.mirror_average", "mocap.mirror_sensors", "mocap.mirror_joints"};

/* A list of exactly `count` integers in lo..hi into out; a message names the key otherwise. */
static mocap_status parse_int_list(const char *path, const char *key, char *text, int count,
                                   int lo, int hi, int *out)
{
    char *items[GEOMETRY_JOINTS + 1];
    int overflow = 0;
    int n = split_list(text, items, GEOMETRY_JOINTS + 1, &overflow);
    if (n != count || overflow)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %s has %d entries, expected %d", path, key,
                          n, count);
    for (int i = 0; i < n; ++i) {
        long v;
        if (!parse_int(items[i], &v) || v < lo || v > hi)
            return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %s[%d] is '%s', expected an integer "
                              "in %d..%d", path, key, i, items[i], lo, hi);
        out[i] = (int)v;
    }
    return MOCAP_OK;
}

static mocap_status parse_flag(const char *path, const char *key, const char *text, int *out)
{
    if (strcmp(text, "0") == 0 || strcmp(text, "1") == 0) {
        *out = text[0] == '1';
        return MOCAP_OK;
    }
    return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %s is '%s', expected 0 or 1", path, key, text);
}

/* Contract 3: what the geometry needs, from the keys (texts[GEO_*], NULL where absent). */
static mocap_status parse_geometry(ort_model *m, char **texts)
{
    const char *path = m->path;
    ort_model_info *info = &m->info;
    const int n = info->sensor_count;
    for (int k = 0; k < GEO_KEY_COUNT; ++k) {
        if (texts[k] || k == GEO_MIRROR_SENSORS || k == GEO_MIRROR_JOINTS) continue;
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: metadata key '%s' is missing (contract 3 "
                          "describes the geometry the engine does)", path, GEOMETRY_KEYS[k]);
    }
    double scale;
    if (!parse_double(texts[GEO_SCALE], &scale) || !(scale > 0.0) || scale > 1e6)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.acceleration_scale '%s' is not a "
                          "positive number", path, texts[GEO_SCALE]);
    int masked = 0, mirror = 0;
    mocap_status r = parse_flag(path, GEOMETRY_KEYS[GEO_MASKED], texts[GEO_MASKED], &masked);
    if (r == MOCAP_OK) r = parse_flag(path, GEOMETRY_KEYS[GEO_MIRROR], texts[GEO_MIRROR], &mirror);
    if (r != MOCAP_OK) return r;
    if (!masked && info->required_mask != (1u << n) - 1u)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.sensor_required makes a sensor "
                          "optional, but mocap.masked_features is 0: a network without the mask "
                          "needs every sensor", path);
    int anchors[MOCAP_MAX_SENSORS], mirror_sensors[MOCAP_MAX_SENSORS], mirror_joints[GEOMETRY_JOINTS];
    r = parse_int_list(path, GEOMETRY_KEYS[GEO_ANCHORS], texts[GEO_ANCHORS], n, 0,
                       GEOMETRY_JOINTS - 1, anchors);
    if (r != MOCAP_OK) return r;
    if (mirror) {
        for (int k = GEO_MIRROR_SENSORS; k <= GEO_MIRROR_JOINTS; ++k)
            if (!texts[k])
                return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.mirror_average is 1 but "
                                  "metadata key '%s' is missing", path, GEOMETRY_KEYS[k]);
        r = parse_int_list(path, GEOMETRY_KEYS[GEO_MIRROR_SENSORS], texts[GEO_MIRROR_SENSORS], n,
                           0, n - 1, mirror_sensors);
        if (r == MOCAP_OK)
            r = parse_int_list(path, GEOMETRY_KEYS[GEO_MIRROR_JOINTS], texts[GEO_MIRROR_JOINTS],
                               GEOMETRY_JOINTS, 0, GEOMETRY_JOINTS - 1, mirror_joints);
        if (r != MOCAP_OK) return r;
        if (info->state_size % 2 != 0)
            return mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.state_size %d is odd; with the "
                              "mirror average it holds both rows' state", path, info->state_size);
    }
    const int32_t pelvis_segment = mocap_segment_find("pelvis");
    int pelvis = -1;
    for (int k = 0; k < n; ++k)
        if (info->sensor_segments[k] == pelvis_segment) pelvis = k;
    r = network_geometry_init(&m->geometry, n, pelvis, masked, mirror, (float)scale,
                              mirror_sensors, mirror_joints, info->joint_parents, anchors);
    if (r != MOCAP_OK) {
        char why[512];
        snprintf(why, sizeof why, "%s", mocap_last_error());
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %s", path, why);
    }
    info->has_mask = masked;
    return MOCAP_OK;
}

static mocap_status read_metadata(ort_model *m)
{
    OrtModelMetadata *md = NULL;
    OrtAllocator *alloc = NULL;
    OrtStatus *st = g_api->GetAllocatorWithDefaultOptions(&alloc);
    if (!st) st = g_api->SessionGetModelMetadata(m->session, &md);
    if (st) return ort_error(st, MOCAP_ERR_FORMAT, ": reading metadata", m->path);

    char *values[KEY_COUNT] = {0};
    mocap_status r = MOCAP_OK;
    for (int k = 0; k < KEY_COUNT; ++k) values[k] = metadata_value(md, alloc, REQUIRED_KEYS[k]);
    char *required = metadata_value(md, alloc, "mocap.sensor_required");
    char *training_height = metadata_value(md, alloc, "mocap.training_height");
    char *stride_exponent = metadata_value(md, alloc, "mocap.stride_exponent");
    char *geometry[GEO_KEY_COUNT];
    for (int k = 0; k < GEO_KEY_COUNT; ++k) geometry[k] = metadata_value(md, alloc, GEOMETRY_KEYS[k]);
    g_api->ReleaseModelMetadata(md);
    ort_model_info *info = &m->info;
    const char *path = m->path;

    /* The version first: another version may legitimately differ in everything else. */
    long lv = 0;
    if (!values[0]) {
        r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: metadata key 'mocap.contract_version' is "
                       "missing (not a mocap pose model, see docs/model-contract.md)", path);
        goto done;
    }
    if (!parse_int(values[0], &lv) || lv < ORT_CONTRACT_MIN || lv > ORT_CONTRACT_MAX) {
        r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.contract_version is '%s'; this engine "
                       "accepts versions %d..%d", path, values[0], ORT_CONTRACT_MIN,
                       ORT_CONTRACT_MAX);
        goto done;
    }
    info->contract_version = (int)lv;
    for (int k = 1; k < KEY_COUNT; ++k)
        if (!values[k]) {
            r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: metadata key '%s' is missing", path,
                           REQUIRED_KEYS[k]);
            goto done;
        }
    if (!parse_double(values[1], &info->frame_rate) || info->frame_rate <= 0 ||
        info->frame_rate > 10000) {
        r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.frame_rate '%s' is not a positive "
                       "number", path, values[1]);
        goto done;
    }
    {   /* sensor order, compared without blanks */
        char compact[sizeof ((ort_model_info *)0)->sensor_order];
        size_t j = 0;
        for (const char *p = values[2]; *p && j + 1 < sizeof compact; ++p)
            if (!isspace((unsigned char)*p)) compact[j++] = *p;
        compact[j] = '\0';
        if (info->contract_version == 1) {
            if (strcmp(compact, CONTRACT1_SENSORS) != 0) {
                r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.sensor_order is '%s', contract "
                               "1 needs '%s'", path, values[2], CONTRACT1_SENSORS);
                goto done;
            }
            if (required) {
                r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.sensor_required belongs to "
                               "contract 2; contract 1 requires all six sensors", path);
                goto done;
            }
        }
        snprintf(info->sensor_order, sizeof info->sensor_order, "%s", compact);
        r = parse_sensor_set(info, path, values[2], required);
        if (r != MOCAP_OK) goto done;
        info->has_mask = info->contract_version >= 2;
    }
    char *items[80];
    int overflow = 0;
    int n = split_list(values[3], items, 80, &overflow);
    if (n != ORT_JOINTS) {
        r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.joint_names has %d names, the contract "
                       "has %d", path, n, ORT_JOINTS);
        goto done;
    }
    for (int j = 0; j < ORT_JOINTS; ++j) {
        if (strcmp(items[j], smpl_joint_name(j)) != 0) {
            r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.joint_names[%d] is '%s', the "
                           "contract has '%s'", path, j, items[j], smpl_joint_name(j));
            goto done;
        }
        snprintf(info->joint_names[j], ORT_NAME_CAP, "%s", items[j]);
    }
    n = split_list(values[4], items, 80, &overflow);
    if (n != ORT_JOINTS) {
        r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.joint_parents has %d entries, the "
                       "contract has %d", path, n, ORT_JOINTS);
        goto done;
    }
    for (int j = 0; j < ORT_JOINTS; ++j) {
        long p;
        if (!parse_int(items[j], &p) || p != smpl_joint_parent(j)) {
            r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.joint_parents[%d] (%s) is '%s', "
                           "the contract has %d", path, j, smpl_joint_name(j), items[j],
                           smpl_joint_parent(j));
            goto done;
        }
        info->joint_parents[j] = (int)p;
    }
    n = split_list(values[5], items, 80, &overflow);
    if (n != ORT_JOINTS * 3) {
        r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.rest_offsets has %d numbers, the "
                       "contract needs %d (24 joints x 3)", path, n, ORT_JOINTS * 3);
        goto done;
    }
    for (int i = 0; i < ORT_JOINTS * 3; ++i) {
        double v;
        if (!parse_double(items[i], &v) || fabs(v) > 10.0) {
            r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.rest_offsets[%d] '%s' is not an "
                           "offset in metres", path, i, items[i]);
            goto done;
        }
        info->rest_offsets[i / 3][i % 3] = (float)v;
    }
    long layers = 0, size = 0;
    if (!parse_int(values[6], &layers) || layers < 1 || layers > 64) {
        r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.state_layers '%s' is not a positive "
                       "integer", path, values[6]);
        goto done;
    }
    if (!parse_int(values[7], &size) || size < 1 || size > 1 << 20) {
        r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.state_size '%s' is not a positive "
                       "integer", path, values[7]);
        goto done;
    }
    info->state_layers = (int)layers;
    info->state_size = (int)size;
    if (strcmp(values[8], "fp32") != 0 && strcmp(values[8], "fp16") != 0 &&
        strcmp(values[8], "int8") != 0) {
        r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: mocap.precision is '%s', expected fp32, fp16 "
                       "or int8", path, values[8]);
        goto done;
    }
    snprintf(info->precision, sizeof info->precision, "%s", values[8]);
    snprintf(info->model_name, sizeof info->model_name, "%s", values[9]);
    r = parse_stride_scaling(info, path, training_height, stride_exponent);
    if (r == MOCAP_OK && info->contract_version >= 3) r = parse_geometry(m, geometry);
done:
    for (int k = 0; k < GEO_KEY_COUNT; ++k) free(geometry[k]);
    for (int k = 0; k < KEY_COUNT; ++k) free(values[k]);
    free(required);
    free(training_height);
    free(stride_exponent);
    return r;
}

/* ---------------------------------------------------------------------------------------- */
/* Input / output validation                                                                   */

static int network_only(const ort_model *m) { return m->info.contract_version >= 3; }

static int model_input_count(const ort_model *m)
{
    if (network_only(m)) return INPUT3_COUNT;
    return m->info.has_mask ? INPUT_COUNT : IN_MASK;
}
static int model_output_count(const ort_model *m)
{
    return network_only(m) ? OUTPUT3_COUNT : OUTPUT_COUNT;
}
static const char *const *input_names(const ort_model *m)
{
    return network_only(m) ? INPUT3_NAMES : INPUT_NAMES;
}
static const char *const *output_names(const ort_model *m)
{
    return network_only(m) ? OUTPUT3_NAMES : OUTPUT_NAMES;
}

/* The state size of the graph's tensors: a contract-3 graph holds each row's own. */
static int64_t graph_state_size(const ort_model *m)
{
    return network_only(m) ? m->info.state_size / network_geometry_rows(&m->geometry)
                           : m->info.state_size;
}

static mocap_status check_tensor(const ort_model *m, const char *kind, const tensor_spec *spec,
                                 OrtTypeInfo *type)
{
    const char *path = m->path;
    enum ONNXType onnx_type;
    OrtStatus *st = g_api->GetOnnxTypeFromTypeInfo(type, &onnx_type);
    if (st) return ort_error(st, MOCAP_ERR_FORMAT, ": reading a type", path);
    if (onnx_type != ONNX_TYPE_TENSOR)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %s '%s' is not a tensor", path, kind,
                          spec->name);
    const OrtTensorTypeAndShapeInfo *tinfo = NULL;
    st = g_api->CastTypeInfoToTensorInfo(type, &tinfo);
    if (st) return ort_error(st, MOCAP_ERR_FORMAT, ": reading a tensor type", path);
    ONNXTensorElementDataType elem;
    size_t rank = 0;
    int64_t dims[8];
    st = g_api->GetTensorElementType(tinfo, &elem);
    if (!st) st = g_api->GetDimensionsCount(tinfo, &rank);
    if (st) return ort_error(st, MOCAP_ERR_FORMAT, ": reading a tensor shape", path);
    if (elem != ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %s '%s' has element type %d, the contract "
                          "needs float32 (%d)", path, kind, spec->name, (int)elem,
                          (int)ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT);
    if ((int)rank != spec->rank)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %s '%s' has rank %d, the contract needs "
                          "rank %d", path, kind, spec->name, (int)rank, spec->rank);
    st = g_api->GetDimensions(tinfo, dims, rank);
    if (st) return ort_error(st, MOCAP_ERR_FORMAT, ": reading tensor dimensions", path);
    char shape[96];
    size_t len = 0;
    for (int d = 0; d < spec->rank; ++d)
        len += (size_t)snprintf(shape + len, sizeof shape - len, "%s%s", d ? ", " : "[",
                                spec->dim_names[d]);
    snprintf(shape + len, sizeof shape - len, "]");
    for (int d = 0; d < spec->rank; ++d) {
        int64_t want = spec->dims[d];
        if (want == DIM_LAYERS) want = m->info.state_layers;
        else if (want == DIM_STATE) want = graph_state_size(m);
        else if (want == DIM_SENSORS) want = m->info.sensor_count;
        else if (want == DIM_FEATURES) want = m->geometry.features;
        if (want == DIM_DYNAMIC) {
            if (dims[d] >= 0)
                return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %s '%s' dimension %d (%s) is fixed "
                                  "to %lld; the contract makes it dynamic (shape %s)", path, kind,
                                  spec->name, d, spec->dim_names[d], (long long)dims[d], shape);
        } else if (dims[d] < 0) {
            /* Left symbolic in the file (exporters often do): checked by the probe run. */
        } else if (dims[d] != want) {
            const char *which = spec->dims[d] == DIM_LAYERS     ? " (mocap.state_layers)"
                                : spec->dims[d] == DIM_STATE    ? " (mocap.state_size)"
                                : spec->dims[d] == DIM_SENSORS  ? " (mocap.sensor_order)"
                                : spec->dims[d] == DIM_FEATURES ? " (the features of "
                                                                  "mocap.sensor_order)"
                                                                : "";
            return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %s '%s' dimension %d (%s) is %lld, the "
                              "contract needs %lld%s (shape %s)", path, kind, spec->name, d,
                              spec->dim_names[d], (long long)dims[d], (long long)want, which,
                              shape);
        }
    }
    return MOCAP_OK;
}

static mocap_status check_io(ort_model *m, int outputs)
{
    const char *kind = outputs ? "output" : "input";
    const tensor_spec *specs = network_only(m) ? (outputs ? OUTPUT3_SPECS : INPUT3_SPECS)
                                               : (outputs ? OUTPUT_SPECS : INPUT_SPECS);
    int nspec = outputs ? model_output_count(m) : model_input_count(m);
    OrtAllocator *alloc = NULL;
    size_t count = 0;
    OrtStatus *st = g_api->GetAllocatorWithDefaultOptions(&alloc);
    if (!st) st = outputs ? g_api->SessionGetOutputCount(m->session, &count)
                          : g_api->SessionGetInputCount(m->session, &count);
    if (st) return ort_error(st, MOCAP_ERR_FORMAT, ": reading the graph", m->path);

    char names[16][64];
    size_t listed = count < 16 ? count : 16;
    for (size_t i = 0; i < listed; ++i) {
        char *name = NULL;
        st = outputs ? g_api->SessionGetOutputName(m->session, i, alloc, &name)
                     : g_api->SessionGetInputName(m->session, i, alloc, &name);
        if (st) return ort_error(st, MOCAP_ERR_FORMAT, ": reading a name", m->path);
        snprintf(names[i], sizeof names[i], "%s", name);
        release(g_api->AllocatorFree(alloc, name));
    }
    char all[512];
    size_t len = 0;
    all[0] = '\0';
    for (size_t i = 0; i < listed && len < sizeof all; ++i)
        len += (size_t)snprintf(all + len, sizeof all - len, "%s%s", i ? ", " : "", names[i]);

    /* A missing name first (the most useful message), then an unexpected one, then types. */
    int index_of[16];
    for (int k = 0; k < nspec; ++k) {
        index_of[k] = -1;
        for (size_t i = 0; i < listed; ++i)
            if (strcmp(names[i], specs[k].name) == 0) index_of[k] = (int)i;
        if (index_of[k] < 0)
            return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %s '%s' is missing (the model's %ss: "
                              "%s; contract %d)", m->path, kind, specs[k].name, kind, all,
                              m->info.contract_version);
    }
    for (size_t i = 0; i < listed; ++i) {
        int known = 0;
        for (int k = 0; k < nspec; ++k) known |= index_of[k] == (int)i;
        if (!known)
            return mocap_fail(MOCAP_ERR_FORMAT, "model %s: unexpected %s '%s' (the model's %ss: "
                              "%s; contract %d)", m->path, kind, names[i], kind, all,
                              m->info.contract_version);
    }
    for (int k = 0; k < nspec; ++k) {
        OrtTypeInfo *type = NULL;
        st = outputs ? g_api->SessionGetOutputTypeInfo(m->session, (size_t)index_of[k], &type)
                     : g_api->SessionGetInputTypeInfo(m->session, (size_t)index_of[k], &type);
        if (st) return ort_error(st, MOCAP_ERR_FORMAT, ": reading a type", m->path);
        mocap_status r = check_tensor(m, kind, &specs[k], type);
        g_api->ReleaseTypeInfo(type);
        if (r != MOCAP_OK) return r;
    }
    if (count > (size_t)nspec)
        return mocap_fail(MOCAP_ERR_FORMAT, "model %s: %zu %ss, the contract has %d", m->path,
                          count, kind, nspec);
    return MOCAP_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Session                                                                                     */

static mocap_status append_provider(OrtSessionOptions *so, const ort_options *o)
{
    if (o->provider == ORT_PROVIDER_CPU) return MOCAP_OK;
    if (o->provider != ORT_PROVIDER_CUDA)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "unknown execution provider %d",
                          (int)o->provider);
    char **providers = NULL;
    int count = 0, has_cuda = 0;
    OrtStatus *st = g_api->GetAvailableProviders(&providers, &count);
    if (st) return ort_error(st, MOCAP_ERR_UNSUPPORTED, "listing execution providers", NULL);
    char list[256] = "";
    size_t len = 0;
    for (int i = 0; i < count; ++i) {
        if (strcmp(providers[i], "CUDAExecutionProvider") == 0) has_cuda = 1;
        if (len < sizeof list)
            len += (size_t)snprintf(list + len, sizeof list - len, "%s%s", i ? ", " : "",
                                    providers[i]);
    }
    release(g_api->ReleaseAvailableProviders(providers, count));
    if (!has_cuda)
        return mocap_fail(MOCAP_ERR_UNSUPPORTED, "the CUDA execution provider was requested, but "
                          "the ONNX Runtime at %s (%s) is a build without CUDA (it has: %s); use "
                          "the CPU provider or a CUDA build of ONNX Runtime", g_path, g_version,
                          list);
    OrtCUDAProviderOptionsV2 *cuda = NULL;
    st = g_api->CreateCUDAProviderOptions(&cuda);
    if (!st) {
        char device[16];
        snprintf(device, sizeof device, "%d", o->cuda_device);
        const char *keys[] = {"device_id"};
        const char *vals[] = {device};
        st = g_api->UpdateCUDAProviderOptions(cuda, keys, vals, 1);
    }
    if (!st) st = g_api->SessionOptionsAppendExecutionProvider_CUDA_V2(so, cuda);
    if (cuda) g_api->ReleaseCUDAProviderOptions(cuda);
    if (st) return ort_error(st, MOCAP_ERR_UNSUPPORTED, "enabling the CUDA execution provider",
                             NULL);
    return MOCAP_OK;
}

/* "[1, 1, 24, 3, 3]" into out, never past cap (a shape the model made can have any rank and
 * any values); dims beyond the 8 that were read are summarised, not printed. */
static void format_dims(char *out, size_t cap, const int64_t *dims, size_t rank)
{
    if (rank > 8) {
        snprintf(out, cap, "a rank-%u tensor", (unsigned)rank);
        return;
    }
    size_t len = (size_t)snprintf(out, cap, "[");
    for (size_t d = 0; d < rank && len < cap; ++d) {
        int n = snprintf(out + len, cap - len, "%s%lld", d ? ", " : "", (long long)dims[d]);
        if (n < 0) break;
        len += (size_t)n;
    }
    if (len < cap) snprintf(out + len, cap - len, "]");
}

/* One inference on a still T-pose (1 character, 1 frame, zero state) with ONNX Runtime
 * allocating the outputs: proves the model runs and that every output has the contract's shape
 * (dimensions a file may leave symbolic are only known here). */
static mocap_status probe_run(ort_model *m)
{
    const int L = m->info.state_layers, H = m->info.state_size, N = m->info.sensor_count;
    const size_t nstate = (size_t)L * (size_t)H;
    const size_t n_ori = (size_t)N * 9, n_acc = (size_t)N * 3, n_mask = (size_t)N;
    float *buf = (float *)calloc(n_ori + n_acc + n_mask + 2 * nstate, sizeof(float));
    if (!buf) return mocap_fail(MOCAP_ERR_NO_MEMORY, "model %s: probe buffers", m->path);
    float *ori = buf, *acc = buf + n_ori, *mask = acc + n_acc, *state = mask + n_mask;
    for (int s = 0; s < N; ++s) {
        ori[s * 9 + 0] = ori[s * 9 + 4] = ori[s * 9 + 8] = 1.0f;
        mask[s] = 1.0f;
    }
    const int64_t sh_ori[5] = {1, 1, N, 3, 3}, sh_acc[4] = {1, 1, N, 3}, sh_mask[3] = {1, 1, N};
    const int64_t sh_state[3] = {L, 1, H};
    OrtValue *in[INPUT_COUNT] = {0}, *out[OUTPUT_COUNT] = {0};
    mocap_status r = MOCAP_OK;
    OrtStatus *st = g_api->CreateTensorWithDataAsOrtValue(m->memory, ori, n_ori * sizeof(float),
                                                          sh_ori, 5, ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT,
                                                          &in[IN_ORIENTATION]);
    if (!st) st = g_api->CreateTensorWithDataAsOrtValue(m->memory, acc, n_acc * sizeof(float),
                                                        sh_acc, 4, ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT,
                                                        &in[IN_ACCELERATION]);
    if (!st) st = g_api->CreateTensorWithDataAsOrtValue(m->memory, state, nstate * sizeof(float),
                                                        sh_state, 3, ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT,
                                                        &in[IN_STATE_H]);
    if (!st) st = g_api->CreateTensorWithDataAsOrtValue(m->memory, state + nstate,
                                                        nstate * sizeof(float), sh_state, 3,
                                                        ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT,
                                                        &in[IN_STATE_C]);
    if (!st && m->info.has_mask)
        st = g_api->CreateTensorWithDataAsOrtValue(m->memory, mask, n_mask * sizeof(float), sh_mask,
                                                   3, ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT,
                                                   &in[IN_MASK]);
    if (st) {
        r = ort_error(st, MOCAP_ERR_NO_MEMORY, ": probe tensors", m->path);
        goto done;
    }
    st = g_api->Run(m->session, NULL, INPUT_NAMES, (const OrtValue *const *)in,
                    (size_t)model_input_count(m), OUTPUT_NAMES, OUTPUT_COUNT, out);
    if (st) {
        r = ort_error(st, MOCAP_ERR_FORMAT, ": a one-frame test inference failed", m->path);
        goto done;
    }
    for (int k = 0; k < OUTPUT_COUNT && r == MOCAP_OK; ++k) {
        const tensor_spec *spec = &OUTPUT_SPECS[k];
        OrtTensorTypeAndShapeInfo *info = NULL;
        size_t rank = 0;
        int64_t dims[8];
        st = g_api->GetTensorTypeAndShape(out[k], &info);
        if (!st) st = g_api->GetDimensionsCount(info, &rank);
        if (!st && rank <= 8) st = g_api->GetDimensions(info, dims, rank);
        if (info) g_api->ReleaseTensorTypeAndShapeInfo(info);
        if (st) {
            r = ort_error(st, MOCAP_ERR_FORMAT, ": reading a probe output", m->path);
            break;
        }
        int ok = (int)rank == spec->rank;
        for (int d = 0; ok && d < spec->rank; ++d) {
            int64_t want = spec->dims[d] == DIM_LAYERS ? L : spec->dims[d] == DIM_STATE ? H
                           : spec->dims[d] == DIM_DYNAMIC ? 1 : spec->dims[d];
            ok = dims[d] == want;
        }
        if (!ok) {
            char got[96];
            format_dims(got, sizeof got, dims, rank);
            r = mocap_fail(MOCAP_ERR_FORMAT, "model %s: output '%s' came out as %s for 1 "
                           "character x 1 frame; the contract needs rank %d (B, T = 1)", m->path,
                           spec->name, got, spec->rank);
        }
    }
done:
    for (int k = 0; k < INPUT_COUNT; ++k)
        if (in[k]) g_api->ReleaseValue(in[k]);
    for (int k = 0; k < OUTPUT_COUNT; ++k)
        if (out[k]) g_api->ReleaseValue(out[k]);
    free(buf);
    return r;
}

static mocap_status probe_stream(ort_model *m);

void ort_model_close(ort_model *m)
{
    if (!m) return;
    if (m->session) g_api->ReleaseSession(m->session);
    if (m->memory) g_api->ReleaseMemoryInfo(m->memory);
    free(m);
}

mocap_status ort_model_open(const char *path, const ort_options *options, ort_model **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "ort_model_open: out is NULL");
    *out = NULL;
    if (!path || !path[0]) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "ort_model_open: no path");
    ort_options o;
    if (options) o = *options;
    else ort_options_defaults(&o);
    if (o.intra_op_threads < 0 || o.optimization_level < 0 || o.optimization_level > 3)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "ort_model_open: intra_op_threads %d / "
                          "optimization_level %d out of range", o.intra_op_threads,
                          o.optimization_level);
    FILE *f = mocap_fopen(path, "rb");
    if (!f) return mocap_fail(MOCAP_ERR_NOT_FOUND, "model %s: no such file", path);
    fclose(f);
    mocap_status r = ort_library_load(o.library_path);
    if (r != MOCAP_OK) return r;

    ort_model *m = (ort_model *)calloc(1, sizeof *m);
    if (!m) return mocap_fail(MOCAP_ERR_NO_MEMORY, "ort_model_open: out of memory");
    snprintf(m->path, sizeof m->path, "%s", path);

    OrtSessionOptions *so = NULL;
    OrtStatus *st = g_api->CreateSessionOptions(&so);
    static const GraphOptimizationLevel levels[4] = {ORT_DISABLE_ALL, ORT_ENABLE_BASIC,
                                                     ORT_ENABLE_EXTENDED, ORT_ENABLE_ALL};
    if (!st) st = g_api->SetSessionGraphOptimizationLevel(so, levels[o.optimization_level]);
    if (!st && o.intra_op_threads > 0) st = g_api->SetIntraOpNumThreads(so, o.intra_op_threads);
    if (!st) st = g_api->SetInterOpNumThreads(so, 1);
    if (!st) st = g_api->SetSessionExecutionMode(so, ORT_SEQUENTIAL);
    if (st) {
        r = ort_error(st, MOCAP_ERR_INVALID_ARGUMENT, ": session options", path);
        goto fail;
    }
    r = append_provider(so, &o);
    if (r != MOCAP_OK) goto fail;

#if defined(_WIN32)
    {
        wchar_t wpath[1024];
        if (mocap_utf8_to_wide(path, wpath, 1024) != 0) {
            r = mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "model %s: path not valid UTF-8", path);
            goto fail;
        }
        st = g_api->CreateSession(g_env, wpath, so, &m->session);
    }
#else
    st = g_api->CreateSession(g_env, path, so, &m->session);
#endif
    if (st) {
        r = ort_error(st, MOCAP_ERR_FORMAT, ": not a model ONNX Runtime can load", path);
        goto fail;
    }
    st = g_api->CreateCpuMemoryInfo(OrtArenaAllocator, OrtMemTypeDefault, &m->memory);
    if (st) {
        r = ort_error(st, MOCAP_ERR_NO_MEMORY, ": memory info", path);
        goto fail;
    }
    /* Metadata first (it gives L and H), then the tensors. */
    r = read_metadata(m);
    if (r == MOCAP_OK) r = check_io(m, 0);
    if (r == MOCAP_OK) r = check_io(m, 1);
    if (r == MOCAP_OK) r = network_only(m) ? probe_stream(m) : probe_run(m);
    if (r != MOCAP_OK) goto fail;
    g_api->ReleaseSessionOptions(so);
    *out = m;
    return MOCAP_OK;
fail:
    if (so) g_api->ReleaseSessionOptions(so);
    ort_model_close(m);
    return r;
}

const ort_model_info *ort_model_get_info(const ort_model *m) { return m ? &m->info : NULL; }

/* ---------------------------------------------------------------------------------------- */
/* Streams                                                                                     */

void ort_stream_destroy(ort_stream *s)
{
    if (!s) return;
    OrtValue *values[] = {s->v_orientation, s->v_acceleration,   s->v_mask,
                          s->v_rotations,   s->v_velocity,       s->v_contact,
                          s->v_features,    s->v_network_output, s->v_state_h[0],
                          s->v_state_h[1],  s->v_state_c[0],     s->v_state_c[1]};
    for (size_t i = 0; i < sizeof values / sizeof values[0]; ++i)
        if (values[i]) g_api->ReleaseValue(values[i]);
    free(s->rows);
    free(s->block);
    free(s);
}

static OrtStatus *wrap(ort_stream *s, float *data, size_t count, const int64_t *shape, size_t rank,
                       OrtValue **out)
{
    return g_api->CreateTensorWithDataAsOrtValue(s->model->memory, data, count * sizeof(float),
                                                 shape, rank, ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT,
                                                 out);
}

mocap_status ort_stream_create(ort_model *m, int batch, int frames, ort_stream **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "ort_stream_create: out is NULL");
    *out = NULL;
    if (!m) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "ort_stream_create: no model");
    if (batch < 1 || frames < 1 || batch > 4096 || (int64_t)batch * frames > (1 << 24))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "ort_stream_create: batch %d x frames %d "
                          "out of range", batch, frames);
    ort_stream *s = (ort_stream *)calloc(1, sizeof *s);
    if (!s) return mocap_fail(MOCAP_ERR_NO_MEMORY, "ort_stream_create: out of memory");
    s->model = m;
    s->batch = batch;
    s->frames = frames;
    const int L = m->info.state_layers, H = m->info.state_size;
    const size_t bt = (size_t)batch * (size_t)frames;
    s->state_count = (size_t)L * (size_t)batch * (size_t)H;
    const size_t N = (size_t)m->info.sensor_count;
    size_t n_ori = bt * N * 9, n_acc = bt * N * 3, n_mask = m->info.has_mask ? bt * N : 0;
    size_t n_rot = bt * ORT_JOINTS * 9, n_vel = bt * 3, n_con = bt * 2;
    const int rows = network_only(m) ? network_geometry_rows(&m->geometry) : 0;
    size_t n_feat = bt * (size_t)rows * (size_t)m->geometry.features;
    size_t n_net = bt * (size_t)rows * GEOMETRY_OUTPUTS;
    size_t total = n_ori + n_acc + n_mask + n_rot + n_vel + n_con + n_feat + n_net + 4 * s->state_count;
    s->block = (float *)calloc(total, sizeof(float));
    if (rows) s->rows = (geometry_row *)calloc(bt * (size_t)rows, sizeof *s->rows);
    if (!s->block || (rows && !s->rows)) {
        free(s->rows);
        free(s->block);
        free(s);
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "ort_stream_create: %zu floats", total);
    }
    float *p = s->block;
    s->orientation = p; p += n_ori;
    s->acceleration = p; p += n_acc;
    s->mask = n_mask ? p : NULL; p += n_mask;
    s->rotations = p; p += n_rot;
    s->velocity = p; p += n_vel;
    s->contact = p; p += n_con;
    s->features = n_feat ? p : NULL; p += n_feat;
    s->network_output = n_net ? p : NULL; p += n_net;
    for (int k = 0; k < 2; ++k) {
        s->state_h[k] = p; p += s->state_count;
        s->state_c[k] = p; p += s->state_count;
    }
    const int64_t B = batch, T = frames;
    const int64_t sh_ori[5] = {B, T, (int64_t)N, 3, 3}, sh_acc[4] = {B, T, (int64_t)N, 3};
    const int64_t sh_mask[3] = {B, T, (int64_t)N};
    const int64_t sh_rot[5] = {B, T, ORT_JOINTS, 3, 3}, sh_vel[3] = {B, T, 3}, sh_con[3] = {B, T, 2};
    const int64_t sh_state[3] = {L, B, H};
    const int64_t R = B * rows, sh_feat[3] = {R, T, m->geometry.features};
    const int64_t sh_net[3] = {R, T, GEOMETRY_OUTPUTS}, sh_state3[3] = {L, R, rows ? H / rows : 0};
    OrtStatus *st = NULL;
    if (rows) { /* the graph sees only the network's tensors */
        st = wrap(s, s->features, n_feat, sh_feat, 3, &s->v_features);
        if (!st) st = wrap(s, s->network_output, n_net, sh_net, 3, &s->v_network_output);
    } else {
        st = wrap(s, s->orientation, n_ori, sh_ori, 5, &s->v_orientation);
        if (!st) st = wrap(s, s->acceleration, n_acc, sh_acc, 4, &s->v_acceleration);
        if (!st && s->mask) st = wrap(s, s->mask, n_mask, sh_mask, 3, &s->v_mask);
        if (!st) st = wrap(s, s->rotations, n_rot, sh_rot, 5, &s->v_rotations);
        if (!st) st = wrap(s, s->velocity, n_vel, sh_vel, 3, &s->v_velocity);
        if (!st) st = wrap(s, s->contact, n_con, sh_con, 3, &s->v_contact);
    }
    const int64_t *state_shape = rows ? sh_state3 : sh_state;
    for (int k = 0; k < 2 && !st; ++k) {
        st = wrap(s, s->state_h[k], s->state_count, state_shape, 3, &s->v_state_h[k]);
        if (!st) st = wrap(s, s->state_c[k], s->state_count, state_shape, 3, &s->v_state_c[k]);
    }
    if (st) {
        mocap_status r = ort_error(st, MOCAP_ERR_NO_MEMORY, "creating tensors", NULL);
        ort_stream_destroy(s);
        return r;
    }
    for (int k = 0; k < 2; ++k) {
        /* Parity k reads state pair k and writes pair 1 - k. */
        if (rows) {
            s->inputs[k][IN3_FEATURES] = s->v_features;
            s->inputs[k][IN3_STATE_H] = s->v_state_h[k];
            s->inputs[k][IN3_STATE_C] = s->v_state_c[k];
            s->outputs[k][OUT3_NETWORK] = s->v_network_output;
            s->outputs[k][OUT3_STATE_H] = s->v_state_h[1 - k];
            s->outputs[k][OUT3_STATE_C] = s->v_state_c[1 - k];
            continue;
        }
        s->inputs[k][IN_ORIENTATION] = s->v_orientation;
        s->inputs[k][IN_ACCELERATION] = s->v_acceleration;
        s->inputs[k][IN_STATE_H] = s->v_state_h[k];
        s->inputs[k][IN_STATE_C] = s->v_state_c[k];
        s->inputs[k][IN_MASK] = s->v_mask;
        s->outputs[k][OUT_ROTATIONS] = s->v_rotations;
        s->outputs[k][OUT_VELOCITY] = s->v_velocity;
        s->outputs[k][OUT_CONTACT] = s->v_contact;
        s->outputs[k][OUT_STATE_H] = s->v_state_h[1 - k];
        s->outputs[k][OUT_STATE_C] = s->v_state_c[1 - k];
    }
    *out = s;
    return MOCAP_OK;
}

int ort_stream_batch(const ort_stream *s) { return s ? s->batch : 0; }
int ort_stream_frames(const ort_stream *s) { return s ? s->frames : 0; }
float *ort_stream_orientation(ort_stream *s) { return s ? s->orientation : NULL; }
float *ort_stream_acceleration(ort_stream *s) { return s ? s->acceleration : NULL; }
float *ort_stream_mask(ort_stream *s) { return s ? s->mask : NULL; }
const float *ort_stream_joint_rotations(const ort_stream *s) { return s ? s->rotations : NULL; }
const float *ort_stream_root_velocity(const ort_stream *s) { return s ? s->velocity : NULL; }
const float *ort_stream_foot_contact(const ort_stream *s) { return s ? s->contact : NULL; }
float *ort_stream_state_h(ort_stream *s) { return s ? s->state_h[s->parity] : NULL; }
float *ort_stream_state_c(ort_stream *s) { return s ? s->state_c[s->parity] : NULL; }
size_t ort_stream_state_count(const ort_stream *s) { return s ? s->state_count : 0; }

void ort_stream_reset_state(ort_stream *s)
{
    if (!s) return;
    for (int k = 0; k < 2; ++k) {
        memset(s->state_h[k], 0, s->state_count * sizeof(float));
        memset(s->state_c[k], 0, s->state_count * sizeof(float));
    }
}

/* Contract 3, before the run: every character's frames -> the graph's rows of features. */
static void stream_features(ort_stream *s)
{
    const network_geometry *g = &s->model->geometry;
    const int rows = network_geometry_rows(g), T = s->frames, N = g->sensors;
    const size_t row_stride = (size_t)T * (size_t)g->features;
    for (int b = 0; b < s->batch; ++b)
        for (int t = 0; t < T; ++t) {
            const size_t f = (size_t)b * (size_t)T + (size_t)t;
            network_geometry_features(g, s->orientation + f * (size_t)N * 9,
                                      s->acceleration + f * (size_t)N * 3,
                                      s->mask ? s->mask + f * (size_t)N : NULL,
                                      s->features + (size_t)b * rows * row_stride +
                                          (size_t)t * (size_t)g->features,
                                      row_stride, s->rows + f * (size_t)rows);
        }
}

/* Contract 3, after the run: the graph's rows -> every character's pose. */
static void stream_outputs(ort_stream *s)
{
    const network_geometry *g = &s->model->geometry;
    const int rows = network_geometry_rows(g), T = s->frames;
    const size_t row_stride = (size_t)T * GEOMETRY_OUTPUTS;
    for (int b = 0; b < s->batch; ++b)
        for (int t = 0; t < T; ++t) {
            const size_t f = (size_t)b * (size_t)T + (size_t)t;
            network_geometry_outputs(g, s->network_output + (size_t)b * rows * row_stride +
                                            (size_t)t * GEOMETRY_OUTPUTS,
                                     row_stride, s->rows + f * (size_t)rows,
                                     s->rotations + f * ORT_JOINTS * 9, s->velocity + f * 3,
                                     s->contact + f * 2);
        }
}

mocap_status ort_stream_run(ort_stream *s)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "ort_stream_run: no stream");
    const int k = s->parity;
    const ort_model *m = s->model;
    if (network_only(m)) stream_features(s);
    OrtStatus *st = g_api->Run(m->session, NULL, input_names(m), s->inputs[k],
                               (size_t)model_input_count(m), output_names(m),
                               (size_t)model_output_count(m), s->outputs[k]);
    if (st) return ort_error(st, MOCAP_ERR_IO, ": inference failed", m->path);
    if (network_only(m)) stream_outputs(s);
    s->parity = 1 - k;
    return MOCAP_OK;
}

/* Contract 3's probe: one frame of a still T-pose through a stream, which binds every tensor at
 * the shape the contract gives it, so a graph that answers another shape fails here. */
static mocap_status probe_stream(ort_model *m)
{
    ort_stream *s = NULL;
    mocap_status r = ort_stream_create(m, 1, 1, &s);
    if (r != MOCAP_OK) return r;
    for (int k = 0; k < m->info.sensor_count; ++k) {
        s->orientation[k * 9 + 0] = s->orientation[k * 9 + 4] = s->orientation[k * 9 + 8] = 1.0f;
        if (s->mask) s->mask[k] = 1.0f;
    }
    stream_features(s);
    const int k = s->parity;
    OrtStatus *st = g_api->Run(m->session, NULL, INPUT3_NAMES, s->inputs[k], INPUT3_COUNT,
                               OUTPUT3_NAMES, OUTPUT3_COUNT, s->outputs[k]);
    if (st) r = ort_error(st, MOCAP_ERR_FORMAT, ": a one-frame test inference failed", m->path);
    ort_stream_destroy(s);
    return r;
}

#endif /* MOCAP_HAVE_ONNXRUNTIME */
