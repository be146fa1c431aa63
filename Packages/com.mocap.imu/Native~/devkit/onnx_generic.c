/* Generic one-input one-output ONNX runner: see onnx_generic.h. */
#include "onnx_generic.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "platform.h"
#include "onnx_runtime.h"

#if !defined(MOCAP_HAVE_ONNXRUNTIME)

mocap_status ort_generic_open(const char *path, int intra_op_threads, ort_generic **out)
{
    (void)path;
    (void)intra_op_threads;
    if (out) *out = NULL;
    return mocap_fail(MOCAP_ERR_UNSUPPORTED,
                      "this engine was built without ONNX Runtime headers: run "
                      "scripts/fetch_onnxruntime.sh, then re-run cmake (MOCAP_ONNXRUNTIME_DIR)");
}
void ort_generic_close(ort_generic *g) { (void)g; }
int ort_generic_input_rank(const ort_generic *g) { (void)g; return 0; }
const int64_t *ort_generic_input_shape(const ort_generic *g) { (void)g; return NULL; }
size_t ort_generic_input_count(const ort_generic *g) { (void)g; return 0; }
int ort_generic_output_rank(const ort_generic *g) { (void)g; return 0; }
const int64_t *ort_generic_output_shape(const ort_generic *g) { (void)g; return NULL; }
size_t ort_generic_output_count(const ort_generic *g) { (void)g; return 0; }
float *ort_generic_input(ort_generic *g) { (void)g; return NULL; }
const float *ort_generic_output(const ort_generic *g) { (void)g; return NULL; }
mocap_status ort_generic_run(ort_generic *g)
{
    (void)g;
    return mocap_fail(MOCAP_ERR_UNSUPPORTED, "built without ONNX Runtime");
}

#else

#include <onnxruntime_c_api.h>

#define MAX_RANK 8

struct ort_generic {
    const OrtApi *api;
    OrtEnv *env;
    OrtSession *session;
    OrtMemoryInfo *memory;
    char *in_name, *out_name;
    int in_rank, out_rank;
    int64_t in_shape[MAX_RANK], out_shape[MAX_RANK];
    size_t in_count, out_count;
    float *in_buf, *out_buf;
    OrtValue *in_value, *out_value;
    char path[MOCAP_PATH_MAX];
};

/* The OrtApi of the library the engine loaded (the same file again: the OS returns the handle it
 * already has, so one copy of ONNX Runtime serves both). */
static const OrtApi *engine_api(void)
{
    const char *lib = ort_library_path();
    if (!lib || !lib[0]) return NULL;
    typedef const OrtApiBase *(ORT_API_CALL * get_base_fn)(void);
    get_base_fn get_base = NULL;
    void *h = mocap_library_open(lib, NULL, 0);
    if (h) get_base = (get_base_fn)mocap_library_symbol(h, "OrtGetApiBase");
    const OrtApiBase *base = get_base ? get_base() : NULL;
    return base ? base->GetApi(ORT_API_VERSION) : NULL;
}

static mocap_status fail_ort(ort_generic *g, OrtStatus *st, const char *what)
{
    mocap_status r = mocap_fail(MOCAP_ERR_FORMAT, "%s: %s: %s", g->path, what,
                                g->api->GetErrorMessage(st));
    g->api->ReleaseStatus(st);
    return r;
}

