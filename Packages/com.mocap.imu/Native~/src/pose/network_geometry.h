/* The pose model's geometry, done by the engine for a contract-3 model (docs/model-contract.md):
 * the file holds only the learned network (features -> 149 numbers per row), and these functions
 * turn sensor orientations and accelerations into its features and its numbers into joint
 * rotations, root velocity and foot contact, the same arithmetic training/model.py exports into
 * a contract-1/2 graph. ONNX Runtime charges ~0.2-1 us per operator on tensors this small, and
 * the geometry is ~130 operators: in C it is a few microseconds.
 *
 * Steps, per character and frame:
 *  - a missing sensor (mask 0) reads as identity orientation and zero acceleration;
 *  - heading removal: Ry from the pelvis' horizontal forward direction h = f_xz - f_y * u_xz;
 *  - features: Ry^T R_k and Ry^T a_k / S for every sensor, R_p^T R_j and R_p^T (a_j - a_p) / S
 *    for every non-pelvis sensor (blocks zeroed where a sensor, or the pelvis, is missing), then
 *    the mask when the network reads it;
 *  - outputs: each joint's two columns are residuals on the rest pose (the pelvis: on its
 *    measured heading-free orientation); an anchored sensor bone's are residuals on the measured
 *    orientation relative to its parent's predicted global one; the pelvis and the root velocity
 *    are rotated back by Ry; Gram-Schmidt makes the rotations;
 *  - mirror average (optional): a second row runs on the mirror image of the inputs (left and
 *    right sensors swapped, reflected in the sagittal plane) and its answer, mirrored back, is
 *    averaged with the first (unit columns summed, then Gram-Schmidt; velocity and contact
 *    averaged).
 * Pure functions on caller buffers, no allocation; tested against the exported graphs through
 * the real ONNX Runtime (training/tests/test_network_geometry.py) and in tests/test_network_geometry.cpp. */
#ifndef MOCAP_NETWORK_GEOMETRY_H
#define MOCAP_NETWORK_GEOMETRY_H

#include <stddef.h>

#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

#define GEOMETRY_JOINTS 24
/* The network's numbers per row: 24 joints x (3 rows x 2 columns), laid out joint, row, column;
 * then the root velocity in the heading frame (3) and the two foot contact logits. */
#define GEOMETRY_OUTPUTS (GEOMETRY_JOINTS * 6 + 3 + 2)

typedef struct network_geometry {
    int sensors;                            /* N */
    int pelvis;                             /* the pelvis' index among them */
    int masked;                             /* the features end with the mask */
    int mirror;                             /* two rows per character, averaged */
    float acceleration_scale;               /* S: m/s^2 per network unit */
    int mirror_sensors[MOCAP_MAX_SENSORS];  /* each sensor's left/right counterpart */
    int mirror_joints[GEOMETRY_JOINTS];     /* each joint's counterpart */
    int parents[GEOMETRY_JOINTS];
    /* anchored bones: joint, the sensor that measures it, in the order they are applied */
    int anchored;
    int anchor_joint[MOCAP_MAX_SENSORS];
    int anchor_sensor[MOCAP_MAX_SENSORS];
    int features;                           /* F: numbers per row fed to the network */
} network_geometry;

/* Fill g from the model's description; anchor_joints: the joint each sensor's bone is (0: not
 * anchored; a later sensor of the same bone wins). MOCAP_ERR_FORMAT with a message for an
 * inconsistent description (no pelvis, an index out of range, a mirror table that is not a pairing). */
mocap_status network_geometry_init(network_geometry *g, int sensors, int pelvis, int masked,
                                   int mirror, float acceleration_scale,
                                   const int *mirror_sensors, const int *mirror_joints,
                                   const int *parents, const int *anchor_joints);

/* Rows of the network per character (2 with the mirror average). */
int network_geometry_rows(const network_geometry *g);

/* What the engine keeps of one row between its features and its outputs. */
typedef struct geometry_row {
    float heading[9];                       /* Ry */
    float oriented[MOCAP_MAX_SENSORS][9];   /* Ry^T R_k, missing sensors as identity */
    float present[MOCAP_MAX_SENSORS];       /* the row's mask (all 1 for an unmasked network) */
} geometry_row;

/* One character's frame -> the features of each of its rows: orientation [N][9] (row-major,
 * bone -> model), acceleration [N][3] (m/s^2), mask [N] (NULL: all present); row k's F
 * features at features + k * row_stride; rows [rows]. */
void network_geometry_features(const network_geometry *g, const float *orientation,
                               const float *acceleration, const float *mask, float *features,
                               size_t row_stride, geometry_row *rows);

/* The network's GEOMETRY_OUTPUTS numbers of each row (row k's at network_output + k *
 * row_stride) -> joint rotations [24][9] (joint 0 global, the others local), root velocity [3]
 * (m/s, model frame) and foot contact probabilities [2]. */
void network_geometry_outputs(const network_geometry *g, const float *network_output,
                              size_t row_stride, const geometry_row *rows, float *rotations,
                              float *velocity, float *contact);

#ifdef __cplusplus
}
#endif
#endif
