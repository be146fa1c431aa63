/* Sensor truth CSV (sensor_truth.h). */
#include "sensor_truth.h"

#include <stdio.h>
#include <stdlib.h>

#include "mocap_math.h"
#include "platform.h"

int sensor_truth_load(const char *path, sensor_truth *table)
{
    FILE *f = mocap_fopen(path, "r");
    if (!f) {
        fprintf(stderr, "mocapctl: cannot open truth file %s\n", path);
        return -1;
    }
    size_t cap = 4096;
    table->rows = (sensor_truth_row *)malloc(cap * sizeof(sensor_truth_row));
    table->count = 0;
    table->cursor = 0;
    char line[4096];
    while (table->rows && fgets(line, sizeof line, f)) {
        if (line[0] == '#' || line[0] == '\n' || line[0] == 't') continue;
        if (table->count == cap) {
            cap *= 2;
            sensor_truth_row *grown =
                (sensor_truth_row *)realloc(table->rows, cap * sizeof(sensor_truth_row));
            if (!grown) break;
            table->rows = grown;
        }
        sensor_truth_row *r = &table->rows[table->count];
        /* Columns: t_session, phase, then qw qx qy qz ax ay az per segment; ',' or ' ' apart. */
        double values[2 + MOCAP_SENSOR_COUNT * 7];
        int n = 0;
        char *p = line, *end;
        while (n < (int)(sizeof values / sizeof values[0])) {
            while (*p == ',' || *p == ' ' || *p == '\t') ++p;
            values[n] = strtod(p, &end);
            if (end == p) break;
            p = end;
            ++n;
        }
        /* The phase becomes an int: only a small whole number may (a damaged row is skipped). */
        int ok = n == (int)(sizeof values / sizeof values[0]) && values[1] >= -1e6 && values[1] <= 1e6;
        if (ok) {
            r->t = values[0];
            r->phase = (int)values[1];
            for (int s = 0; s < MOCAP_SENSOR_COUNT; ++s) {
                for (int k = 0; k < 4; ++k) r->q[s][k] = values[2 + s * 7 + k];
                for (int k = 0; k < 3; ++k) r->a[s][k] = values[2 + s * 7 + 4 + k];
            }
        }
        if (ok) table->count++;
    }
    fclose(f);
    if (!table->rows || table->count < 2) {
        fprintf(stderr, "mocapctl: truth file %s has no usable rows\n", path);
        free(table->rows);
        table->rows = NULL;
        return -1;
    }
    return 0;
}

void sensor_truth_free(sensor_truth *table)
{
    free(table->rows);
    table->rows = NULL;
    table->count = 0;
}

int sensor_truth_at(sensor_truth *table, double t, sensor_truth_row *out)
{
    if (t < table->rows[0].t || t > table->rows[table->count - 1].t) return -1;
    while (table->cursor + 1 < table->count && table->rows[table->cursor + 1].t < t) table->cursor++;
    const sensor_truth_row *a = &table->rows[table->cursor];
    const size_t next = table->cursor + 1 < table->count ? table->cursor + 1 : table->cursor;
    const sensor_truth_row *b = &table->rows[next];
    double u = b->t > a->t ? (t - a->t) / (b->t - a->t) : 0.0;
    if (u < 0) u = 0;
    if (u > 1) u = 1;
    out->t = t;
    out->phase = u < 0.5 ? a->phase : b->phase;
    for (int s = 0; s < MOCAP_SENSOR_COUNT; ++s) {
        quat_slerp(out->q[s], a->q[s], b->q[s], u);
        for (int k = 0; k < 3; ++k) out->a[s][k] = a->a[s][k] + u * (b->a[s][k] - a->a[s][k]);
    }
    return 0;
}
