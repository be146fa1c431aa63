/* Double-precision rotation maths. Everything is small and allocation-free so it can run on
 * the capture thread. */
#include "mocap_math.h"

#include <math.h>
#include <string.h>

void quat_identity(double q[4])
{
    q[0] = 1.0;
    q[1] = q[2] = q[3] = 0.0;
}

void quat_copy(double out[4], const double q[4])
{
    memmove(out, q, 4 * sizeof(double));
}

double quat_norm(const double q[4])
{
    return sqrt(quat_dot(q, q));
}

double quat_dot(const double a[4], const double b[4])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
}

void quat_align_hemisphere(double q[4], const double ref[4])
{
    if (quat_dot(q, ref) < 0.0)
        for (int i = 0; i < 4; i++)
            q[i] = -q[i];
}

int quat_normalize(double q[4])
{
    double n = quat_norm(q);
    if (!(n > 0.0) || !isfinite(n))
        return -1;
    for (int i = 0; i < 4; i++)
        q[i] /= n;
    return 0;
}

void quat_conjugate(double out[4], const double q[4])
{
    out[0] = q[0];
    out[1] = -q[1];
    out[2] = -q[2];
    out[3] = -q[3];
}

void quat_multiply(double out[4], const double a[4], const double b[4])
{
    /* Computed into a temporary so out may alias either input. */
    double r[4];
    r[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    r[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    r[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    r[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    memcpy(out, r, sizeof r);
}

void quat_rotate(double out[3], const double q[4], const double v[3])
{
    /* v' = v + 2w (u x v) + 2 u x (u x v), u = vector part; avoids building a matrix. */
    const double *u = q + 1;
    double t[3], c[3], r[3];
    vec3_cross(t, u, v);
    for (int i = 0; i < 3; i++)
        t[i] *= 2.0;
    vec3_cross(c, u, t);
    for (int i = 0; i < 3; i++)
        r[i] = v[i] + q[0] * t[i] + c[i];
    memcpy(out, r, sizeof r);
}

void quat_slerp(double out[4], const double a[4], const double b[4], double t)
{
    double bb[4];
    double d = quat_dot(a, b);
    /* q and -q are the same rotation: flip b to take the short way round. */
    double sign = d < 0.0 ? -1.0 : 1.0;
    for (int i = 0; i < 4; i++)
        bb[i] = sign * b[i];
    d = fabs(d);
    double r[4];
    if (d > 0.9995) {
        /* Nearly identical: sin(theta) is tiny and the slerp weights lose precision; linear
         * interpolation plus renormalisation is accurate to well below 1e-6 here. */
        for (int i = 0; i < 4; i++)
            r[i] = a[i] + t * (bb[i] - a[i]);
    } else {
        /* Nearly opposite rotations (d ~ 0 in 4D) are 180 deg apart and still well conditioned:
         * theta ~ 90 deg, so the general formula applies. */
        double theta = acos(d > 1.0 ? 1.0 : d);
        double s = sin(theta);
        double wa = sin((1.0 - t) * theta) / s;
        double wb = sin(t * theta) / s;
        for (int i = 0; i < 4; i++)
            r[i] = wa * a[i] + wb * bb[i];
    }
    if (quat_normalize(r) != 0)
        quat_identity(r);
    memcpy(out, r, sizeof r);
}

double quat_angle_deg(const double a[4], const double b[4])
{
    /* |dot| = |cos(angle/2)| for unit quaternions; atan2 of the relative quaternion's vector and
     * scalar parts keeps precision near 0 and 180 degrees, where acos would not. */
    double ac[4], rel[4];
    quat_conjugate(ac, a);
    quat_multiply(rel, ac, b);
    double v = sqrt(rel[1] * rel[1] + rel[2] * rel[2] + rel[3] * rel[3]);
    double w = fabs(rel[0]);
    return 2.0 * atan2(v, w) * MOCAP_RAD2DEG;
}

void quat_from_axis_angle(double out[4], const double axis[3], double angle_rad)
{
    double n = vec3_norm(axis);
    if (!(n > 0.0) || !isfinite(n)) {
        quat_identity(out);
        return;
    }
    double s = sin(0.5 * angle_rad) / n;
    out[0] = cos(0.5 * angle_rad);
    out[1] = axis[0] * s;
    out[2] = axis[1] * s;
    out[3] = axis[2] * s;
}

void quat_from_euler_zyx(double out[4], double roll_rad, double pitch_rad, double yaw_rad)
{
    /* R = Rz(yaw) * Ry(pitch) * Rx(roll). */
    double cr = cos(0.5 * roll_rad), sr = sin(0.5 * roll_rad);
    double cp = cos(0.5 * pitch_rad), sp = sin(0.5 * pitch_rad);
    double cy = cos(0.5 * yaw_rad), sy = sin(0.5 * yaw_rad);
    out[0] = cy * cp * cr + sy * sp * sr;
    out[1] = cy * cp * sr - sy * sp * cr;
    out[2] = cy * sp * cr + sy * cp * sr;
    out[3] = sy * cp * cr - cy * sp * sr;
}

void quat_to_mat3(double m[9], const double q[4])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    m[0] = 1.0 - 2.0 * (y * y + z * z);
    m[1] = 2.0 * (x * y - w * z);
    m[2] = 2.0 * (x * z + w * y);
    m[3] = 2.0 * (x * y + w * z);
    m[4] = 1.0 - 2.0 * (x * x + z * z);
    m[5] = 2.0 * (y * z - w * x);
    m[6] = 2.0 * (x * z - w * y);
    m[7] = 2.0 * (y * z + w * x);
    m[8] = 1.0 - 2.0 * (x * x + y * y);
}

void mat3_to_quat(double q[4], const double m[9])
{
    /* Solve for the largest of the four components first (Shepperd's choice): it is at least
     * 1/2 in magnitude, so dividing by it never amplifies rounding. */
    double tr = m[0] + m[4] + m[8];
    double r[4];
    if (tr >= m[0] && tr >= m[4] && tr >= m[8]) {
        double s = 2.0 * sqrt(fmax(1.0 + tr, 0.0));
        r[0] = 0.25 * s;
        r[1] = (m[7] - m[5]) / s;
        r[2] = (m[2] - m[6]) / s;
        r[3] = (m[3] - m[1]) / s;
    } else if (m[0] >= m[4] && m[0] >= m[8]) {
        double s = 2.0 * sqrt(fmax(1.0 + m[0] - m[4] - m[8], 0.0));
        r[0] = (m[7] - m[5]) / s;
        r[1] = 0.25 * s;
        r[2] = (m[1] + m[3]) / s;
        r[3] = (m[2] + m[6]) / s;
    } else if (m[4] >= m[8]) {
        double s = 2.0 * sqrt(fmax(1.0 + m[4] - m[0] - m[8], 0.0));
        r[0] = (m[2] - m[6]) / s;
        r[1] = (m[1] + m[3]) / s;
        r[2] = 0.25 * s;
        r[3] = (m[5] + m[7]) / s;
    } else {
        double s = 2.0 * sqrt(fmax(1.0 + m[8] - m[0] - m[4], 0.0));
        r[0] = (m[3] - m[1]) / s;
        r[1] = (m[2] + m[6]) / s;
        r[2] = (m[5] + m[7]) / s;
        r[3] = 0.25 * s;
    }
    /* A canonical sign (w >= 0) makes results comparable and reproducible. */
    if (r[0] < 0.0)
        for (int i = 0; i < 4; i++)
            r[i] = -r[i];
    if (quat_normalize(r) != 0)
        quat_identity(r);
    memcpy(q, r, sizeof r);
}

void mat3_identity(double m[9])
{
    memset(m, 0, 9 * sizeof(double));
    m[0] = m[4] = m[8] = 1.0;
}

void mat3_multiply(double out[9], const double a[9], const double b[9])
{
    double r[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
    memcpy(out, r, sizeof r);
}

void mat3_multiply_transposed(double out[9], const double a[9], const double b[9])
{
    double r[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r[3 * i + j] = a[3 * i] * b[3 * j] + a[3 * i + 1] * b[3 * j + 1] +
                           a[3 * i + 2] * b[3 * j + 2];
    memcpy(out, r, sizeof r);
}

void mat3_transpose(double out[9], const double m[9])
{
    double r[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r[3 * i + j] = m[3 * j + i];
    memcpy(out, r, sizeof r);
}

void mat3_apply(double out[3], const double m[9], const double v[3])
{
    double r[3];
    for (int i = 0; i < 3; i++)
        r[i] = m[3 * i] * v[0] + m[3 * i + 1] * v[1] + m[3 * i + 2] * v[2];
    memcpy(out, r, sizeof r);
}

void mat3_rotation_x(double m[9], double a)
{
    double c = cos(a), s = sin(a);
    m[0] = 1; m[1] = 0; m[2] = 0;
    m[3] = 0; m[4] = c; m[5] = -s;
    m[6] = 0; m[7] = s; m[8] = c;
}

void mat3_rotation_y(double m[9], double a)
{
    double c = cos(a), s = sin(a);
    m[0] = c;  m[1] = 0; m[2] = s;
    m[3] = 0;  m[4] = 1; m[5] = 0;
    m[6] = -s; m[7] = 0; m[8] = c;
}

void mat3_rotation_z(double m[9], double a)
{
    double c = cos(a), s = sin(a);
    m[0] = c; m[1] = -s; m[2] = 0;
    m[3] = s; m[4] = c;  m[5] = 0;
    m[6] = 0; m[7] = 0;  m[8] = 1;
}

double mat3_angle_deg(const double a[9], const double b[9])
{
    double qa[4], qb[4];
    mat3_to_quat(qa, a);
    mat3_to_quat(qb, b);
    return quat_angle_deg(qa, qb);
}

void mat3_orthonormalize(double m[9])
{
    double q[4];
    mat3_to_quat(q, m);
    quat_to_mat3(m, q);
}

double vec3_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

double vec3_norm(const double v[3])
{
    return sqrt(vec3_dot(v, v));
}

void vec3_cross(double out[3], const double a[3], const double b[3])
{
    double r[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                   a[0] * b[1] - a[1] * b[0]};
    memcpy(out, r, sizeof r);
}

void mocap_world_zup_to_model(double m[9])
{
    /* Columns are the images of world x (forward) -> model z, world y (left) -> model x,
     * world z (up) -> model y. */
    m[0] = 0; m[1] = 1; m[2] = 0;
    m[3] = 0; m[4] = 0; m[5] = 1;
    m[6] = 1; m[7] = 0; m[8] = 0;
}

/* ---- random numbers: xoshiro256** seeded through splitmix64 ---- */

static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static uint64_t rotl64(uint64_t x, int k)
{
    return (x << k) | (x >> (64 - k));
}

void mocap_rng_seed(mocap_rng *rng, uint64_t seed)
{
    /* splitmix64 spreads any seed (including 0) into a state that is never all zero. */
    uint64_t st = seed;
    for (int i = 0; i < 4; i++)
        rng->s[i] = splitmix64(&st);
}

uint64_t mocap_rng_next(mocap_rng *rng)
{
    uint64_t *s = rng->s;
    uint64_t result = rotl64(s[1] * 5u, 7) * 9u;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl64(s[3], 45);
    return result;
}

double mocap_rng_uniform(mocap_rng *rng)
{
    /* Top 53 bits give every representable multiple of 2^-53 in [0, 1). */
    return (double)(mocap_rng_next(rng) >> 11) * (1.0 / 9007199254740992.0);
}

double mocap_rng_gaussian(mocap_rng *rng)
{
    /* Box-Muller without caching the second value, so the stream stays stateless beyond s[]. */
    double u1 = 1.0 - mocap_rng_uniform(rng); /* (0, 1]: log stays finite */
    double u2 = mocap_rng_uniform(rng);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * MOCAP_PI * u2);
}

void mocap_rng_rotation(mocap_rng *rng, double q[4])
{
    /* Shoemake's subgroup algorithm: uniform on SO(3). */
    double u1 = mocap_rng_uniform(rng);
    double u2 = mocap_rng_uniform(rng);
    double u3 = mocap_rng_uniform(rng);
    double a = sqrt(1.0 - u1), b = sqrt(u1);
    q[0] = a * sin(2.0 * MOCAP_PI * u2);
    q[1] = a * cos(2.0 * MOCAP_PI * u2);
    q[2] = b * sin(2.0 * MOCAP_PI * u3);
    q[3] = b * cos(2.0 * MOCAP_PI * u3);
}
