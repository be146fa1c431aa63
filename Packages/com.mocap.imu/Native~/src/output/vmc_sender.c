/* VMC protocol sender (see vmc_sender.h and mocap_imu.h "Streaming and export"). */
#include "vmc_sender.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "osc_encoder.h"
#include "smpl_skeleton.h"
#include "udp_sender.h"

/* The first VMC_BONE_COUNT joints of the SMPL-24 order are those that drive a humanoid bone. */
const char *vmc_bone_name(const char *smpl_joint)
{
    int j = smpl_joint_index(smpl_joint);
    return j >= 0 && j < VMC_BONE_COUNT ? smpl_humanoid_bone(j) : NULL;
}

void vmc_bone_pair(int i, const char **smpl_joint, const char **bone)
{
    int ok = i >= 0 && i < VMC_BONE_COUNT;
    if (smpl_joint) *smpl_joint = ok ? smpl_joint_name(i) : NULL;
    if (bone) *bone = ok ? smpl_humanoid_bone(i) : NULL;
}

void vmc_position_to_unity(const float model[3], float unity[3])
{
    unity[0] = -model[0];
    unity[1] = model[1];
    unity[2] = model[2];
}

void vmc_rotation_to_unity(const float q[4], float unity_xyzw[4])
{
    int ok = 0;
    for (int k = 0; k < 4; ++k) {
        if (!isfinite(q[k])) {
            ok = 0;
            break;
        }
        if (q[k] != 0.0f) ok = 1;
    }
    if (!ok) {
        unity_xyzw[0] = unity_xyzw[1] = unity_xyzw[2] = 0.0f;
        unity_xyzw[3] = 1.0f;
        return;
    }
    /* Mirroring X (M = diag(-1,1,1)) turns R into M R M: the rotation axis (an axial vector)
     * becomes det(M) M a = (ax, -ay, -az), the angle is unchanged. */
    unity_xyzw[0] = q[1];
    unity_xyzw[1] = -q[2];
    unity_xyzw[2] = -q[3];
    unity_xyzw[3] = q[0];
}

static void put_transform(osc_writer *w, const char *address, const char *name, const float p[3],
                          const float q_xyzw[4])
{
    osc_message_begin(w, address, ",sfffffff");
    osc_arg_string(w, name);
    for (int k = 0; k < 3; ++k) osc_arg_float(w, p[k]);
    for (int k = 0; k < 4; ++k) osc_arg_float(w, q_xyzw[k]);
    osc_message_end(w);
}

size_t vmc_encode_pose(uint8_t *buf, size_t cap, const mocap_model_info *info,
                       const mocap_pose *pose, int32_t calibration_state, uint32_t *bones)
{
    if (bones) *bones = 0;
    if (!info || !pose) return 0;
    int joint_of[VMC_BONE_COUNT];
    int found = 0;
    for (int i = 0; i < VMC_BONE_COUNT; ++i) {
        joint_of[i] = -1;
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            if (strncmp(info->joint_names[j], smpl_joint_name(i), sizeof info->joint_names[j]) == 0) {
                joint_of[i] = j;
                found++;
                break;
            }
        }
    }
    if (found == 0 || joint_of[0] < 0) return 0; /* no pelvis: not an SMPL skeleton */
    const int pelvis = joint_of[0];

    osc_writer w;
    osc_writer_init(&w, buf, cap);
    osc_bundle_begin(&w, OSC_TIMETAG_IMMEDIATELY);
    if (calibration_state >= 0) {
        osc_message_begin(&w, "/VMC/Ext/OK", ",iii");
        osc_arg_int32(&w, 1);
        osc_arg_int32(&w, calibration_state);
        osc_arg_int32(&w, 0);
    } else {
        osc_message_begin(&w, "/VMC/Ext/OK", ",i");
        osc_arg_int32(&w, 1);
    }
    osc_message_end(&w);
    osc_message_begin(&w, "/VMC/Ext/T", ",f");
    osc_arg_float(&w, (float)pose->time_s);
    osc_message_end(&w);

    /* Root on the floor under the pelvis: Root * Hips(rest offset, global rotation) = pelvis. */
    float root_model[3], p[3], q[4];
    for (int k = 0; k < 3; ++k)
        root_model[k] = pose->root_position[k] - info->rest_offsets[pelvis][k];
    vmc_position_to_unity(root_model, p);
    const float identity[4] = {0.0f, 0.0f, 0.0f, 1.0f};
    put_transform(&w, "/VMC/Ext/Root/Pos", "root", p, identity);

    uint32_t n = 0;
    for (int i = 0; i < VMC_BONE_COUNT; ++i) {
        int j = joint_of[i];
        if (j < 0) continue;
        vmc_position_to_unity(info->rest_offsets[j], p);
        vmc_rotation_to_unity(pose->joint_rotations[j], q);
        put_transform(&w, "/VMC/Ext/Bone/Pos", smpl_humanoid_bone(i), p, q);
        n++;
    }
    osc_bundle_end(&w);
    size_t size = osc_writer_finish(&w);
    if (size && bones) *bones = n;
    return size;
}

