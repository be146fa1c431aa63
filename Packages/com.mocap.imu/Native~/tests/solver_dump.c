/* solver_dump: runs the engine's pose solver over a capture and writes, for every pose, the exact
 * calibrated inputs the model was fed and the pose (for tests/golden_pose_test.py).
 *
 *   solver_dump MODEL.onnx CAPTURE OUT.bin [HEADING_S STRAP_S TPOSE_S]
 *
 * The capture's calibration prelude (mocapctl synth: 3 s heading, 2 s strap, 3 s T-pose) is
 * scheduled as mocapctl replay does. OUT.bin: "MCPSDUMP", uint32 record count, uint32 record size,
 * then per pose (little-endian): int64 frame_sequence, int64 pose_sequence, uint32 flags,
 * uint32 0, float32 orientation[54], acceleration[18], joint_rotations[96] (quaternions w,x,y,z),
 * joint_positions[72], root_position[3], root_velocity[3], foot_contact[2]. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mocap_imu.h"
#include "platform.h"
#include "solver.h"
#include "synth.h"

typedef struct input_record {
    uint64_t frame_sequence;
    float ori[54], acc[18];
} input_record;

typedef struct tap_log {
    input_record *items;
    size_t count, cap;
    int failed;
} tap_log;

/* The golden records hold a contract-1 model's inputs: six sensors, no mask. */
static void tap(void *user, int32_t character, const mocap_frame *frame, const float *ori,
                const float *acc, const float *mask, int sensor_count)
{
    tap_log *log = (tap_log *)user;
    (void)character;
    if (mask || sensor_count != 6) {
        log->failed = 1;
        return;
    }
    if (log->count == log->cap) {
        size_t cap = log->cap ? log->cap * 2 : 1024;
        input_record *p = (input_record *)realloc(log->items, cap * sizeof *p);
        if (!p) {
            log->failed = 1;
            return;
        }
        log->items = p;
        log->cap = cap;
    }
    input_record *r = &log->items[log->count++];
    r->frame_sequence = frame->sequence;
    memcpy(r->ori, ori, sizeof r->ori);
    memcpy(r->acc, acc, sizeof r->acc);
}

static int fail(const char *what)
{
    fprintf(stderr, "solver_dump: %s: %s\n", what, mocap_last_error());
    return 1;
}

int main(int argc, char **argv)
{
    if (argc != 4 && argc != 7) {
        fprintf(stderr, "usage: solver_dump MODEL.onnx CAPTURE OUT.bin [HEADING_S STRAP_S TPOSE_S]\n");
        return 2;
    }
    double heading_s = 3.0, strap_s = 2.0, tpose_s = 3.0;
    if (argc == 7) {
        heading_s = atof(argv[4]);
        strap_s = atof(argv[5]);
        tpose_s = atof(argv[6]);
    }
    mocap_model_options mo;
    mocap_model_options_defaults(&mo);
    mo.intra_op_threads = 1;
    mocap_model *model = NULL;
    if (mocap_model_open(argv[1], &mo, &model) != MOCAP_OK) return fail("model");
    mocap_session_config sc;
    mocap_config_defaults(&sc);
    sc.source_kind = MOCAP_SOURCE_REPLAY;
    snprintf(sc.path, sizeof sc.path, "%s", argv[2]);
    mocap_session *session = NULL;
    if (mocap_session_open(&sc, &session) != MOCAP_OK) return fail("session");
    /* The prelude starts at the first packet's receive time (mocapctl synth's defaults). */
    synth_config defaults;
    synth_config_defaults(&defaults);
    const double prelude_t0 = synth_session_time(&defaults, 0.0);
    if (mocap_calibration_schedule(session, MOCAP_CALIBRATION_HEADING, prelude_t0 + 0.5, (float)(heading_s - 1.0)) != MOCAP_OK ||
        mocap_calibration_schedule(session, MOCAP_CALIBRATION_TPOSE, prelude_t0 + heading_s + strap_s + 0.5,
                                   (float)(tpose_s - 1.0)) != MOCAP_OK)
        return fail("calibration schedule");
    mocap_solver *solver = NULL;
    /* The golden test compares the model's own output with PyTorch: no output smoothing. */
    mocap_solver_config solver_config;
    mocap_solver_config_defaults(&solver_config);
    solver_config.smoothing_min_cutoff_hz = 0.0f;
    if (mocap_solver_open(model, &solver_config, &solver) != MOCAP_OK) return fail("solver");
    int32_t ch = -1;
    if (mocap_solver_add_character(solver, session, &ch) != MOCAP_OK) return fail("add character");
    tap_log log = {0};
    solver_set_input_tap(solver, tap, &log);
    if (mocap_solver_start(solver) != MOCAP_OK || mocap_session_start(session) != MOCAP_OK)
        return fail("start");

    size_t cap = 4096, n = 0;
    mocap_pose *poses = (mocap_pose *)malloc(cap * sizeof *poses);
    int64_t t0 = mocap_monotonic_ns();
    mocap_status st = MOCAP_OK;
    for (;;) {
        if (n == cap) {
            cap *= 2;
            poses = (mocap_pose *)realloc(poses, cap * sizeof *poses);
        }
        if (!poses) return fail("out of memory");
        uint32_t got = 0;
        st = mocap_solver_drain(solver, ch, poses + n, (uint32_t)(cap - n), &got);
        n += got;
        if (st == MOCAP_ERR_END_OF_STREAM) break;
        if (st != MOCAP_OK && st != MOCAP_ERR_NO_DATA) return fail("drain");
        if (mocap_monotonic_ns() - t0 > 120000000000LL) return fail("timeout");
        if (got == 0) mocap_sleep_ms(1);
    }
    mocap_solver_close(solver); /* joins the thread: the tap log is complete */
    mocap_session_close(session);
    mocap_model_close(model);
    if (log.failed || log.count != n) {
        fprintf(stderr, "solver_dump: %zu inputs for %zu poses\n", log.count, n);
        return 1;
    }
    FILE *f = fopen(argv[3], "wb");
    if (!f) return fail("output");
    uint32_t head[2] = {(uint32_t)n, 8 + 8 + 4 + 4 + 4 * (54 + 18 + 96 + 72 + 3 + 3 + 2)};
    fwrite("MCPSDUMP", 1, 8, f);
    fwrite(head, 4, 2, f);
    for (size_t i = 0; i < n; ++i) {
        const mocap_pose *p = &poses[i];
        const input_record *r = &log.items[i];
        if (r->frame_sequence != p->frame_sequence) {
            fprintf(stderr, "solver_dump: input %zu is frame %llu, pose is frame %llu\n", i,
                    (unsigned long long)r->frame_sequence, (unsigned long long)p->frame_sequence);
            return 1;
        }
        int64_t seq[2] = {(int64_t)p->frame_sequence, (int64_t)p->sequence};
        uint32_t flags[2] = {p->flags, 0};
        fwrite(seq, 8, 2, f);
        fwrite(flags, 4, 2, f);
        fwrite(r->ori, 4, 54, f);
        fwrite(r->acc, 4, 18, f);
        fwrite(p->joint_rotations, 4, 96, f);
        fwrite(p->joint_positions, 4, 72, f);
        fwrite(p->root_position, 4, 3, f);
        fwrite(p->root_velocity, 4, 3, f);
        fwrite(p->foot_contact, 4, 2, f);
    }
    if (fclose(f) != 0) return fail("write");
    printf("solver_dump: %zu poses\n", n);
    free(poses);
    free(log.items);
    return 0;
}
