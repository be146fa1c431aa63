/* A minimal generic ONNX runner: any model with one float32 input and one float32 output of
 * static shape, through the same ONNX Runtime library the engine loads (ort_library_load in
 * onnx_runtime.h). Used by `mocapctl bench tip` to run a network of TIP's shape, which the
 * contract-checking loader refuses by design.
 *
 * Buffers are allocated once at open with their ORT tensors wrapped around them; a run allocates
 * nothing on our side. One thread at a time per runner. Errors: status + mocap_last_error(). */
#ifndef MOCAP_ONNX_GENERIC_H
#define MOCAP_ONNX_GENERIC_H

#include <stddef.h>
#include <stdint.h>
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ort_generic ort_generic;

/* Loads ONNX Runtime if needed (NULL: the engine's search order) and the model at path, CPU,
 * all graph optimisations, intra_op_threads (0: ONNX Runtime's default), one inter-op thread.
 * The model must have exactly one input and one output, float32, every dimension static. */
mocap_status ort_generic_open(const char *path, int intra_op_threads, ort_generic **out);
void ort_generic_close(ort_generic *g);

/* Shapes (rank <= 8) and element counts of the input and output. */
int ort_generic_input_rank(const ort_generic *g);
const int64_t *ort_generic_input_shape(const ort_generic *g);
size_t ort_generic_input_count(const ort_generic *g);
int ort_generic_output_rank(const ort_generic *g);
const int64_t *ort_generic_output_shape(const ort_generic *g);
size_t ort_generic_output_count(const ort_generic *g);

/* The buffers: fill the input, run, read the output (row-major float32). */
float *ort_generic_input(ort_generic *g);
const float *ort_generic_output(const ort_generic *g);
mocap_status ort_generic_run(ort_generic *g);

#ifdef __cplusplus
}
#endif
#endif
