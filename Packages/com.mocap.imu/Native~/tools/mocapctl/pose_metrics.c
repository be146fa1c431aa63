/* Pose accuracy figures (pose_metrics.h). */
#include "pose_metrics.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mocap_math.h"
#include "output_file.h"
#include "platform.h"
#include "report.h"

/* The DIP/TransPose 15-joint subset (no pelvis, ankles, feet, wrists, hands) and SIP joints. */
static int dip_joint(int j)
{
    return !(j == 0 || j == 7 || j == 8 || j == 10 || j == 11 || j == 20 || j == 21 || j == 22 || j == 23);
}
static const int SIP_JOINTS[4] = {1, 2, 16, 17};

static const double ROOT_ORIGIN[3] = {0.0, 0.0, 0.0}; /* positions are root-aligned */

int pose_metrics_init(pose_metrics *m, const mocap_model_info *info)
{
    memset(m, 0, sizeof *m);
    m->fps = info->frame_rate;
    mocap_status s = skeleton_init(&m->skeleton, info->joint_parents,
                                   (const float (*)[3])info->rest_offsets, MOCAP_JOINT_COUNT);
    if (s != MOCAP_OK) return report_failure(s, "the model's skeleton");
    return 0;
}

void pose_metrics_free(pose_metrics *m)
{
    free(m->pred_root);
    free(m->vel_root);
    free(m->true_root);
    free(m->times);
    m->pred_root = m->vel_root = m->true_root = m->times = NULL;
    m->cap = 0;
}

void pose_metrics_add(pose_metrics *m, const mocap_pose *pose, const pose_truth_row *truth)
{
    double qp[MOCAP_JOINT_COUNT][4], gp[MOCAP_JOINT_COUNT][4], gt[MOCAP_JOINT_COUNT][4];
    double pp[MOCAP_JOINT_COUNT][3], ptr[MOCAP_JOINT_COUNT][3];
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        for (int k = 0; k < 4; ++k) qp[j][k] = pose->joint_rotations[j][k];
        if (quat_normalize(qp[j]) != 0) quat_identity(qp[j]);
    }
    skeleton_fk(&m->skeleton, (const double (*)[4])qp, ROOT_ORIGIN, gp, pp);
    skeleton_fk(&m->skeleton, truth->q, ROOT_ORIGIN, gt, ptr);
    double all = 0, dip = 0, sip = 0, pos = 0;
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        double a = quat_angle_deg(qp[j], truth->q[j]);
        all += a;
        if (dip_joint(j)) dip += a;
        double d2 = 0;
        for (int k = 0; k < 3; ++k) d2 += (pp[j][k] - ptr[j][k]) * (pp[j][k] - ptr[j][k]);
        pos += sqrt(d2);
    }
    for (int i = 0; i < 4; ++i) sip += quat_angle_deg(gp[SIP_JOINTS[i]], gt[SIP_JOINTS[i]]);
    m->angle_all += all / MOCAP_JOINT_COUNT;
    m->angle_dip += dip / 15.0;
    m->sip += sip / 4.0;
    m->pos_cm += 100.0 * pos / MOCAP_JOINT_COUNT;

    /* Jitter: third difference of root-aligned positions over consecutive frames. */
    if (m->compared > 0 && pose->frame_sequence != m->last_frame_sequence + 1) m->hist_len = 0;
    m->last_frame_sequence = pose->frame_sequence;
    if (m->hist_len == 3) {
        double jp = 0, jt = 0;
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            double a2 = 0, b2 = 0;
            for (int k = 0; k < 3; ++k) {
                double dp = pp[j][k] - 3 * m->hist_p[2][j][k] + 3 * m->hist_p[1][j][k] - m->hist_p[0][j][k];
                double dt = ptr[j][k] - 3 * m->hist_t[2][j][k] + 3 * m->hist_t[1][j][k] - m->hist_t[0][j][k];
                a2 += dp * dp;
                b2 += dt * dt;
            }
            jp += sqrt(a2);
            jt += sqrt(b2);
        }
        const double f3 = m->fps * m->fps * m->fps;
        m->jitter_sum += jp / MOCAP_JOINT_COUNT * f3;
        m->truth_jitter_sum += jt / MOCAP_JOINT_COUNT * f3;
        m->jitter_n++;
        memmove(m->hist_p[0], m->hist_p[1], 2 * sizeof m->hist_p[0]);
        memmove(m->hist_t[0], m->hist_t[1], 2 * sizeof m->hist_t[0]);
        m->hist_len = 2;
    }
    memcpy(m->hist_p[m->hist_len], pp, sizeof pp);
    memcpy(m->hist_t[m->hist_len], ptr, sizeof ptr);
    m->hist_len++;

    if (m->compared == m->cap) {
        size_t cap = m->cap ? m->cap * 2 : 4096;
        double *a = (double *)realloc(m->pred_root, cap * 3 * sizeof(double));
        if (a) m->pred_root = a;
        double *v = (double *)realloc(m->vel_root, cap * 3 * sizeof(double));
        if (v) m->vel_root = v;
        double *b = (double *)realloc(m->true_root, cap * 3 * sizeof(double));
        if (b) m->true_root = b;
        double *t = (double *)realloc(m->times, cap * sizeof(double));
        if (t) m->times = t;
        if (!a || !b || !t || !v) return;
        m->cap = cap;
    }
    size_t i = m->compared;
    for (int k = 0; k < 3; ++k) {
        m->pred_root[i * 3 + k] = pose->root_position[k];
        /* Integrated model velocity (no drift correction), as training/evaluate.py measures. */
        m->vel_root[i * 3 + k] = (i ? m->vel_root[(i - 1) * 3 + k] : 0.0) +
                                 (i ? pose->root_velocity[k] / m->fps : 0.0);
        m->true_root[i * 3 + k] = truth->root[k];
    }
    m->times[i] = pose->time_s;
    m->compared++;
}

