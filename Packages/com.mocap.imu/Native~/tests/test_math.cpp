// Rotation maths: known rotations, round trips, composition order, slerp, Euler, rng.
#include <gtest/gtest.h>

#include <cmath>

extern "C" {
#include "mocap_math.h"
}

namespace {

void expect_vec3_near(const double a[3], const double b[3], double tol)
{
    for (int i = 0; i < 3; i++)
        EXPECT_NEAR(a[i], b[i], tol) << "component " << i;
}

void expect_mat_near(const double a[9], const double b[9], double tol)
{
    for (int i = 0; i < 9; i++)
        EXPECT_NEAR(a[i], b[i], tol) << "element " << i;
}

// Same rotation regardless of the quaternion sign.
void expect_same_rotation(const double a[4], const double b[4], double tol)
{
    double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    EXPECT_NEAR(std::fabs(d), 1.0, tol);
}

} // namespace

TEST(Math, AxisAngleRotatesKnownVectors)
{
    const double z[3] = {0, 0, 1}, x[3] = {1, 0, 0}, y[3] = {0, 1, 0};
    double q[4], out[3];
    quat_from_axis_angle(q, z, MOCAP_PI / 2);
    quat_rotate(out, q, x);
    expect_vec3_near(out, y, 1e-12); // +90 deg about Z takes X to Y (right-handed)
    const double axis_unnormalised[3] = {2, 0, 0};
    quat_from_axis_angle(q, axis_unnormalised, MOCAP_PI / 2);
    quat_rotate(out, q, y);
    expect_vec3_near(out, z, 1e-12);
    EXPECT_NEAR(quat_norm(q), 1.0, 1e-12);
}

TEST(Math, AxisMatricesMatchQuaternions)
{
    const double axes[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    void (*mats[3])(double *, double) = {mat3_rotation_x, mat3_rotation_y, mat3_rotation_z};
    for (int a = 0; a < 3; a++) {
        for (double ang : {-2.5, -0.3, 0.0, 0.7, 3.0}) {
            double q[4], mq[9], m[9];
            quat_from_axis_angle(q, axes[a], ang);
            quat_to_mat3(mq, q);
            mats[a](m, ang);
            expect_mat_near(m, mq, 1e-12);
        }
    }
}

TEST(Math, MatrixQuaternionRoundTripAllBranches)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, 42);
    for (int i = 0; i < 2000; i++) {
        double q[4], m[9], q2[4], m2[9];
        mocap_rng_rotation(&rng, q);
        EXPECT_NEAR(quat_norm(q), 1.0, 1e-12);
        quat_to_mat3(m, q);
        mat3_to_quat(q2, m);
        EXPECT_GE(q2[0], 0.0);
        expect_same_rotation(q, q2, 1e-12);
        quat_to_mat3(m2, q2);
        expect_mat_near(m, m2, 1e-12);
    }
    // 180 degree rotations hit the x/y/z branches where w = 0.
    const double axes[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (const auto &ax : axes) {
        double q[4], m[9], q2[4];
        quat_from_axis_angle(q, ax, MOCAP_PI);
        quat_to_mat3(m, q);
        mat3_to_quat(q2, m);
        expect_same_rotation(q, q2, 1e-12);
    }
}

TEST(Math, MultiplyAppliesRightOperandFirst)
{
    const double x[3] = {1, 0, 0}, z[3] = {0, 0, 1};
    double qa[4], qb[4], qab[4], v1[3], v2[3], tmp[3];
    quat_from_axis_angle(qa, z, MOCAP_PI / 2); // about Z
    quat_from_axis_angle(qb, x, MOCAP_PI / 2); // about X
    quat_multiply(qab, qa, qb);
    const double v[3] = {0, 1, 0};
    quat_rotate(v1, qab, v);
    quat_rotate(tmp, qb, v);
    quat_rotate(v2, qa, tmp);
    expect_vec3_near(v1, v2, 1e-12);
    const double expect[3] = {0, 0, 1}; // Y -X90-> Z -Z90-> Z
    expect_vec3_near(v1, expect, 1e-12);

    // The matrix product agrees with the quaternion product, and aliasing works.
    double ma[9], mb[9], mab[9], mq[9];
    quat_to_mat3(ma, qa);
    quat_to_mat3(mb, qb);
    mat3_multiply(mab, ma, mb);
    quat_to_mat3(mq, qab);
    expect_mat_near(mab, mq, 1e-12);
    mat3_multiply(ma, ma, mb);
    expect_mat_near(ma, mq, 1e-12);
    quat_multiply(qa, qa, qb);
    expect_same_rotation(qa, qab, 1e-12);
}

