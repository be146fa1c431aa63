/* Public BVH export (mocap_imu.h, "Streaming and export"): the streaming writer of
 * src/output/bvh_writer.c behind the stable C API, so C# (the editor's take export) writes the same
 * files as `mocapctl replay --out`. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh_writer.h"
#include "error.h"
#include "mocap_imu.h"

struct mocap_bvh_writer {
    bvh_writer *writer;
};

mocap_status mocap_bvh_options_defaults(mocap_bvh_options *options)
{
    if (!options) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_bvh_options_defaults: NULL");
    memset(options, 0, sizeof *options);
    options->struct_size = (uint32_t)sizeof *options;
    options->rotation_order = MOCAP_BVH_ZXY;
    options->frame_rate = 0.0f;
    options->flush_every = 1;
    return MOCAP_OK;
}

mocap_status mocap_bvh_open(const char *path, const mocap_model_info *info,
                            const mocap_bvh_options *options, mocap_bvh_writer **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_bvh_open: out is NULL");
    *out = NULL;
    if (!path || !path[0] || !info)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_bvh_open: path and model info are required");
    mocap_bvh_options opt;
    mocap_bvh_options_defaults(&opt);
    if (options) {
        if (options->struct_size != sizeof *options)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "mocap_bvh_options.struct_size is %u, the library expects %u",
                              (unsigned)options->struct_size, (unsigned)sizeof *options);
        opt = *options;
    }
    if (opt.rotation_order != MOCAP_BVH_ZXY && opt.rotation_order != MOCAP_BVH_XYZ)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "BVH %s: rotation_order must be ZXY (0) or XYZ (1)", path);
    double rate = opt.frame_rate > 0 ? (double)opt.frame_rate : (double)info->frame_rate;
    if (!(rate > 0) || !isfinite(rate))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "BVH %s: no frame rate (options and model info)", path);
    bvh_skeleton sk;
    mocap_status s = bvh_skeleton_from_model_info(info, &sk);
    if (s != MOCAP_OK) return s;
    mocap_bvh_writer *w = (mocap_bvh_writer *)calloc(1, sizeof *w);
    if (!w) return mocap_fail(MOCAP_ERR_NO_MEMORY, "BVH %s: out of memory", path);
    s = bvh_writer_open(path, &sk, 1.0 / rate,
                        opt.rotation_order == MOCAP_BVH_XYZ ? BVH_ORDER_XYZ : BVH_ORDER_ZXY, &w->writer);
    if (s != MOCAP_OK) {
        free(w);
        return s;
    }
    bvh_writer_set_flush_every(w->writer, opt.flush_every);
    *out = w;
    return MOCAP_OK;
}

mocap_status mocap_bvh_append(mocap_bvh_writer *w, const mocap_pose *pose)
{
    if (!w || !pose) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_bvh_append: NULL argument");
    return bvh_writer_append_pose(w->writer, pose);
}

uint64_t mocap_bvh_frames(const mocap_bvh_writer *w) { return w ? bvh_writer_frames(w->writer) : 0; }

mocap_status mocap_bvh_close(mocap_bvh_writer *w)
{
    if (!w) return MOCAP_OK;
    mocap_status s = bvh_writer_close(w->writer);
    free(w);
    return s;
}
