/* Small double-precision rotation maths shared by the engine. Quaternions are (w, x, y, z);
 * matrices are row-major double[9]; a rotation R_ab maps vectors in frame b to frame a. */
#ifndef MOCAP_MATH_H
#define MOCAP_MATH_H

#include <stdint.h>

#define MOCAP_PI 3.14159265358979323846
#define MOCAP_STANDARD_GRAVITY 9.80665
#define MOCAP_DEG2RAD (MOCAP_PI / 180.0)
#define MOCAP_RAD2DEG (180.0 / MOCAP_PI)

#ifdef __cplusplus
extern "C" {
#endif

void quat_identity(double q[4]);
void quat_copy(double out[4], const double q[4]);
double quat_norm(const double q[4]);
double quat_dot(const double a[4], const double b[4]);
/* q and -q are the same rotation: negates q if it lies on the other hemisphere from ref, so
 * sums, interpolation and differences of nearby rotations see no sign flip. */
void quat_align_hemisphere(double q[4], const double ref[4]);
/* Returns 0 on success, -1 if the norm is zero or not finite (q untouched then). */
int quat_normalize(double q[4]);
void quat_conjugate(double out[4], const double q[4]);
/* out = a * b (apply b first, then a). out may alias a or b. */
void quat_multiply(double out[4], const double a[4], const double b[4]);
void quat_rotate(double out[3], const double q[4], const double v[3]);
/* Shortest-path spherical interpolation, t in [0,1]. */
void quat_slerp(double out[4], const double a[4], const double b[4], double t);
/* Angle of the rotation a^-1 b in degrees, in [0, 180]. */
double quat_angle_deg(const double a[4], const double b[4]);
void quat_from_axis_angle(double out[4], const double axis[3], double angle_rad);
/* HiPNUC Euler angles: roll about X, pitch about Y, yaw about Z, applied Z-Y-X (yaw first). */
void quat_from_euler_zyx(double out[4], double roll_rad, double pitch_rad, double yaw_rad);

void quat_to_mat3(double m[9], const double q[4]);
void mat3_to_quat(double q[4], const double m[9]);
void mat3_identity(double m[9]);
/* out = a * b. out may alias a or b. */
void mat3_multiply(double out[9], const double a[9], const double b[9]);
/* out = a * b^T. */
void mat3_multiply_transposed(double out[9], const double a[9], const double b[9]);
void mat3_transpose(double out[9], const double m[9]);
void mat3_apply(double out[3], const double m[9], const double v[3]);
void mat3_rotation_x(double m[9], double angle_rad);
void mat3_rotation_y(double m[9], double angle_rad);
void mat3_rotation_z(double m[9], double angle_rad);
/* Angle of the rotation a^T b in degrees. */
double mat3_angle_deg(const double a[9], const double b[9]);
/* Nearest rotation to a (nearly orthonormal) matrix, by quaternion round trip. */
void mat3_orthonormalize(double m[9]);

double vec3_dot(const double a[3], const double b[3]);
double vec3_norm(const double v[3]);
void vec3_cross(double out[3], const double a[3], const double b[3]);

/* Z-up world (x forward, y left, z up) -> Y-up model (x left, y up, z forward). */
void mocap_world_zup_to_model(double m[9]);

/* Deterministic random numbers for generators and tests (xoshiro-style, not crypto). */
typedef struct mocap_rng { uint64_t s[4]; } mocap_rng;
void mocap_rng_seed(mocap_rng *rng, uint64_t seed);
uint64_t mocap_rng_next(mocap_rng *rng);
double mocap_rng_uniform(mocap_rng *rng);              /* [0, 1) */
double mocap_rng_gaussian(mocap_rng *rng);             /* N(0, 1) */
void mocap_rng_rotation(mocap_rng *rng, double q[4]);  /* uniformly random unit quaternion */

#ifdef __cplusplus
}
#endif
#endif
