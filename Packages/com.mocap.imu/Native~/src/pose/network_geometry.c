/* The pose model's geometry outside the graph (network_geometry.h). Single precision, as the
 * exported graphs compute it, so a contract-3 model answers what its contract-2 twin does to
 * float rounding. */
#include "network_geometry.h"

#include <math.h>
#include <string.h>

#include "error.h"

/* Reflection in the sagittal plane: x changes sign. */
static const float REFLECT[3] = {-1.0f, 1.0f, 1.0f};

/* A mirror table must pair its entries: each maps to one whose image is itself. */
static mocap_status copy_pairing(const int *table, int n, const char *what, int *out)
{
    for (int k = 0; k < n; ++k) {
        const int m = table[k];
        if (m < 0 || m >= n || table[m] != k)
            return mocap_fail(MOCAP_ERR_FORMAT, "mirror %s table: %s %d maps to %d, not one half "
                              "of a pair", what, what, k, m);
        out[k] = m;
    }
    return MOCAP_OK;
}

mocap_status network_geometry_init(network_geometry *g, int sensors, int pelvis, int masked,
                                   int mirror, float acceleration_scale,
                                   const int *mirror_sensors, const int *mirror_joints,
                                   const int *parents, const int *anchor_joints)
{
    if (!g || !parents || !anchor_joints)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "network_geometry_init: NULL argument");
    memset(g, 0, sizeof *g);
    if (sensors < 1 || sensors > MOCAP_MAX_SENSORS)
        return mocap_fail(MOCAP_ERR_FORMAT, "%d sensors; the engine carries 1..%d", sensors,
                          MOCAP_MAX_SENSORS);
    if (pelvis < 0 || pelvis >= sensors)
        return mocap_fail(MOCAP_ERR_FORMAT, "the network's geometry needs the pelvis among its "
                          "sensors (it removes the pelvis heading)");
    if (!(acceleration_scale > 0.0f) || !isfinite(acceleration_scale))
        return mocap_fail(MOCAP_ERR_FORMAT, "acceleration scale %g is not a positive number",
                          (double)acceleration_scale);
    g->sensors = sensors;
    g->pelvis = pelvis;
    g->masked = masked ? 1 : 0;
    g->mirror = mirror ? 1 : 0;
    g->acceleration_scale = acceleration_scale;
    for (int j = 0; j < GEOMETRY_JOINTS; ++j) {
        if ((j == 0 && parents[j] != -1) || (j > 0 && (parents[j] < 0 || parents[j] >= j)))
            return mocap_fail(MOCAP_ERR_FORMAT, "joint %d's parent %d: the geometry needs each "
                              "joint after its parent and the root first", j, parents[j]);
        g->parents[j] = parents[j];
    }
    if (g->mirror) {
        if (!mirror_sensors || !mirror_joints)
            return mocap_fail(MOCAP_ERR_FORMAT, "the mirror average needs the mirror tables");
        mocap_status r = copy_pairing(mirror_sensors, sensors, "sensor", g->mirror_sensors);
        if (r == MOCAP_OK) r = copy_pairing(mirror_joints, GEOMETRY_JOINTS, "joint", g->mirror_joints);
        if (r != MOCAP_OK) return r;
        if (mirror_sensors[pelvis] != pelvis)
            return mocap_fail(MOCAP_ERR_FORMAT, "mirror sensor table: the pelvis is its own mirror "
                              "image, not sensor %d's", mirror_sensors[pelvis]);
    }
    for (int k = 0; k < sensors; ++k) {
        int j = anchor_joints[k];
        if (j < 0 || j >= GEOMETRY_JOINTS)
            return mocap_fail(MOCAP_ERR_FORMAT, "sensor %d anchors joint %d, not one of the %d", k,
                              j, GEOMETRY_JOINTS);
        if (j == 0) continue; /* the pelvis is a residual on its measurement already */
        int a = 0;
        while (a < g->anchored && g->anchor_joint[a] != j) ++a;
        g->anchor_joint[a] = j;
        g->anchor_sensor[a] = k;
        if (a == g->anchored) ++g->anchored;
    }
    g->features = sensors * 12 + (sensors - 1) * 12 + (g->masked ? sensors : 0);
    return MOCAP_OK;
}

int network_geometry_rows(const network_geometry *g) { return g && g->mirror ? 2 : 1; }

/* --------------------------------------------------------------------------------- helpers */

/* out = a^T b, 3x3 row-major */
static void mul_at_b(float out[9], const float a[9], const float b[9])
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            out[i * 3 + j] = a[0 * 3 + i] * b[0 * 3 + j] + a[1 * 3 + i] * b[1 * 3 + j] +
                             a[2 * 3 + i] * b[2 * 3 + j];
}

static void mul_ab(float out[9], const float a[9], const float b[9])
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            out[i * 3 + j] = a[i * 3 + 0] * b[0 * 3 + j] + a[i * 3 + 1] * b[1 * 3 + j] +
                             a[i * 3 + 2] * b[2 * 3 + j];
}