TEST(Math, TransposeAndMultiplyTransposed)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, 7);
    double q[4], m[9], mt[9], prod[9], id[9], bt[9], ref[9];
    mocap_rng_rotation(&rng, q);
    quat_to_mat3(m, q);
    mat3_transpose(mt, m);
    mat3_multiply(prod, m, mt);
    mat3_identity(id);
    expect_mat_near(prod, id, 1e-12);
    double q2[4], m2[9];
    mocap_rng_rotation(&rng, q2);
    quat_to_mat3(m2, q2);
    mat3_multiply_transposed(prod, m, m2);
    mat3_transpose(bt, m2);
    mat3_multiply(ref, m, bt);
    expect_mat_near(prod, ref, 1e-12);
    // Conjugate = inverse.
    double qc[4], qi[4];
    quat_conjugate(qc, q);
    quat_multiply(qi, q, qc);
    EXPECT_NEAR(qi[0], 1.0, 1e-12);
    // mat3_apply agrees with quat_rotate.
    const double v[3] = {0.3, -1.2, 2.0};
    double a1[3], a2[3];
    mat3_apply(a1, m, v);
    quat_rotate(a2, q, v);
    expect_vec3_near(a1, a2, 1e-12);
}

TEST(Math, EulerZyxMatchesComposedAxisRotations)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, 3);
    for (int i = 0; i < 200; i++) {
        double roll = (mocap_rng_uniform(&rng) * 2 - 1) * MOCAP_PI;
        double pitch = (mocap_rng_uniform(&rng) * 2 - 1) * MOCAP_PI / 2;
        double yaw = (mocap_rng_uniform(&rng) * 2 - 1) * MOCAP_PI;
        double q[4], m[9], rx[9], ry[9], rz[9], r[9];
        quat_from_euler_zyx(q, roll, pitch, yaw);
        EXPECT_NEAR(quat_norm(q), 1.0, 1e-12);
        quat_to_mat3(m, q);
        mat3_rotation_x(rx, roll);
        mat3_rotation_y(ry, pitch);
        mat3_rotation_z(rz, yaw);
        mat3_multiply(r, ry, rx);
        mat3_multiply(r, rz, r);
        expect_mat_near(m, r, 1e-12);
    }
}

TEST(Math, SlerpEndpointsAndMidpoint)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, 11);
    for (int i = 0; i < 200; i++) {
        double a[4], b[4], out[4];
        mocap_rng_rotation(&rng, a);
        mocap_rng_rotation(&rng, b);
        quat_slerp(out, a, b, 0.0);
        expect_same_rotation(out, a, 1e-12);
        quat_slerp(out, a, b, 1.0);
        expect_same_rotation(out, b, 1e-12);
        double total = quat_angle_deg(a, b);
        quat_slerp(out, a, b, 0.5);
        EXPECT_NEAR(quat_angle_deg(a, out), total / 2, 1e-9);
        EXPECT_NEAR(quat_angle_deg(out, b), total / 2, 1e-9);
        quat_slerp(out, a, b, 0.25);
        EXPECT_NEAR(quat_angle_deg(a, out), total / 4, 1e-9);
        // Short path: negating b does not change the result.
        double nb[4] = {-b[0], -b[1], -b[2], -b[3]}, out2[4];
        quat_slerp(out2, a, nb, 0.25);
        expect_same_rotation(out, out2, 1e-12);
    }
}

TEST(Math, SlerpNearlyIdenticalAndOpposite)
{
    const double z[3] = {0, 0, 1};
    double a[4], b[4], out[4];
    quat_identity(a);
    quat_from_axis_angle(b, z, 1e-9);
    quat_slerp(out, a, b, 0.5);
    EXPECT_TRUE(std::isfinite(out[0]));
    EXPECT_NEAR(quat_norm(out), 1.0, 1e-12);
    EXPECT_NEAR(out[3], std::sin(0.25e-9), 1e-15);
    // Identical inputs.
    quat_slerp(out, a, a, 0.3);
    expect_same_rotation(out, a, 1e-12);
    // b = -a is the same rotation: the result must stay that rotation, not blow up.
    double na[4] = {-1, 0, 0, 0};
    quat_slerp(out, a, na, 0.5);
    EXPECT_NEAR(quat_norm(out), 1.0, 1e-12);
    expect_same_rotation(out, a, 1e-12);
    // 180 degrees apart (dot = 0): the midpoint is 90 degrees from each end.
    quat_from_axis_angle(b, z, MOCAP_PI);
    quat_slerp(out, a, b, 0.5);
    EXPECT_NEAR(quat_angle_deg(a, out), 90.0, 1e-9);
    EXPECT_NEAR(quat_angle_deg(out, b), 90.0, 1e-9);
}

TEST(Math, AngleDegreesKnownValues)
{
    const double y[3] = {0, 1, 0};
    double a[4], b[4];
    quat_identity(a);
    for (double deg : {0.0, 1e-4, 1.0, 45.0, 179.0, 180.0}) {
        quat_from_axis_angle(b, y, deg * MOCAP_DEG2RAD);
        EXPECT_NEAR(quat_angle_deg(a, b), deg, 1e-9);
        double ma[9], mb[9];
        quat_to_mat3(ma, a);
        quat_to_mat3(mb, b);
        EXPECT_NEAR(mat3_angle_deg(ma, mb), deg, 1e-6);
    }
    // Beyond 180 the short way round is reported.
    quat_from_axis_angle(b, y, 270 * MOCAP_DEG2RAD);
    EXPECT_NEAR(quat_angle_deg(a, b), 90.0, 1e-9);
}