/* ---------------------------------------------------------------------------------------- */
/* Public API                                                                                 */

struct mocap_vmc {
    udp_sender *udp;
    mocap_vmc_options options;
    mocap_vmc_stats stats;
    int have_due;
    double due_s;      /* pose time from which the next bundle may go */
    double last_t;
    uint8_t buf[VMC_BUNDLE_CAPACITY];
};

mocap_status mocap_vmc_options_defaults(mocap_vmc_options *options)
{
    if (!options) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_vmc_options_defaults: NULL");
    memset(options, 0, sizeof *options);
    options->struct_size = (uint32_t)sizeof *options;
    options->max_rate_hz = 60.0f;
    options->allow_remote = 0;
    options->calibration_state = 3;
    return MOCAP_OK;
}

mocap_status mocap_vmc_open(const char *destination, const mocap_vmc_options *options,
                            mocap_vmc **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_vmc_open: out is NULL");
    *out = NULL;
    mocap_vmc_options opt;
    mocap_vmc_options_defaults(&opt);
    if (options) {
        if (options->struct_size != sizeof *options)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "mocap_vmc_options.struct_size is %u, the library expects %u",
                              (unsigned)options->struct_size, (unsigned)sizeof *options);
        if (!isfinite(options->max_rate_hz))
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_vmc_options.max_rate_hz is not finite");
        if (options->calibration_state > 3 || options->calibration_state < -1)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "mocap_vmc_options.calibration_state must be -1 or 0..3 (got %d)",
                              (int)options->calibration_state);
        opt = *options;
    }
    mocap_vmc *v = (mocap_vmc *)calloc(1, sizeof *v);
    if (!v) return mocap_fail(MOCAP_ERR_NO_MEMORY, "mocap_vmc_open: out of memory");
    mocap_status s = udp_sender_open(destination, opt.allow_remote != 0, &v->udp);
    if (s != MOCAP_OK) {
        free(v);
        return s;
    }
    v->options = opt;
    *out = v;
    return MOCAP_OK;
}

mocap_status mocap_vmc_send_pose(mocap_vmc *v, const mocap_model_info *info, const mocap_pose *pose)
{
    if (!v || !info || !pose)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_vmc_send_pose: NULL argument");
    const double t = pose->time_s;
    if (!isfinite(t)) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_vmc_send_pose: time_s is not finite");
    v->stats.poses++;
    if (v->have_due && t < v->last_t - 1.0) v->have_due = 0; /* time went back: a new stream */
    v->last_t = t;
    const double rate = v->options.max_rate_hz;
    const double period = rate > 0 ? 1.0 / rate : 0.0;
    if (period > 0 && v->have_due && t < v->due_s - 1e-3 * period) {
        v->stats.skipped_rate++;
        return MOCAP_ERR_NO_DATA;
    }
    uint32_t bones = 0;
    size_t size = vmc_encode_pose(v->buf, sizeof v->buf, info, pose, v->options.calibration_state, &bones);
    if (size == 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "VMC to %s: the model info has no SMPL joint "
                          "names (pelvis, spine1, ...)", udp_sender_address(v->udp));
    /* Bundles are due every period of pose time; a sender that fell behind starts over from now. */
    if (period > 0) {
        v->due_s = (v->have_due && t - v->due_s < period) ? v->due_s + period : t + period;
        v->have_due = 1;
    }
    mocap_status s = udp_sender_send(v->udp, v->buf, size);
    if (s != MOCAP_OK) {
        v->stats.send_failures++;
        return s;
    }
    v->stats.bundles_sent++;
    v->stats.bytes_sent += size;
    v->stats.bones_per_bundle = bones;
    v->stats.last_bundle_size = (uint32_t)size;
    return MOCAP_OK;
}

mocap_status mocap_vmc_get_stats(const mocap_vmc *v, mocap_vmc_stats *out)
{
    if (!v || !out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_vmc_get_stats: NULL argument");
    *out = v->stats;
    return MOCAP_OK;
}

void mocap_vmc_close(mocap_vmc *v)
{
    if (!v) return;
    udp_sender_close(v->udp);
    free(v);
}
