/* Pose truth CSV (pose_truth.h). */
#include "pose_truth.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mocap_math.h"
#include "platform.h"

/* A data line starts with a number; headers and comments do not. */
static int is_data_line(const char *line)
{
    return (line[0] >= '0' && line[0] <= '9') || line[0] == '-';
}

int csv_first_row_columns(const char *path)
{
    FILE *f = mocap_fopen(path, "r");
    if (!f) return -1;
    static char line[16384];
    int cols = 0;
    while (fgets(line, sizeof line, f)) {
        if (!is_data_line(line)) continue;
        char *p = line, *end;
        for (;;) {
            while (*p == ',' || *p == ' ' || *p == '\t') ++p;
            strtod(p, &end);
            if (end == p) break;
            p = end;
            ++cols;
        }
        break;
    }
    fclose(f);
    return cols;
}

int pose_truth_load(const char *path, pose_truth *pt)
{
    memset(pt, 0, sizeof *pt);
    FILE *f = mocap_fopen(path, "r");
    if (!f) {
        fprintf(stderr, "mocapctl: cannot open truth file %s\n", path);
        return -1;
    }
    size_t cap = 4096;
    pt->rows = (pose_truth_row *)malloc(cap * sizeof *pt->rows);
    static char line[16384];
    while (pt->rows && fgets(line, sizeof line, f)) {
        if (!is_data_line(line)) continue;
        double v[POSE_TRUTH_COLUMNS];
        int n = 0;
        char *p = line, *end;
        while (n < POSE_TRUTH_COLUMNS) {
            while (*p == ',' || *p == ' ' || *p == '\t') ++p;
            v[n] = strtod(p, &end);
            if (end == p) break;
            p = end;
            ++n;
        }
        if (n != POSE_TRUTH_COLUMNS || !(v[1] >= -1e6 && v[1] <= 1e6)) continue; /* (int) below */
        if (pt->count == cap) {
            cap *= 2;
            pose_truth_row *g = (pose_truth_row *)realloc(pt->rows, cap * sizeof *g);
            if (!g) break;
            pt->rows = g;
        }
        pose_truth_row *r = &pt->rows[pt->count++];
        r->t = v[0];
        r->motion = (int)v[1];
        for (int k = 0; k < 3; ++k) r->root[k] = v[2 + k];
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            for (int k = 0; k < 4; ++k) r->q[j][k] = v[5 + j * 4 + k];
            quat_normalize(r->q[j]);
        }
    }
    fclose(f);
    if (!pt->rows || pt->count < 2) {
        fprintf(stderr, "mocapctl: pose truth %s has no usable rows (expected %d columns: "
                "t_session, motion, root xyz, 24 x qw qx qy qz)\n", path, POSE_TRUTH_COLUMNS);
        free(pt->rows);
        pt->rows = NULL;
        return -1;
    }
    return 0;
}

void pose_truth_free(pose_truth *pt)
{
    free(pt->rows);
    pt->rows = NULL;
    pt->count = 0;
}

int pose_truth_at(pose_truth *pt, double t, pose_truth_row *out)
{
    if (t < pt->rows[0].t - 1e-6 || t > pt->rows[pt->count - 1].t + 1e-6) return -1;
    while (pt->cursor + 1 < pt->count && pt->rows[pt->cursor + 1].t < t) pt->cursor++;
    const pose_truth_row *a = &pt->rows[pt->cursor];
    const pose_truth_row *b = &pt->rows[pt->cursor + 1 < pt->count ? pt->cursor + 1 : pt->cursor];
    double u = b->t > a->t ? (t - a->t) / (b->t - a->t) : 0.0;
    u = u < 0 ? 0 : (u > 1 ? 1 : u);
    out->t = t;
    out->motion = u < 0.5 ? a->motion : b->motion;
    for (int k = 0; k < 3; ++k) out->root[k] = a->root[k] + u * (b->root[k] - a->root[k]);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) quat_slerp(out->q[j], a->q[j], b->q[j], u);
    return 0;
}