TEST(Math, NormalizeRejectsZeroAndNonFinite)
{
    double q[4] = {0, 0, 0, 0};
    EXPECT_EQ(quat_normalize(q), -1);
    double n[4] = {NAN, 0, 0, 1};
    EXPECT_EQ(quat_normalize(n), -1);
    EXPECT_TRUE(std::isnan(n[0])); // untouched
    double g[4] = {2, 0, 0, 0};
    EXPECT_EQ(quat_normalize(g), 0);
    EXPECT_DOUBLE_EQ(g[0], 1.0);
}

TEST(Math, OrthonormalizeRepairsPerturbedMatrix)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, 5);
    double q[4], m[9], p[9];
    mocap_rng_rotation(&rng, q);
    quat_to_mat3(m, q);
    for (int i = 0; i < 9; i++)
        p[i] = m[i] + 1e-4 * mocap_rng_gaussian(&rng);
    mat3_orthonormalize(p);
    double pt[9], prod[9], id[9];
    mat3_transpose(pt, p);
    mat3_multiply(prod, p, pt);
    mat3_identity(id);
    expect_mat_near(prod, id, 1e-12);
    EXPECT_LT(mat3_angle_deg(m, p), 0.05);
}

TEST(Math, WorldZupToModel)
{
    double a[9];
    mocap_world_zup_to_model(a);
    const double fwd[3] = {1, 0, 0}, left[3] = {0, 1, 0}, up[3] = {0, 0, 1};
    const double mz[3] = {0, 0, 1}, mx[3] = {1, 0, 0}, my[3] = {0, 1, 0};
    double out[3];
    mat3_apply(out, a, fwd);
    expect_vec3_near(out, mz, 0);
    mat3_apply(out, a, left);
    expect_vec3_near(out, mx, 0);
    mat3_apply(out, a, up);
    expect_vec3_near(out, my, 0);
    // A proper rotation (det +1), so handedness is preserved.
    double c[3];
    vec3_cross(c, fwd, left);
    EXPECT_DOUBLE_EQ(vec3_dot(c, up), 1.0);
    double col0[3] = {a[0], a[3], a[6]}, col1[3] = {a[1], a[4], a[7]}, col2[3] = {a[2], a[5], a[8]};
    vec3_cross(c, col0, col1);
    EXPECT_DOUBLE_EQ(vec3_dot(c, col2), 1.0);
}

TEST(Math, RngDeterministicAndDistributed)
{
    mocap_rng r1, r2, r3;
    mocap_rng_seed(&r1, 123);
    mocap_rng_seed(&r2, 123);
    mocap_rng_seed(&r3, 124);
    int differ = 0;
    for (int i = 0; i < 100; i++) {
        uint64_t a = mocap_rng_next(&r1);
        EXPECT_EQ(a, mocap_rng_next(&r2));
        differ += a != mocap_rng_next(&r3);
    }
    EXPECT_GT(differ, 95);

    const int n = 200000;
    double sum = 0, sq = 0, usum = 0, umin = 1, umax = 0;
    double axis_sum[3] = {0, 0, 0}, wabs = 0;
    for (int i = 0; i < n; i++) {
        double g = mocap_rng_gaussian(&r1);
        sum += g;
        sq += g * g;
        double u = mocap_rng_uniform(&r1);
        ASSERT_GE(u, 0.0);
        ASSERT_LT(u, 1.0);
        usum += u;
        umin = std::fmin(umin, u);
        umax = std::fmax(umax, u);
        double q[4], m[9];
        mocap_rng_rotation(&r1, q);
        quat_to_mat3(m, q);
        // A uniform rotation sends X to a uniform direction on the sphere: mean ~ 0.
        axis_sum[0] += m[0];
        axis_sum[1] += m[3];
        axis_sum[2] += m[6];
        wabs += std::fabs(q[0]);
    }
    EXPECT_NEAR(sum / n, 0.0, 0.01);
    EXPECT_NEAR(sq / n, 1.0, 0.02);
    EXPECT_NEAR(usum / n, 0.5, 0.005);
    EXPECT_LT(umin, 1e-3);
    EXPECT_GT(umax, 1 - 1e-3);
    for (double s : axis_sum)
        EXPECT_NEAR(s / n, 0.0, 0.01);
    // Haar-uniform: E|w| = E cos(theta/2) under the density (1 - cos theta)/pi = 4/(3 pi).
    EXPECT_NEAR(wabs / n, 4.0 / (3.0 * MOCAP_PI), 0.005);
}
