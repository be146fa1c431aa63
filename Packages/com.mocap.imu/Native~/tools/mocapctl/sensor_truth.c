/* Sensor truth CSV (sensor_truth.h). */
#include "sensor_truth.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mocap_math.h"
#include "platform.h"

#define TRUTH_MAX_VALUES (2 + MOCAP_MAX_SENSORS * 7)

/* The header "t_session,phase,pelvis_qw,...,pelvis_az,left_wrist_qw,...": the segment of each
 * group of seven columns. 0, or -1 after printing why. */
static int read_header(const char *path, char *line, sensor_truth *table)
{
    int column = 0, groups = 0;
    char *save = line;
    for (char *p = line;; ++p) {
        if (*p != ',' && *p != '\n' && *p != '\r' && *p != '\0') continue;
        const char end = *p;
        *p = '\0';
        /* Columns 2, 9, 16 ... open a sensor's group: NAME_qw. */
        if (column >= 2 && (column - 2) % 7 == 0) {
            size_t len = strlen(save);
            if (len < 4 || strcmp(save + len - 3, "_qw") != 0) {
                fprintf(stderr, "mocapctl: truth file %s: column %d is '%s', not SEGMENT_qw\n", path,
                        column + 1, save);
                return -1;
            }
            save[len - 3] = '\0';
            const int32_t seg = mocap_segment_find(save);
            if (seg < 0 || groups == MOCAP_MAX_SENSORS || (table->segment_mask >> seg) & 1u) {
                fprintf(stderr, "mocapctl: truth file %s: '%s' is not a segment of its own "
                                "(unknown, or named twice)\n", path, save);
                return -1;
            }
            table->segments[groups++] = seg;
            table->segment_mask |= 1u << seg;
        }
        column++;
        save = p + 1;
        if (end != ',') break;
    }
    if (groups == 0 || column != 2 + 7 * groups) {
        fprintf(stderr, "mocapctl: truth file %s: the header has %d columns, expected 2 + 7 per "
                        "sensor\n", path, column);
        return -1;
    }
    table->segment_count = groups;
    return 0;
}

int sensor_truth_load(const char *path, sensor_truth *table)
{
    FILE *f = mocap_fopen(path, "r");
    if (!f) {
        fprintf(stderr, "mocapctl: cannot open truth file %s\n", path);
        return -1;
    }
    memset(table, 0, sizeof *table);
    mocap_session_config defaults;
    mocap_config_defaults(&defaults);
    table->segment_count = (int)defaults.sensor_count;
    for (int k = 0; k < table->segment_count; ++k) {
        table->segments[k] = defaults.sensor_segments[k];
        table->segment_mask |= 1u << defaults.sensor_segments[k];
    }
    size_t cap = 4096;
    table->rows = (sensor_truth_row *)malloc(cap * sizeof(sensor_truth_row));
    char line[8192];
    int header_seen = 0;
    while (table->rows && fgets(line, sizeof line, f)) {
        if (line[0] == '#' || line[0] == '\n') continue;
        if (line[0] == 't') {
            if (header_seen || table->count > 0) continue;
            header_seen = 1;
            table->segment_mask = 0;
            if (read_header(path, line, table) != 0) {
                fclose(f);
                free(table->rows);
                table->rows = NULL;
                return -1;
            }
            continue;
        }
        if (table->count == cap) {
            cap *= 2;
            sensor_truth_row *grown =
                (sensor_truth_row *)realloc(table->rows, cap * sizeof(sensor_truth_row));
            if (!grown) break;
            table->rows = grown;
        }
        sensor_truth_row *r = &table->rows[table->count];
        /* Columns: t_session, phase, then qw qx qy qz ax ay az per sensor; ',' or ' ' apart. */
        const int expected = 2 + 7 * table->segment_count;
        double values[TRUTH_MAX_VALUES];
        int n = 0;
        char *p = line, *end;
        while (n < expected) {
            while (*p == ',' || *p == ' ' || *p == '\t') ++p;
            values[n] = strtod(p, &end);
            if (end == p) break;
            p = end;
            ++n;
        }
        /* The phase becomes an int: only a small whole number may (a damaged row is skipped). */
        int ok = n == expected && values[1] >= -1e6 && values[1] <= 1e6;
        if (ok) {
            memset(r, 0, sizeof *r);
            r->t = values[0];
            r->phase = (int)values[1];
            for (int k = 0; k < table->segment_count; ++k) {
                const int seg = table->segments[k];
                for (int c = 0; c < 4; ++c) r->q[seg][c] = values[2 + k * 7 + c];
                for (int c = 0; c < 3; ++c) r->a[seg][c] = values[2 + k * 7 + 4 + c];
            }
            table->count++;
        }
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
    for (int k = 0; k < table->segment_count; ++k) {
        const int seg = table->segments[k];
        quat_slerp(out->q[seg], a->q[seg], b->q[seg], u);
        for (int c = 0; c < 3; ++c) out->a[seg][c] = a->a[seg][c] + u * (b->a[seg][c] - a->a[seg][c]);
    }
    return 0;
}
