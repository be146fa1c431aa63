/* Forward kinematics of the model's skeleton. See skeleton_fk.h. */
#include "skeleton_fk.h"

#include <math.h>
#include <string.h>

#include "error.h"
#include "mocap_math.h"

mocap_status skeleton_init(skeleton *sk, const int32_t *parents, const float (*offsets)[3],
                           int count)
{
    if (!sk || !parents || !offsets || count < 1 || count > SKELETON_MAX_JOINTS)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "skeleton: bad arguments (%d joints)", count);
    memset(sk, 0, sizeof *sk);
    sk->count = count;
    for (int j = 0; j < count; ++j) {
        int p = parents[j];
        if ((j == 0 && p != -1) || (j > 0 && (p < 0 || p >= j)))
            return mocap_fail(MOCAP_ERR_FORMAT, "skeleton: joint %d has parent %d (the root must "
                              "have -1 and every parent must come before its child)", j, p);
        sk->parents[j] = p;
        for (int k = 0; k < 3; ++k) {
            if (!isfinite(offsets[j][k]))
                return mocap_fail(MOCAP_ERR_FORMAT, "skeleton: rest offset of joint %d is not "
                                  "finite", j);
            sk->offsets[j][k] = offsets[j][k];
        }
    }
    double ident[SKELETON_MAX_JOINTS][4];
    for (int j = 0; j < count; ++j) quat_identity(ident[j]);
    skeleton_fk(sk, (const double (*)[4])ident, sk->offsets[0], NULL, sk->rest_positions);
    if (count > SKELETON_RIGHT_FOOT) {
        sk->foot_height[0] = fmax(0.0, sk->rest_positions[SKELETON_LEFT_FOOT][1]);
        sk->foot_height[1] = fmax(0.0, sk->rest_positions[SKELETON_RIGHT_FOOT][1]);
    }
    return MOCAP_OK;
}

void skeleton_fk(const skeleton *sk, const double (*local)[4], const double root[3],
                 double (*global_out)[4], double (*positions_out)[3])
{
    double g[SKELETON_MAX_JOINTS][4];
    double p[SKELETON_MAX_JOINTS][3];
    quat_copy(g[0], local[0]);
    memcpy(p[0], root, sizeof p[0]);
    for (int j = 1; j < sk->count; ++j) {
        int par = sk->parents[j];
        double off[3];
        quat_rotate(off, g[par], sk->offsets[j]);
        for (int k = 0; k < 3; ++k) p[j][k] = p[par][k] + off[k];
        quat_multiply(g[j], g[par], local[j]);
    }
    if (global_out) memcpy(global_out, g, (size_t)sk->count * sizeof g[0]);
    if (positions_out) memcpy(positions_out, p, (size_t)sk->count * sizeof p[0]);
}

int skeleton_matrix_to_quat(const float m[9], double q[4])
{
    double d[9];
    for (int i = 0; i < 9; ++i) {
        if (!isfinite(m[i])) {
            quat_identity(q);
            return -1;
        }
        d[i] = m[i];
    }
    mat3_to_quat(q, d);
    if (quat_normalize(q) != 0) {
        quat_identity(q);
        return -1;
    }
    if (q[0] < 0) for (int k = 0; k < 4; ++k) q[k] = -q[k];
    return 0;
}
