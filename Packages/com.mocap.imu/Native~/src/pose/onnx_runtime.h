/* The pose model through ONNX Runtime (docs/model-contract.md at the repository root).
 *
 * ONNX Runtime is loaded at run time (dlopen / LoadLibrary + OrtGetApiBase()->GetApi), so the
 * engine builds and runs without it; only its C headers are needed at compile time (CMake
 * variable MOCAP_ONNXRUNTIME_DIR). Built without the headers, every function here fails with
 * MOCAP_ERR_UNSUPPORTED and says so.
 *
 * A model is validated against the contract when it is opened: input/output names, element
 * types, ranks, fixed dimensions, state sizes, metadata keys and the contract version. A model
 * that differs is refused with a message naming the difference; nothing else is affected.
 *
 * Running: an ort_stream is a fixed (batch B, frames T) binding with its own input, output and
 * state buffers, all allocated once with their ORT tensors wrapped around them, so a run
 * allocates nothing on our side (ONNX Runtime's own internals aside). The recurrent state is
 * carried from one run to the next (two state buffers used in turn: no copy).
 *
 * Threads: a model and its streams are used from one thread at a time. Loading the library is
 * thread-safe. Errors: status + mocap_last_error() text, like the rest of the engine. */
#ifndef MOCAP_ONNX_RUNTIME_H
#define MOCAP_ONNX_RUNTIME_H

#include <stddef.h>
#include <stdint.h>
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Contract versions this engine reads: 1 (the six default sensors, no mask), 2 (the model's
 * own sensor list from the segment table, with a mask input) and 3 (the learned network alone,
 * its geometry done by the engine: network_geometry.h; same stream interface). */
#define ORT_CONTRACT_MIN 1
#define ORT_CONTRACT_MAX 3
#define ORT_JOINTS 24
#define ORT_NAME_CAP 32

/* Load ONNX Runtime once per process. library_path: a file to load (the only one tried); NULL
 * loads the environment variable MOCAP_ONNXRUNTIME_PATH when it is set (again the only one
 * tried), else tries the library fetched by scripts/fetch_onnxruntime.sh (the path configured at
 * build time) and the platform's standard names (libonnxruntime.so.1 / libonnxruntime.so,
 * libonnxruntime.dylib, onnxruntime.dll).
 * Later calls return the first result (a different path after a success is ignored). */
mocap_status ort_library_load(const char *library_path);
/* 1 when ort_library_load(library_path) succeeds (never prints; leaves the error text set). */
int ort_library_available(const char *library_path);
/* ONNX Runtime's version string ("1.29.0"), or "" before a successful load. */
const char *ort_library_version(void);
/* The file that was loaded ("" before a successful load). */
const char *ort_library_path(void);

typedef enum ort_provider {
    ORT_PROVIDER_CPU = 0,
    ORT_PROVIDER_CUDA = 1,
} ort_provider;

typedef struct ort_options {
    const char *library_path;  /* passed to ort_library_load; NULL: the defaults above */
    int intra_op_threads;      /* threads for one operator; 0: ONNX Runtime's default */
    int optimization_level;    /* 0 none, 1 basic, 2 extended, 3 all (the default) */
    ort_provider provider;     /* CPU, or CUDA (refused clearly when the build has no CUDA) */
    int cuda_device;           /* device index for CUDA */
} ort_options;

void ort_options_defaults(ort_options *o);

/* What the model's metadata says (validated). */
typedef struct ort_model_info {
    int contract_version;
    double frame_rate;
    int state_layers;                        /* L */
    int state_size;                          /* H */
    char joint_names[ORT_JOINTS][ORT_NAME_CAP];
    int joint_parents[ORT_JOINTS];
    float rest_offsets[ORT_JOINTS][3];       /* metres, model frame; [0] = pelvis height */
    char precision[8];                       /* "fp32" or "fp16" */
    char model_name[128];
    char sensor_order[256];
    int sensor_count;                        /* N: the sensor dimension of the inputs */
    int32_t sensor_segments[MOCAP_MAX_SENSORS];
    uint32_t required_mask;                  /* bit k: sensor k must be present */
    int has_mask;                            /* contract 2, or 3 with masked features: the mask */
    /* Optional (has_stride_scaling 0 when the model gives neither): the standing height of the
     * body the model learned, metres, and how its root speed follows a performer's size. */
    int has_stride_scaling;
    double training_height;
    double stride_exponent;
} ort_model_info;

typedef struct ort_model ort_model;

/* Open and validate path (.onnx). MOCAP_ERR_NOT_FOUND: no such file; MOCAP_ERR_FORMAT: not a
 * model ONNX Runtime can load, or one that breaks the contract (the message names what);
 * MOCAP_ERR_UNSUPPORTED: no ONNX Runtime, or a provider it lacks. options may be NULL. */
mocap_status ort_model_open(const char *path, const ort_options *options, ort_model **out);
void ort_model_close(ort_model *m);
const ort_model_info *ort_model_get_info(const ort_model *m);

typedef struct ort_stream ort_stream;

/* A binding for `batch` characters and `frames` frames per run (the engine streams T = 1),
 * state zeroed. Several streams of one model may exist (e.g. a whole-clip one and a T = 1 one). */
mocap_status ort_stream_create(ort_model *m, int batch, int frames, ort_stream **out);
void ort_stream_destroy(ort_stream *s);
int ort_stream_batch(const ort_stream *s);
int ort_stream_frames(const ort_stream *s);

/* Input buffers to fill before ort_stream_run, row-major float32, N = info.sensor_count:
 * orientation [B][T][N][3][3] (bone -> model), acceleration [B][T][N][3] (m/s^2), mask [B][T][N]
 * (1 present, 0 missing; NULL for a model without the mask input). */
float *ort_stream_orientation(ort_stream *s);
float *ort_stream_acceleration(ort_stream *s);
float *ort_stream_mask(ort_stream *s);
/* Results of the last run: rotations [B][T][24][3][3], root velocity [B][T][3],
 * foot contact [B][T][2]. */
const float *ort_stream_joint_rotations(const ort_stream *s);
const float *ort_stream_root_velocity(const ort_stream *s);
const float *ort_stream_foot_contact(const ort_stream *s);

/* The state the next run starts from, [L][B][H] each (after a run: the state it produced).
 * Writable, e.g. to continue another stream's state. Count: L * B * H floats. */
float *ort_stream_state_h(ort_stream *s);
float *ort_stream_state_c(ort_stream *s);
size_t ort_stream_state_count(const ort_stream *s);
void ort_stream_reset_state(ort_stream *s);

/* One inference over the bound inputs; the new state replaces the old. */
mocap_status ort_stream_run(ort_stream *s);

#ifdef __cplusplus
}
#endif
#endif