/* Name, element type and static shape of input/output 0. */
static mocap_status describe(ort_generic *g, int output, char **name, int *rank, int64_t *shape,
                             size_t *count)
{
    const OrtApi *api = g->api;
    OrtAllocator *alloc = NULL;
    size_t n = 0;
    OrtStatus *st = api->GetAllocatorWithDefaultOptions(&alloc);
    if (!st) st = output ? api->SessionGetOutputCount(g->session, &n)
                         : api->SessionGetInputCount(g->session, &n);
    if (st) return fail_ort(g, st, "reading the model's inputs/outputs");
    if (n != 1)
        return mocap_fail(MOCAP_ERR_FORMAT, "%s: has %zu %s; the generic runner takes exactly one",
                          g->path, n, output ? "outputs" : "inputs");
    char *nm = NULL;
    st = output ? api->SessionGetOutputName(g->session, 0, alloc, &nm)
                : api->SessionGetInputName(g->session, 0, alloc, &nm);
    if (st) return fail_ort(g, st, "reading a name");
    *name = (char *)malloc(strlen(nm) + 1);
    if (*name) strcpy(*name, nm);
    OrtStatus *fs = api->AllocatorFree(alloc, nm);
    if (fs) api->ReleaseStatus(fs);
    if (!*name) return mocap_fail(MOCAP_ERR_NO_MEMORY, "out of memory");

    OrtTypeInfo *type = NULL;
    const OrtTensorTypeAndShapeInfo *tinfo = NULL;
    ONNXTensorElementDataType elem = ONNX_TENSOR_ELEMENT_DATA_TYPE_UNDEFINED;
    size_t r = 0;
    st = output ? api->SessionGetOutputTypeInfo(g->session, 0, &type)
                : api->SessionGetInputTypeInfo(g->session, 0, &type);
    if (!st) st = api->CastTypeInfoToTensorInfo(type, &tinfo);
    if (!st && !tinfo) {
        api->ReleaseTypeInfo(type);
        return mocap_fail(MOCAP_ERR_FORMAT, "%s: %s is not a tensor", g->path, *name);
    }
    if (!st) st = api->GetTensorElementType(tinfo, &elem);
    if (!st) st = api->GetDimensionsCount(tinfo, &r);
    if (!st && r <= MAX_RANK) st = api->GetDimensions(tinfo, shape, r);
    if (type) api->ReleaseTypeInfo(type);
    if (st) return fail_ort(g, st, "reading a tensor type");
    if (elem != ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT)
        return mocap_fail(MOCAP_ERR_FORMAT, "%s: %s is not float32", g->path, *name);
    if (r < 1 || r > MAX_RANK)
        return mocap_fail(MOCAP_ERR_FORMAT, "%s: %s has rank %zu (1..%d)", g->path, *name, r,
                          MAX_RANK);
    size_t c = 1;
    for (size_t k = 0; k < r; ++k) {
        if (shape[k] <= 0)
            return mocap_fail(MOCAP_ERR_FORMAT, "%s: %s has a dynamic dimension %zu; the generic "
                              "runner needs static shapes", g->path, *name, k);
        /* Bounded before multiplying: a static shape can be anything, and the product must
         * neither wrap (size_t is 32 bits on some targets) nor ask for more than 1 GiB. */
        if ((uint64_t)shape[k] > (((uint64_t)1 << 28) / c))
            return mocap_fail(MOCAP_ERR_FORMAT, "%s: %s holds more than 2^28 values (1 GiB); the "
                              "generic runner refuses it", g->path, *name);
        c *= (size_t)shape[k];
    }
    *rank = (int)r;
    *count = c;
    return MOCAP_OK;
}

mocap_status ort_generic_open(const char *path, int intra_op_threads, ort_generic **out)
{
    if (!out || !path) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "ort_generic_open: NULL");
    *out = NULL;
    FILE *probe = mocap_fopen(path, "rb");
    if (!probe) return mocap_fail(MOCAP_ERR_NOT_FOUND, "model %s: no such file", path);
    fclose(probe);
    mocap_status r = ort_library_load(NULL);
    if (r != MOCAP_OK) return r;
    ort_generic *g = (ort_generic *)calloc(1, sizeof *g);
    if (!g) return mocap_fail(MOCAP_ERR_NO_MEMORY, "out of memory");
    snprintf(g->path, sizeof g->path, "%s", path);
    g->api = engine_api();
    if (!g->api) {
        free(g);
        return mocap_fail(MOCAP_ERR_UNSUPPORTED, "cannot reach the ONNX Runtime C API of %s",
                          ort_library_path());
    }
    const OrtApi *api = g->api;
    OrtSessionOptions *so = NULL;
    /* The process-wide environment (CreateEnv returns the one the engine made). */
    OrtStatus *st = api->CreateEnv(ORT_LOGGING_LEVEL_ERROR, "mocap", &g->env);
    if (!st) st = api->CreateSessionOptions(&so);
    if (!st) st = api->SetSessionGraphOptimizationLevel(so, ORT_ENABLE_ALL);
    if (!st && intra_op_threads > 0) st = api->SetIntraOpNumThreads(so, intra_op_threads);
    if (!st) st = api->SetInterOpNumThreads(so, 1);
    if (!st) st = api->SetSessionExecutionMode(so, ORT_SEQUENTIAL);