/* Mean root drift over windows of w seconds starting every second: |d_pred - d_true| (m). */
static double drift_mean(const pose_metrics *m, const double *pred, double window_s)
{
    double sum = 0;
    int n = 0;
    size_t j = 0;
    double next_start = m->compared ? m->times[0] : 0;
    for (size_t i = 0; i < m->compared; ++i) {
        if (m->times[i] + 1e-9 < next_start) continue;
        next_start = m->times[i] + 1.0;
        if (j < i) j = i;
        while (j < m->compared && m->times[j] < m->times[i] + window_s - 1e-6) ++j;
        if (j >= m->compared) break;
        double e2 = 0;
        for (int k = 0; k < 3; ++k) {
            double dp = pred[j * 3 + k] - pred[i * 3 + k];
            double dt = m->true_root[j * 3 + k] - m->true_root[i * 3 + k];
            e2 += (dp - dt) * (dp - dt);
        }
        sum += sqrt(e2);
        ++n;
    }
    return n ? sum / n : NAN;
}

static const double DRIFT_WINDOWS_S[3] = {2.0, 5.0, 10.0};

void pose_metrics_print(const pose_metrics *m, const char *truth_path)
{
    if (!m->compared) {
        printf("  pose accuracy: no pose fell inside the truth's time range (%s)\n", truth_path);
        return;
    }
    const double n = (double)m->compared;
    printf("  pose accuracy against %s (%llu poses, %.1f s; the whole byte-level pipeline):\n",
           truth_path, (unsigned long long)m->compared, m->times[m->compared - 1] - m->times[0]);
    printf("    joint angle error: %.2f deg (24 joints), %.2f deg (15 DIP joints), SIP %.2f deg\n",
           m->angle_all / n, m->angle_dip / n, m->sip / n);
    printf("    joint position error (root-aligned): %.2f cm\n", m->pos_cm / n);
    printf("    root drift (pose root, drift-corrected):");
    for (int w = 0; w < 3; ++w)
        printf(" %gs %.3f m%s", DRIFT_WINDOWS_S[w], drift_mean(m, m->pred_root, DRIFT_WINDOWS_S[w]),
               w < 2 ? "," : "");
    printf("\n    root drift (integrated root_velocity):");
    for (int w = 0; w < 3; ++w)
        printf(" %gs %.3f m%s", DRIFT_WINDOWS_S[w], drift_mean(m, m->vel_root, DRIFT_WINDOWS_S[w]),
               w < 2 ? "," : "");
    printf("\n    jitter: %.2f x10^2 m/s^3 (truth %.2f)\n",
           m->jitter_n ? m->jitter_sum / (double)m->jitter_n / 100.0 : NAN,
           m->jitter_n ? m->truth_jitter_sum / (double)m->jitter_n / 100.0 : NAN);
}

/* A number for JSON: NaN and infinities (no pose, no drift window) become null. */
static void json_number(FILE *f, const char *key, double value, const char *after)
{
    if (isfinite(value)) fprintf(f, "\"%s\":%.6g%s", key, value, after);
    else fprintf(f, "\"%s\":null%s", key, after);
}

int pose_metrics_write_json(const pose_metrics *m, const char *truth_path, const char *path)
{
    FILE *f = mocap_fopen(path, "w");
    if (!f) {
        fprintf(stderr, "mocapctl: cannot write %s\n", path);
        return 1;
    }
    const double n = m->compared ? (double)m->compared : NAN;
    fputs("{", f);
    fputs("\"truth\":\"", f);
    for (const char *c = truth_path; *c; ++c) {
        if (*c == '"' || *c == '\\') fputc('\\', f);
        if ((unsigned char)*c >= 0x20) fputc(*c, f);
    }
    fprintf(f, "\",\"poses\":%llu,", (unsigned long long)m->compared);
    json_number(f, "seconds", m->compared ? m->times[m->compared - 1] - m->times[0] : NAN, ",");
    json_number(f, "angle_error_deg", m->angle_all / n, ",");
    json_number(f, "angle_error_dip_deg", m->angle_dip / n, ",");
    json_number(f, "sip_error_deg", m->sip / n, ",");
    json_number(f, "position_error_cm", m->pos_cm / n, ",");
    static const char *const drift_keys[3] = {"2s", "5s", "10s"};
    const double *roots[2] = {m->pred_root, m->vel_root};
    static const char *const root_keys[2] = {"root_drift_m", "root_drift_integrated_velocity_m"};
    for (int r = 0; r < 2; ++r) {
        fprintf(f, "\"%s\":{", root_keys[r]);
        for (int w = 0; w < 3; ++w) {
            double d = m->compared ? drift_mean(m, roots[r], DRIFT_WINDOWS_S[w]) : NAN;
            json_number(f, drift_keys[w], d, w < 2 ? "," : "},");
        }
    }
    json_number(f, "jitter_100m_s3", m->jitter_n ? m->jitter_sum / (double)m->jitter_n / 100.0 : NAN, ",");
    json_number(f, "truth_jitter_100m_s3",
                m->jitter_n ? m->truth_jitter_sum / (double)m->jitter_n / 100.0 : NAN, "}\n");
    return output_close(&f, path);
}