/* out = m^T v */
static void mul_at_v(float out[3], const float m[9], const float v[3])
{
    for (int i = 0; i < 3; ++i) out[i] = m[0 * 3 + i] * v[0] + m[1 * 3 + i] * v[1] + m[2 * 3 + i] * v[2];
}

/* A vector scaled to unit length; a zero vector stays zero (as ONNX Runtime's LpNormalization). */
static void unit3(float v[3])
{
    float n = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (n > 0.0f) {
        v[0] /= n;
        v[1] /= n;
        v[2] /= n;
    } else {
        v[0] = v[1] = v[2] = 0.0f;
    }
}

/* Two columns (3x2, row-major, [row][column]) -> rotation (3x3 row-major). */
static void gram_schmidt(float out[9], const float cols[6])
{
    float b1[3] = {cols[0], cols[2], cols[4]}, b2[3] = {cols[1], cols[3], cols[5]};
    unit3(b1);
    float d = b1[0] * b2[0] + b1[1] * b2[1] + b1[2] * b2[2];
    for (int i = 0; i < 3; ++i) b2[i] -= d * b1[i];
    unit3(b2);
    float b3[3] = {b1[1] * b2[2] - b1[2] * b2[1], b1[2] * b2[0] - b1[0] * b2[2],
                   b1[0] * b2[1] - b1[1] * b2[0]};
    for (int i = 0; i < 3; ++i) {
        out[i * 3 + 0] = b1[i];
        out[i * 3 + 1] = b2[i];
        out[i * 3 + 2] = b3[i];
    }
}

/* Each of the two columns scaled to unit length. */
static void unit_columns(float cols[6])
{
    for (int c = 0; c < 2; ++c) {
        float v[3] = {cols[c], cols[2 + c], cols[4 + c]};
        unit3(v);
        cols[c] = v[0];
        cols[2 + c] = v[1];
        cols[4 + c] = v[2];
    }
}

/* ------------------------------------------------------------------------------- features */

static void row_features(const network_geometry *g, const float *orientation,
                         const float *acceleration, const float *mask, int mirrored,
                         float *features, geometry_row *row)
{
    const int n = g->sensors, p = g->pelvis;
    float rot[MOCAP_MAX_SENSORS][9], acc[MOCAP_MAX_SENSORS][3];
    for (int k = 0; k < n; ++k) {
        const int src = mirrored ? g->mirror_sensors[k] : k;
        const float m = g->masked && mask ? mask[src] : 1.0f;
        row->present[k] = m;
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                float v = orientation[src * 9 + i * 3 + j];
                if (mirrored) v *= REFLECT[i] * REFLECT[j];
                /* a missing sensor's zeros read as no rotation */
                rot[k][i * 3 + j] = g->masked ? v * m + (i == j ? 1.0f - m : 0.0f) : v;
            }
            float a = acceleration[src * 3 + i];
            if (mirrored) a *= REFLECT[i];
            acc[k][i] = g->masked ? a * m : a;
        }
    }

    /* heading of the pelvis: h = f_xz - f_y * u_xz, f and u its forward and up columns */
    const float *r0 = rot[p];
    float hx = r0[2] - r0[5] * r0[1], hz = r0[8] - r0[5] * r0[7];
    float hn = sqrtf(hx * hx + hz * hz);
    float s = hn > 0.0f ? hx / hn : 0.0f, c = hn > 0.0f ? hz / hn : 0.0f;
    float *ry = row->heading;
    ry[0] = c;  ry[1] = 0.0f; ry[2] = s;
    ry[3] = 0.0f; ry[4] = 1.0f; ry[5] = 0.0f;
    ry[6] = -s; ry[7] = 0.0f; ry[8] = c;

    const float scale = g->acceleration_scale;
    float *f_ori = features, *f_acc = f_ori + 9 * n, *f_rel = f_acc + 3 * n;
    float *f_rel_acc = f_rel + 9 * (n - 1), *f_mask = f_rel_acc + 3 * (n - 1);
    for (int k = 0; k < n; ++k) {
        const float m = g->masked ? row->present[k] : 1.0f;
        mul_at_b(row->oriented[k], ry, rot[k]);
        for (int e = 0; e < 9; ++e) f_ori[k * 9 + e] = row->oriented[k][e] * m;
        float a[3];
        mul_at_v(a, ry, acc[k]);
        for (int i = 0; i < 3; ++i) f_acc[k * 3 + i] = a[i] / scale * m;
    }
    int o = 0;
    for (int k = 0; k < n; ++k) {
        if (k == p) continue;
        const float m = g->masked ? row->present[k] * row->present[p] : 1.0f;
        float rel[9], d[3], a[3];
        mul_at_b(rel, r0, rot[k]);
        for (int e = 0; e < 9; ++e) f_rel[o * 9 + e] = rel[e] * m;
        for (int i = 0; i < 3; ++i) d[i] = acc[k][i] - acc[p][i];
        mul_at_v(a, r0, d);
        for (int i = 0; i < 3; ++i) f_rel_acc[o * 3 + i] = a[i] / scale * m;
        ++o;
    }
    if (g->masked)
        for (int k = 0; k < n; ++k) f_mask[k] = row->present[k];
}

