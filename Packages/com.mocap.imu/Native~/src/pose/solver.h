/* The pose solver (public API in mocap_imu.h, "Pose model and solver"): internal pieces that
 * tests and tools reach.
 *
 * Thread: each tick it takes at most one new frame from every character's session (it is the
 * only consumer of those sessions), feeds the characters that have one to the model in ONE
 * ort_stream_run (batch B = characters ready; one stream per B = 1..N created at start; each
 * character's recurrent state [L][H] is gathered into / scattered out of the stream's [L][B][H]
 * state), and turns the outputs into poses pushed to a per-character SPSC ring. It waits at most
 * one frame period for characters that have no frame yet, and not at all while some character
 * has a backlog, so a late or unplugged device never stalls the others. A replay played as fast
 * as possible loses nothing: its frames stay in its session (which then waits) while its pose
 * ring is full. Nothing is allocated per frame. */
#ifndef MOCAP_SOLVER_H
#define MOCAP_SOLVER_H

#include <stdint.h>
#include "mocap_imu.h"
#include "onnx_runtime.h"

#ifdef __cplusplus
extern "C" {
#endif

/* model.c */
ort_model *model_ort(mocap_model *model);
const mocap_model_info *model_info(const mocap_model *model);
/* 1 when the model reads which sensors are present (contract 2, or 3 with masked features). */
int model_has_mask(const mocap_model *model);

/* A calibrated frame as the inputs of a model with `sensors` sensors: model sensor k is the
 * frame's sensor slot_of[k] (-1: none). orientation [N][3][3] (bone -> model, row-major) from
 * bone_orientation, acceleration [N][3] from bone_acceleration. with_mask (contract 2): a sensor
 * that is missing, has never sent or is uncalibrated gets mask 0 and zero inputs, the others
 * mask 1 (a silent one its held value, which the solver's stand-ins then replace); mask may be
 * NULL. Returns 0, or -1 when a value fed is NaN/Inf or a quaternion is zero (nothing of
 * that frame may reach the model). */
int solver_frame_input(const mocap_frame *frame, const int8_t *slot_of, int sensors, int with_mask,
                       float *orientation, float *acceleration, float *mask);

/* Create the per-batch-size streams (mocap_solver_start does it; tests that drive
 * solver_solve directly call it instead of starting the thread). */
mocap_status solver_prepare(mocap_solver *solver);

/* One tick over explicit frames: frames[i] belongs to characters[i] (distinct); taken_ns[i] is
 * when it left its session (may be NULL: now). Frames are filtered (calibration, NaN/Inf),
 * solved in one batched call and their poses pushed to the characters' rings. The solver
 * thread calls this; so can a test, on a prepared solver that was not started. */
mocap_status solver_solve(mocap_solver *solver, const int32_t *characters,
                          const mocap_frame *const *frames, const int64_t *taken_ns, int n);

/* Called on the solver thread for every frame fed to the model, with the exact inputs (for
 * golden tests and debugging). Set before mocap_solver_start. */
typedef void (*solver_input_tap)(void *user, int32_t character, const mocap_frame *frame,
                                 const float *orientation, const float *acceleration,
                                 const float *mask, int sensor_count);
void solver_set_input_tap(mocap_solver *solver, solver_input_tap tap, void *user);

#ifdef __cplusplus
}
#endif
#endif
