/* Public mocap_model_* API: a thin layer over the ONNX Runtime module (onnx_runtime.h), which
 * loads the library at run time and validates the model against docs/model-contract.md. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "mocap_imu.h"
#include "onnx_runtime.h"
#include "solver.h"

struct mocap_model {
    ort_model *ort;
    mocap_model_info info;
};

mocap_status mocap_model_options_defaults(mocap_model_options *o)
{
    if (!o) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "model options are NULL");
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->execution_provider = MOCAP_PROVIDER_CPU;
    /* One thread: a frame is ~0.1-0.2 ms of small operators that gain nothing from more, and
     * ONNX Runtime's own default (a pool thread per core) keeps its idle threads spinning, a
     * whole core busy for as long as the session lives. */
    o->intra_op_threads = 1;
    o->optimization_level = 3;
    o->cuda_device = 0;
    return MOCAP_OK;
}

mocap_status mocap_model_open(const char *path, const mocap_model_options *options,
                              mocap_model **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_model_open: out is NULL");
    *out = NULL;
    if (!path || !path[0]) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_model_open: no path");
    mocap_model_options o;
    if (options) {
        if (options->struct_size != sizeof(mocap_model_options))
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "model options struct_size is %u, this "
                              "library expects %u (call mocap_model_options_defaults)",
                              (unsigned)options->struct_size, (unsigned)sizeof(mocap_model_options));
        o = *options;
    } else {
        mocap_model_options_defaults(&o);
    }
    if (o.execution_provider != MOCAP_PROVIDER_CPU && o.execution_provider != MOCAP_PROVIDER_CUDA)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "execution_provider %d is unknown",
                          o.execution_provider);
    if (memchr(o.onnxruntime_path, '\0', sizeof o.onnxruntime_path) == NULL)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "onnxruntime_path is not NUL-terminated");
    ort_options oo;
    ort_options_defaults(&oo);
    oo.library_path = o.onnxruntime_path[0] ? o.onnxruntime_path : NULL;
    oo.intra_op_threads = o.intra_op_threads;
    oo.optimization_level = o.optimization_level;
    oo.provider = o.execution_provider == MOCAP_PROVIDER_CUDA ? ORT_PROVIDER_CUDA : ORT_PROVIDER_CPU;
    oo.cuda_device = o.cuda_device;

    mocap_model *m = (mocap_model *)calloc(1, sizeof *m);
    if (!m) return mocap_fail(MOCAP_ERR_NO_MEMORY, "mocap_model_open: out of memory");
    mocap_status st = ort_model_open(path, &oo, &m->ort);
    if (st != MOCAP_OK) {
        free(m);
        return st; /* ort_model_open's message names the file and what differs */
    }
    const ort_model_info *oi = ort_model_get_info(m->ort);
    mocap_model_info *info = &m->info;
    info->contract_version = oi->contract_version;
    info->sensor_count = (uint32_t)oi->sensor_count;
    info->sensor_required_mask = oi->required_mask;
    for (int k = 0; k < oi->sensor_count; ++k) info->sensor_segments[k] = oi->sensor_segments[k];
    info->frame_rate = (float)oi->frame_rate;
    info->state_layers = oi->state_layers;
    info->state_size = oi->state_size;
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        info->joint_parents[j] = oi->joint_parents[j];
        memcpy(info->rest_offsets[j], oi->rest_offsets[j], sizeof info->rest_offsets[j]);
        snprintf(info->joint_names[j], sizeof info->joint_names[j], "%s", oi->joint_names[j]);
    }
    snprintf(info->precision, sizeof info->precision, "%s", oi->precision);
    snprintf(info->model_name, sizeof info->model_name, "%s", oi->model_name);
    *out = m;
    return MOCAP_OK;
}

mocap_status mocap_model_get_info(const mocap_model *m, mocap_model_info *out)
{
    if (!m || !out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "model or out is NULL");
    *out = m->info;
    return MOCAP_OK;
}

mocap_status mocap_model_get_stride_scaling(const mocap_model *m, float *training_height_m,
                                            float *stride_exponent)
{
    if (!m || !training_height_m || !stride_exponent)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "model or an out pointer is NULL");
    const ort_model_info *oi = ort_model_get_info(m->ort);
    if (!oi || !oi->has_stride_scaling)
        return mocap_fail(MOCAP_ERR_UNSUPPORTED, "model '%s' has no stride scaling (metadata "
                          "mocap.training_height and mocap.stride_exponent)", m->info.model_name);
    *training_height_m = (float)oi->training_height;
    *stride_exponent = (float)oi->stride_exponent;
    return MOCAP_OK;
}

void mocap_model_close(mocap_model *m)
{
    if (!m) return;
    ort_model_close(m->ort);
    free(m);
}

ort_model *model_ort(mocap_model *m) { return m ? m->ort : NULL; }
const mocap_model_info *model_info(const mocap_model *m) { return m ? &m->info : NULL; }
int model_has_mask(const mocap_model *m)
{
    const ort_model_info *oi = m ? ort_model_get_info(m->ort) : NULL;
    return oi ? oi->has_mask : 0;
}