void network_geometry_features(const network_geometry *g, const float *orientation,
                               const float *acceleration, const float *mask, float *features,
                               size_t row_stride, geometry_row *rows)
{
    const int r = network_geometry_rows(g);
    for (int k = 0; k < r; ++k)
        row_features(g, orientation, acceleration, mask, k == 1,
                     features + (size_t)k * row_stride, &rows[k]);
}

/* -------------------------------------------------------------------------------- outputs */

/* One row's numbers -> each joint's two columns (joint 0 in the model frame, the others local),
 * root velocity (model frame) and contact probabilities. */
static void row_outputs(const network_geometry *g, const float *out, const geometry_row *row,
                        float columns[GEOMETRY_JOINTS][6], float velocity[3], float contact[2])
{
    const float *residual = out;
    for (int j = 0; j < GEOMETRY_JOINTS; ++j) {
        memcpy(columns[j], residual + j * 6, sizeof columns[j]);
        if (j == 0) {
            const float *rp = row->oriented[g->pelvis];
            for (int i = 0; i < 3; ++i) {
                columns[0][i * 2 + 0] += rp[i * 3 + 0];
                columns[0][i * 2 + 1] += rp[i * 3 + 1];
            }
        } else {
            columns[j][0] += 1.0f; /* the rest pose: identity's first two columns */
            columns[j][3] += 1.0f;
        }
    }
    if (g->anchored) {
        /* each anchored bone's parent from the predicted (not anchored) rotations above it */
        float local[GEOMETRY_JOINTS][9], global[GEOMETRY_JOINTS][9];
        for (int j = 0; j < GEOMETRY_JOINTS; ++j) gram_schmidt(local[j], columns[j]);
        memcpy(global[0], local[0], sizeof global[0]);
        for (int j = 1; j < GEOMETRY_JOINTS; ++j) mul_ab(global[j], global[g->parents[j]], local[j]);
        float anchored[MOCAP_MAX_SENSORS][6];
        for (int a = 0; a < g->anchored; ++a) {
            const int j = g->anchor_joint[a], k = g->anchor_sensor[a];
            float measured[9];
            mul_at_b(measured, global[g->parents[j]], row->oriented[k]);
            const float m = g->masked ? row->present[k] : 1.0f;
            for (int i = 0; i < 3; ++i)
                for (int c = 0; c < 2; ++c)
                    anchored[a][i * 2 + c] = residual[j * 6 + i * 2 + c] + measured[i * 3 + c] * m +
                                             (i == c ? 1.0f - m : 0.0f);
        }
        for (int a = 0; a < g->anchored; ++a)
            memcpy(columns[g->anchor_joint[a]], anchored[a], sizeof anchored[a]);
    }
    /* the pelvis out of the heading frame */
    const float *ry = row->heading;
    float pelvis[6];
    for (int i = 0; i < 3; ++i)
        for (int c = 0; c < 2; ++c)
            pelvis[i * 2 + c] = ry[i * 3 + 0] * columns[0][0 * 2 + c] +
                                ry[i * 3 + 1] * columns[0][1 * 2 + c] +
                                ry[i * 3 + 2] * columns[0][2 * 2 + c];
    memcpy(columns[0], pelvis, sizeof pelvis);
    const float *vh = out + GEOMETRY_JOINTS * 6;
    for (int i = 0; i < 3; ++i) velocity[i] = ry[i * 3 + 0] * vh[0] + ry[i * 3 + 1] * vh[1] + ry[i * 3 + 2] * vh[2];
    for (int f = 0; f < 2; ++f) contact[f] = 1.0f / (1.0f + expf(-vh[3 + f]));
}

void network_geometry_outputs(const network_geometry *g, const float *network_output,
                              size_t row_stride, const geometry_row *rows, float *rotations,
                              float *velocity, float *contact)
{
    float columns[GEOMETRY_JOINTS][6];
    row_outputs(g, network_output, &rows[0], columns, velocity, contact);
    if (!g->mirror) {
        for (int j = 0; j < GEOMETRY_JOINTS; ++j) gram_schmidt(rotations + j * 9, columns[j]);
        return;
    }
    float back[GEOMETRY_JOINTS][6], back_velocity[3], back_contact[2];
    row_outputs(g, network_output + row_stride, &rows[1], back, back_velocity, back_contact);
    for (int j = 0; j < GEOMETRY_JOINTS; ++j) {
        float sum[6], other[6];
        memcpy(sum, columns[j], sizeof sum);
        memcpy(other, back[g->mirror_joints[j]], sizeof other);
        unit_columns(sum);
        unit_columns(other);
        for (int i = 0; i < 3; ++i)
            for (int c = 0; c < 2; ++c) sum[i * 2 + c] += other[i * 2 + c] * REFLECT[i] * REFLECT[c];
        gram_schmidt(rotations + j * 9, sum);
    }
    for (int i = 0; i < 3; ++i) velocity[i] = 0.5f * (velocity[i] + back_velocity[i] * REFLECT[i]);
    const float left = contact[0], right = contact[1];
    contact[0] = 0.5f * (left + back_contact[1]);
    contact[1] = 0.5f * (right + back_contact[0]);
}