#if defined(_WIN32)
    if (!st) {
        wchar_t wpath[1024];
        /* The probe above already opened this path, so it converts; if not, ONNX Runtime
         * reports the empty path as a missing file. */
        if (mocap_utf8_to_wide(path, wpath, 1024) != 0) wpath[0] = L'\0';
        st = api->CreateSession(g->env, wpath, so, &g->session);
    }
#else
    if (!st) st = api->CreateSession(g->env, path, so, &g->session);
#endif
    if (!st) st = api->CreateCpuMemoryInfo(OrtArenaAllocator, OrtMemTypeDefault, &g->memory);
    if (so) api->ReleaseSessionOptions(so);
    if (st) {
        r = fail_ort(g, st, "loading");
        ort_generic_close(g);
        return r;
    }
    r = describe(g, 0, &g->in_name, &g->in_rank, g->in_shape, &g->in_count);
    if (r == MOCAP_OK) r = describe(g, 1, &g->out_name, &g->out_rank, g->out_shape, &g->out_count);
    if (r != MOCAP_OK) {
        ort_generic_close(g);
        return r;
    }
    g->in_buf = (float *)calloc(g->in_count, sizeof(float));
    g->out_buf = (float *)calloc(g->out_count, sizeof(float));
    if (!g->in_buf || !g->out_buf) {
        ort_generic_close(g);
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "out of memory");
    }
    st = api->CreateTensorWithDataAsOrtValue(g->memory, g->in_buf, g->in_count * sizeof(float),
                                             g->in_shape, (size_t)g->in_rank,
                                             ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT, &g->in_value);
    if (!st)
        st = api->CreateTensorWithDataAsOrtValue(g->memory, g->out_buf, g->out_count * sizeof(float),
                                                 g->out_shape, (size_t)g->out_rank,
                                                 ONNX_TENSOR_ELEMENT_DATA_TYPE_FLOAT, &g->out_value);
    if (st) {
        r = fail_ort(g, st, "binding tensors");
        ort_generic_close(g);
        return r;
    }
    *out = g;
    return MOCAP_OK;
}

void ort_generic_close(ort_generic *g)
{
    if (!g) return;
    const OrtApi *api = g->api;
    if (api) {
        if (g->in_value) api->ReleaseValue(g->in_value);
        if (g->out_value) api->ReleaseValue(g->out_value);
        if (g->memory) api->ReleaseMemoryInfo(g->memory);
        if (g->session) api->ReleaseSession(g->session);
        if (g->env) api->ReleaseEnv(g->env);
    }
    free(g->in_buf);
    free(g->out_buf);
    free(g->in_name);
    free(g->out_name);
    free(g);
}

int ort_generic_input_rank(const ort_generic *g) { return g->in_rank; }
const int64_t *ort_generic_input_shape(const ort_generic *g) { return g->in_shape; }
size_t ort_generic_input_count(const ort_generic *g) { return g->in_count; }
int ort_generic_output_rank(const ort_generic *g) { return g->out_rank; }
const int64_t *ort_generic_output_shape(const ort_generic *g) { return g->out_shape; }
size_t ort_generic_output_count(const ort_generic *g) { return g->out_count; }
float *ort_generic_input(ort_generic *g) { return g->in_buf; }
const float *ort_generic_output(const ort_generic *g) { return g->out_buf; }

mocap_status ort_generic_run(ort_generic *g)
{
    if (!g) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "ort_generic_run: NULL");
    const char *in_names[1] = {g->in_name};
    const char *out_names[1] = {g->out_name};
    const OrtValue *inputs[1] = {g->in_value};
    OrtValue *outputs[1] = {g->out_value};
    OrtStatus *st = g->api->Run(g->session, NULL, in_names, inputs, 1, out_names, 1, outputs);
    if (st) return fail_ort(g, st, "run");
    return MOCAP_OK;
}

#endif
